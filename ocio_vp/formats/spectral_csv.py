"""Spectral CSV files a stage may bring: measured LED panel spectra, camera sensitivities, the
location light (``solve --led-spectra``, ``--camera-sensitivities``, ``--location-light``).

One layout for all: a row per wavelength, the wavelength in nm first, then one column per
channel; an optional first row of names (``nm,red,green,blue``). Every problem is refused on one
line naming the file, the column and the problem (docs/skin.md): a wrong column count, a value
that is not a finite number, a negative value, wavelengths that do not increase, a range that
does not cover the visible (400-700 nm), too few samples in it, a channel that is all zero. The
values are resampled (linearly) onto the project's grid (:mod:`ocio_vp.spectra`), 0 outside
the file's range.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError, excerpt

__all__ = ["MIN_SAMPLES", "VISIBLE", "SpectralTable", "read_spectral_csv"]

#: The range a spectral file must cover (nm): where cameras and skin differ.
VISIBLE = (400.0, 700.0)
#: Samples a file must have inside :data:`VISIBLE` (every 20 nm or finer).
MIN_SAMPLES = 16
#: Wavelengths outside this range (nm) are a mistake (units, or a column swapped).
PLAUSIBLE = (200.0, 2000.0)
#: Rows a spectral file may have (a 0.1 nm spectrometer from 200 to 2000 nm has 18001).
MAX_ROWS = 20000


@dataclass(frozen=True)
class SpectralTable:
    """A spectral file on the project grid: ``values`` (W, k), the ``columns``' names, the
    ``source`` file."""

    source: str
    columns: tuple[str, ...]
    values: np.ndarray


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _rows(path: Path, source: str) -> list[list[str]]:
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = []
            for row in csv.reader(handle):
                if row and any(cell.strip() for cell in row):
                    rows.append([cell.strip() for cell in row])
                if len(rows) > MAX_ROWS + 1:
                    raise InputError(f"more than {MAX_ROWS} rows", source=source)
            return rows
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise InputError(f"cannot read it as CSV text ({error})", source=source) from None


def read_spectral_csv(path: str | Path, *, columns: int, names: tuple[str, ...]) -> SpectralTable:
    """Read and check a spectral CSV of ``columns`` channels (module docstring); ``names``
    label the channels in messages when the file has no header row."""
    path = Path(path)
    source = str(path)
    rows = _rows(path, source)
    header = names
    if rows and _number(rows[0][0]) is None:
        header = tuple(rows[0][1:])
        rows = rows[1:]
    if len(header) != columns:
        raise InputError(
            f"has {len(header)} channel column(s), expected {columns} (wavelength in nm, then "
            f"{', '.join(names)})",
            source=source,
        )
    table = np.empty((len(rows), columns + 1))
    for i, row in enumerate(rows):
        if len(row) != columns + 1:
            raise InputError(
                f"row {i + 1} has {len(row)} columns, expected {columns + 1} (wavelength, "
                f"{', '.join(header)})",
                source=source,
            )
        for k, cell in enumerate(row):
            value = _number(cell)
            column = "wavelength" if k == 0 else header[k - 1]
            if value is None:
                raise InputError(
                    f"column {column!r}, row {i + 1}: expected a finite number, got "
                    f"{excerpt(cell)}",
                    source=source,
                )
            table[i, k] = value
    return SpectralTable(source, tuple(header), _checked(table, header, source))


def _checked(table: np.ndarray, header: tuple[str, ...], source: str) -> np.ndarray:
    """The table's channels on the project grid, after the checks of the module docstring."""
    from ocio_vp.spectra import wavelengths

    nm = table[:, 0]

    def wavelength_error(problem: str) -> InputError:
        return InputError(f"column 'wavelength': {problem}", source=source)

    if len(nm) < 2 or np.any(np.diff(nm) <= 0):
        raise wavelength_error("expected increasing wavelengths in nm")
    if nm[0] < PLAUSIBLE[0] or nm[-1] > PLAUSIBLE[1]:
        raise wavelength_error(f"{nm[0]:g}-{nm[-1]:g} is not a range of wavelengths in nm")
    low, high = VISIBLE
    if nm[0] > low or nm[-1] < high:
        raise wavelength_error(f"covers {nm[0]:g}-{nm[-1]:g} nm, need at least {low:g}-{high:g} nm")
    inside = int(np.count_nonzero((nm >= low) & (nm <= high)))
    if inside < MIN_SAMPLES:
        raise wavelength_error(
            f"too few samples: {inside} between {low:g} and {high:g} nm, need at least "
            f"{MIN_SAMPLES}"
        )
    for k, name in enumerate(header):
        values = table[:, k + 1]
        if np.any(values < 0):
            j = int(np.argmin(values))
            raise InputError(
                f"column {name!r}: negative value {values[j]:.6g} at {nm[j]:g} nm", source=source
            )
        if not np.any(values > 0):
            raise InputError(f"column {name!r}: all zero", source=source)
    grid = wavelengths()
    return np.stack(
        [np.interp(grid, nm, table[:, k + 1], left=0.0, right=0.0) for k in range(len(header))],
        axis=1,
    )
