"""The optional ``panels`` section of a measurements file: several LED panel types on one stage
(keys and rules: docs/measurements.md, section "panels"; what is solved: docs/panels.md), read
with the file's :class:`~ocio_vp.formats.checker.Validator` (``ctx``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ocio_vp.formats.checker import CHANNELS, Validator, describe
from ocio_vp.formats.geometry import PanelGeometry
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.records import floats
from ocio_vp.wall.linearity import Ramp, parse_ramps, ramps_to_dict

__all__ = [
    "PANEL_KEYS",
    "PanelRegion",
    "PanelType",
    "panel_values_to_dict",
    "panels_to_dict",
    "parse_panel_values",
    "parse_panels",
    "primary_panel",
]

#: Keys of one ``panels`` entry: (required, optional).
PANEL_KEYS = (
    ("name", "in_frustum", "primaries", "lit_chart"),
    ("calibration_panel", "beta", "ramps", "region", "encoding", "peak_nits"),
)


@dataclass(frozen=True)
class PanelRegion:
    """Where a panel type sits in the volume, as seen from the chart (degrees).

    ``elevation`` from the horizon (-90 nadir, 90 zenith); ``azimuth`` from the chart's normal
    (the HDRI's centre), positive towards +x (the image's right), in [-180, 180].
    """

    elevation: tuple[float, float]
    azimuth: tuple[float, float] = (-180.0, 180.0)

    def overlaps(self, other: PanelRegion) -> bool:
        """True when the two boxes share directions (touching edges do not count)."""
        (e0, e1), (a0, a1) = self.elevation, self.azimuth
        (f0, f1), (b0, b1) = other.elevation, other.azimuth
        return e0 < f1 and f0 < e1 and a0 < b1 and b0 < a1


@dataclass(frozen=True)
class PanelType:
    """One panel type: its [SL] (3, 3) and [SRL]_j (n, 3, 3) as photographed, like a file
    without ``panels`` gives them for its one wall, plus where it is and how it is driven.

    ``panel`` is the calibration panel's geometry (a
    :class:`~ocio_vp.formats.measurements.PanelGeometry`) or None when ``beta`` is given.
    """

    name: str
    in_frustum: bool
    SL: np.ndarray
    SRL: np.ndarray
    panel: PanelGeometry | None = None
    beta: float | None = None
    ramps: Mapping[str, Ramp] | None = None
    regions: tuple[PanelRegion, ...] = ()
    encoding: str | None = None
    peak_nits: float | None = None


def primary_panel(panels: tuple[PanelType, ...]) -> PanelType:
    """The first in-frustum panel type: its M and N are solution.json's top-level ones."""
    return next(p for p in panels if p.in_frustum)


def _pair(
    ctx: Validator, value: JsonValue, key: tuple, low: float, high: float
) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ctx.error(key, f"expected [min, max] in degrees, got {describe(value)}")
    a, b = (ctx.number(v, (*key, i), minimum=low, maximum=high) for i, v in enumerate(value))
    if not a < b:
        raise ctx.error(key, f"expected min < max, got [{a:g}, {b:g}]")
    return a, b


def _region(ctx: Validator, value: JsonValue, key: tuple) -> PanelRegion:
    raw = ctx.mapping(value, key, required=("elevation",), optional=("azimuth",))
    elevation = _pair(ctx, raw["elevation"], (*key, "elevation"), -90.0, 90.0)
    azimuth = (-180.0, 180.0)
    if "azimuth" in raw:
        azimuth = _pair(ctx, raw["azimuth"], (*key, "azimuth"), -180.0, 180.0)
    return PanelRegion(elevation, azimuth)


def _regions(ctx: Validator, value: JsonValue, key: tuple) -> tuple[PanelRegion, ...]:
    """One ``{elevation, azimuth}`` box or a non-empty list of them."""
    if isinstance(value, list):
        if not value:
            raise ctx.error(key, "expected a region or a non-empty list of regions")
        return tuple(_region(ctx, v, (*key, i)) for i, v in enumerate(value))
    return (_region(ctx, value, key),)


def _parse_one(ctx: Validator, value: JsonValue, key: tuple, n: int | None) -> PanelType:
    required, optional = PANEL_KEYS
    entry = ctx.mapping(value, key, required=required, optional=optional)
    name = ctx.name(entry["name"], (*key, "name"))
    in_frustum = ctx.flag(entry["in_frustum"], (*key, "in_frustum"))
    panel, beta = ctx.calibration(entry, key)
    SL = ctx.primaries(entry["primaries"], (*key, "primaries"))
    SRL = ctx.lit_chart(entry["lit_chart"], (*key, "lit_chart"), n, "panels[0].lit_chart.red")
    ramps = None
    if "ramps" in entry:
        ramps = parse_ramps(entry["ramps"], source=ctx.source, key=(*key, "ramps"))
    regions = _regions(ctx, entry["region"], (*key, "region")) if "region" in entry else ()
    encoding, peak = ctx.encoding(entry, key, "encoding")
    return PanelType(name, in_frustum, SL, SRL, panel, beta, ramps, regions, encoding, peak)


def parse_panels(ctx: Validator, value: JsonValue) -> tuple[PanelType, ...]:
    """Validate the ``panels`` list: safe, unique names, the same number of chart patches in
    every ``lit_chart``, at least one in-frustum type, regions that do not overlap."""
    panels: list[PanelType] = []
    seen: dict[str, int] = {}
    for i, raw in enumerate(ctx.items(value, ("panels",), "panel types")):
        panel = _parse_one(ctx, raw, ("panels", i), panels[0].SRL.shape[0] if panels else None)
        ctx.unique_name(panel.name, ("panels", i), seen)
        for j, other in enumerate(panels):
            for a in panel.regions:
                if any(a.overlaps(b) for b in other.regions):
                    raise ctx.error(
                        ("panels", i, "region"),
                        f"overlaps panels[{j}].region ({other.name}): light from one "
                        "direction would be counted for two panel types",
                    )
        panels.append(panel)
    if not any(p.in_frustum for p in panels):
        raise ctx.error(
            ("panels",),
            "no panel type has in_frustum: true; one must show the in-camera background "
            "(its M and N are solution.json's top-level ones)",
        )
    return tuple(panels)


def parse_panel_values(
    ctx: Validator,
    value: JsonValue,
    key: tuple,
    panels: tuple[PanelType, ...],
    *,
    in_frustum_only: bool = False,
) -> dict[str, np.ndarray]:
    """An environment's per-panel ``w_avg`` (every panel type) or ``black_level``
    (``in_frustum_only``: in-frustum types, each optional) as ``{name: (3,)}``."""
    names = [p.name for p in panels]
    if not isinstance(value, Mapping):
        raise ctx.error(
            key,
            f"with panels, expected a mapping of panel type -> [r, g, b] ({', '.join(names)}), "
            f"got {describe(value)}",
        )
    ctx.mapping(value, key, (), tuple(names), what="panel type", listing="panel types")
    out = {}
    for panel in panels:
        if panel.name not in value:
            if not in_frustum_only:
                raise ctx.error(
                    key,
                    f"missing panel type {panel.name!r}: give the diffuse light every panel "
                    "type delivers (or no w_avg, to take it from an HDRI with --hdri)",
                )
            continue
        if in_frustum_only and not panel.in_frustum:
            raise ctx.error(
                (*key, panel.name),
                "is not an in-frustum panel type (in_frustum: false): the camera never sees "
                "its black level",
            )
        out[panel.name] = ctx.rgb(value[panel.name], (*key, panel.name))
    if not in_frustum_only and not any(np.any(v > 0) for v in out.values()):
        raise ctx.error(key, "is black for every panel type: the environment gives no light")
    return out


def lit_dicts(SL: np.ndarray, SRL: np.ndarray) -> JsonObject:
    """``primaries`` and ``lit_chart`` blocks of [SL] (3, 3) and [SRL] (n, 3, 3)."""
    return {
        "primaries": {c: floats(SL[:, k]) for k, c in enumerate(CHANNELS)},
        "lit_chart": {c: floats(SRL[:, :, k]) for k, c in enumerate(CHANNELS)},
    }


def _region_dict(region: PanelRegion) -> JsonObject:
    out: JsonObject = {"elevation": list(region.elevation)}
    if region.azimuth != (-180.0, 180.0):
        out["azimuth"] = list(region.azimuth)
    return out


def panels_to_dict(panels: tuple[PanelType, ...]) -> list[JsonObject]:
    """The inverse of :func:`parse_panels` (plain Python types, file key order)."""
    out = []
    for p in panels:
        entry: JsonObject = {"name": p.name, "in_frustum": p.in_frustum}
        if p.panel is not None:
            entry["calibration_panel"] = p.panel.to_dict()
        if p.beta is not None:
            entry["beta"] = p.beta
        entry |= lit_dicts(p.SL, p.SRL)
        if p.ramps is not None:
            entry["ramps"] = ramps_to_dict(p.ramps)
        if p.regions:
            regions = [_region_dict(r) for r in p.regions]
            entry["region"] = regions[0] if len(regions) == 1 else regions
        if p.encoding is not None:
            entry["encoding"] = p.encoding
        if p.peak_nits is not None:
            entry["peak_nits"] = p.peak_nits
        out.append(entry)
    return out


def panel_values_to_dict(values: Mapping[str, np.ndarray]) -> JsonObject:
    """``{name: [r, g, b]}`` of per-panel values (plain floats)."""
    return {name: floats(rgb) for name, rgb in values.items()}
