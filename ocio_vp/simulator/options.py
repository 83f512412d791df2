"""Turn ``ocio-vp simulate`` options into simulator inputs (spectra from CSV files, LED pairs).

Every bad value becomes an :class:`~ocio_vp.errors.InputError` naming the option or file.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.documents import read_bounded
from ocio_vp.formats.measurements import PANEL_RANGE, PanelGeometry
from ocio_vp.simulator.data import PAPER_ENVIRONMENTS, wavelengths

if TYPE_CHECKING:
    from ocio_vp.simulator.stage import EnvironmentLight, Leds

__all__ = [
    "ceiling_leds_from_arg",
    "environments_from_args",
    "read_spectra_csv",
    "stage_options_from_args",
]


def read_spectra_csv(path: str | Path, *, columns: int) -> np.ndarray:
    """Read ``wavelength,value...`` rows (optional header) onto the simulator grid.

    Values are linearly interpolated; outside the file's wavelength range they are 0.

    Returns
    -------
    ndarray
        (W, columns) float64.
    """
    source = str(path)
    try:
        text = read_bounded(path).decode("utf-8")
    except UnicodeDecodeError:
        raise InputError("not a UTF-8 text file", source=source) from None
    rows: list[list[float]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = [f.strip() for f in line.replace(";", ",").split(",") if f.strip()]
        if not fields or fields[0].startswith("#"):
            continue
        try:
            values = [float(f) for f in fields]
        except ValueError:
            if not rows:
                continue  # a header line
            raise InputError(
                f"not a number in {excerpt(line)}", source=source, key=f"line {number}"
            ) from None
        if len(values) != columns + 1 or not np.all(np.isfinite(values)):
            raise InputError(
                f"expected {columns + 1} finite numbers (wavelength and {columns} values), "
                f"got {line!r}",
                source=source,
                key=f"line {number}",
            )
        rows.append(values)
    data = np.array(rows, dtype=np.float64)
    if len(data) < 2 or np.any(np.diff(data[:, 0]) <= 0):
        raise InputError("need at least 2 rows with increasing wavelengths", source=source)
    if np.any(data[:, 1:] < 0):
        raise InputError("spectral values must be >= 0", source=source)
    grid = wavelengths()
    return np.stack(
        [
            np.interp(grid, data[:, 0], data[:, k], left=0.0, right=0.0)
            for k in range(1, columns + 1)
        ],
        axis=1,
    )


def _leds(value: str, key: str = "--leds") -> Leds:
    if value.lower().endswith(".csv"):
        return read_spectra_csv(value, columns=3)
    try:
        pairs = [tuple(float(x) for x in item.split("/")) for item in value.split(",")]
    except ValueError:
        pairs = []
    if len(pairs) != 3 or any(len(p) != 2 for p in pairs):
        raise InputError(
            f"expected PEAK/FWHM,PEAK/FWHM,PEAK/FWHM (nm) or a .csv file, got {excerpt(value)}",
            key=key,
        )
    return pairs


def ceiling_leds_from_arg(value: str) -> Leds:
    """``--ceiling-leds``: three PEAK/FWHM pairs or a CSV of measured spectra, as ``--leds``."""
    return _leds(value, "--ceiling-leds")


def _panel(value: str) -> PanelGeometry:
    try:
        width, height, distance = (float(x) for x in value.lower().split("x"))
    except ValueError:
        raise InputError(
            f"expected WIDTHxHEIGHTxDISTANCE in metres, got {excerpt(value)}", key="--panel"
        ) from None
    low, high = PANEL_RANGE
    if not all(low <= v <= high for v in (width, height, distance)):
        raise InputError(
            f"panel sizes must be {low:g}..{high:g} m, got {excerpt(value)}", key="--panel"
        )
    return PanelGeometry(width=width, height=height, distance=distance)


class StageOptions(TypedDict, total=False):
    """Keyword options of :func:`ocio_vp.simulator.stage.spectral_stage` given on the command
    line."""

    camera: str
    leds: Leds
    chart: str
    panel: PanelGeometry
    panel_albedo: float | None
    name: str
    wall_gain: float


def stage_options_from_args(args: argparse.Namespace) -> StageOptions:
    """Keyword options for :func:`ocio_vp.simulator.stage.spectral_stage` from parsed arguments."""
    options = StageOptions()
    if args.camera is not None:
        options["camera"] = args.camera
    if args.leds is not None:
        options["leds"] = _leds(args.leds)
    if args.chart is not None:
        options["chart"] = args.chart
    if args.panel is not None:
        options["panel"] = _panel(args.panel)
    if args.albedo is not None:
        options["panel_albedo"] = None if args.albedo == 0 else args.albedo
    if args.name is not None:
        options["name"] = args.name
    options["wall_gain"] = args.wall_gain
    return options


def environments_from_args(values: list[str] | None) -> dict[str, EnvironmentLight]:
    """``NAME`` or ``NAME=FILE.csv`` items -> the simulator's environments mapping (a bare
    ``NAME`` is checked when the stage is simulated)."""
    if not values:
        return {name: name for name in PAPER_ENVIRONMENTS}
    environments: dict[str, EnvironmentLight] = {}
    for value in values:
        name, _, path = value.partition("=")
        if name in environments:
            raise InputError(f"environment {name!r} given twice", key="--environment")
        environments[name] = read_spectra_csv(path, columns=1)[:, 0] if path else name
    return environments
