"""The optional ``fixtures`` section of a measurements file: practical lights beside the wall.

Each fixture (an RGBW soft light, an RGBACL panel, a pixel-mapped tile with a white channel) is
described by what the camera saw of it, like the wall's ``lit_chart``::

    fixtures:
      - name: key                     # same rules as environment names
        channels: [red, green, blue, white]
        reference_drive: 1.0          # the drive at which each channel's chart was shot
        max_drive: 1.0                # optional, default 1.0
        pixel_mapped: false           # optional: fed from the content (exports a k x 3 matrix)
        lit_chart:                    # the chart lit by that channel alone, as photographed
          red: [[r, g, b], ...]       # one row per patch, same camera/exposure as lit_chart
          ...
        direct:                       # optional: camera RGB of each channel seen directly
          red: [r, g, b]

The solver assumes each channel's light is proportional to its drive (set the fixture's dimming
curve to linear), so the chart lit by channel c at drive u is ``u / reference_drive`` times
its ``lit_chart``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Fixture", "fixtures_to_dict", "parse_fixtures"]


@dataclass(frozen=True)
class Fixture:
    """One practical light: ``lit_chart`` (k, n, 3) per channel at ``reference_drive``."""

    name: str
    channels: tuple[str, ...]
    reference_drive: float
    lit_chart: np.ndarray
    max_drive: float = 1.0
    pixel_mapped: bool = False
    direct: np.ndarray | None = None  # (k, 3) or None

    @property
    def per_unit_drive(self) -> np.ndarray:
        """(n, 3, k): camera RGB of every patch per unit drive of each channel."""
        return np.moveaxis(self.lit_chart, 0, 2) / self.reference_drive


def _parse_one(ctx: Any, value: Any, key: tuple, n: int) -> Fixture:
    entry = ctx.mapping(
        value,
        key,
        required=("name", "channels", "reference_drive", "lit_chart"),
        optional=("max_drive", "pixel_mapped", "direct"),
    )
    name = ctx.name(entry["name"], (*key, "name"))
    channels = entry["channels"]
    if not isinstance(channels, list) or not channels:
        raise ctx.error((*key, "channels"), "expected a non-empty list of channel names")
    channels = tuple(ctx.name(c, (*key, "channels", i)) for i, c in enumerate(channels))
    if len(set(channels)) != len(channels):
        raise ctx.error((*key, "channels"), f"channel names repeat: {list(channels)}")
    reference = ctx.number(entry["reference_drive"], (*key, "reference_drive"), strict=True)
    max_drive = ctx.number(entry.get("max_drive", 1.0), (*key, "max_drive"), strict=True)
    pixel_mapped = entry.get("pixel_mapped", False)
    if not isinstance(pixel_mapped, bool):
        raise ctx.error((*key, "pixel_mapped"), f"expected true or false, got {pixel_mapped!r}")
    lit = ctx.mapping(entry["lit_chart"], (*key, "lit_chart"), required=channels)
    chart = np.stack([ctx.chart(lit[c], (*key, "lit_chart", c), n) for c in channels])
    for k, c in enumerate(channels):
        if not np.any(chart[k] > 0):
            raise ctx.error(
                (*key, "lit_chart", c), "the chart is black: the channel gives no light"
            )
    direct = None
    if "direct" in entry:
        seen = ctx.mapping(entry["direct"], (*key, "direct"), required=channels)
        direct = np.stack([ctx.rgb(seen[c], (*key, "direct", c)) for c in channels])
    return Fixture(name, channels, reference, chart, max_drive, pixel_mapped, direct)


def parse_fixtures(ctx: Any, value: Any, n: int) -> tuple[Fixture, ...]:
    """Validate the ``fixtures`` list (``n`` chart patches).

    ``ctx`` is the measurements file's :class:`~ocio_vp.formats.measurements.Validator`, so every
    error names the file and the key path (``fixtures[0].lit_chart.white[3][1]``).
    """
    if not isinstance(value, list) or not value:
        raise ctx.error(("fixtures",), "expected a non-empty list of fixtures")
    fixtures = tuple(_parse_one(ctx, v, ("fixtures", i), n) for i, v in enumerate(value))
    names = [f.name for f in fixtures]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ctx.error(("fixtures", i, "name"), f"fixture name {name!r} is used twice")
    return fixtures


def fixtures_to_dict(fixtures: tuple[Fixture, ...]) -> list[dict[str, Any]]:
    """The inverse of :func:`parse_fixtures` (plain Python types)."""
    out = []
    for f in fixtures:
        entry: dict[str, Any] = {
            "name": f.name,
            "channels": list(f.channels),
            "reference_drive": float(f.reference_drive),
            "max_drive": float(f.max_drive),
        }
        if f.pixel_mapped:
            entry["pixel_mapped"] = True
        entry["lit_chart"] = {
            c: [[float(v) for v in row] for row in f.lit_chart[k]] for k, c in enumerate(f.channels)
        }
        if f.direct is not None:
            entry["direct"] = {c: [float(v) for v in f.direct[k]] for k, c in enumerate(f.channels)}
        out.append(entry)
    return out
