"""The optional ``fixtures`` section of a measurements file: practical lights beside the wall
(keys: docs/fixtures.md).

Each fixture is described by what the camera saw of it, like the wall's ``lit_chart``: one
chart per channel at ``reference_drive``. The solver assumes light proportional to drive, so
channel c at drive u lights the chart ``u / reference_drive`` times its ``lit_chart``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocio_vp.formats.checker import Validator
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.records import floats

__all__ = ["DMX_MODES", "DmxPatch", "Fixture", "fixtures_to_dict", "parse_fixtures"]

#: Fixture modes: DMX slots per channel.
DMX_MODES = {"8-bit": 1, "16-bit": 2}
MAX_UNIVERSE = 63999


@dataclass(frozen=True)
class DmxPatch:
    """Where a fixture is patched: universe, start address (1-512) and mode (:data:`DMX_MODES`)."""

    universe: int
    address: int
    mode: str

    def to_dict(self) -> JsonObject:
        return {"universe": self.universe, "address": self.address, "mode": self.mode}


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
    dmx: DmxPatch | None = None

    @property
    def per_unit_drive(self) -> np.ndarray:
        """(n, 3, k): camera RGB of every patch per unit drive of each channel."""
        return np.moveaxis(self.lit_chart, 0, 2) / self.reference_drive


def _parse_one(ctx: Validator, value: JsonValue, key: tuple, n: int) -> Fixture:
    entry = ctx.mapping(
        value,
        key,
        required=("name", "channels", "reference_drive", "lit_chart"),
        optional=("max_drive", "pixel_mapped", "direct", "dmx"),
    )
    name = ctx.name(entry["name"], (*key, "name"))
    listed = ctx.items(entry["channels"], (*key, "channels"), "channel names")
    channels = tuple(ctx.name(c, (*key, "channels", i)) for i, c in enumerate(listed))
    if len(set(channels)) != len(channels):
        raise ctx.error((*key, "channels"), f"channel names repeat: {list(channels)}")
    reference = ctx.number(entry["reference_drive"], (*key, "reference_drive"), strict=True)
    max_drive = ctx.number(entry.get("max_drive", 1.0), (*key, "max_drive"), strict=True)
    pixel_mapped = ctx.flag(entry.get("pixel_mapped", False), (*key, "pixel_mapped"))
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
    dmx = _parse_dmx(ctx, entry["dmx"], (*key, "dmx"), len(channels)) if "dmx" in entry else None
    return Fixture(name, channels, reference, chart, max_drive, pixel_mapped, direct, dmx)


def _parse_dmx(ctx: Validator, value: JsonValue, key: tuple, channels: int) -> DmxPatch:
    entry = ctx.mapping(value, key, required=("universe", "address", "mode"))
    universe = ctx.whole(entry["universe"], (*key, "universe"), 0, MAX_UNIVERSE, noun="an integer")
    address = ctx.whole(entry["address"], (*key, "address"), 1, 512, noun="an integer")
    mode = ctx.choice(entry["mode"], (*key, "mode"), tuple(DMX_MODES), quoted=True)
    last = address + channels * DMX_MODES[mode] - 1
    if last > 512:
        raise ctx.error(
            (*key, "address"),
            f"{channels} channels in {mode} mode from address {address} end at {last}, past 512",
        )
    return DmxPatch(universe, address, mode)


def parse_fixtures(ctx: Validator, value: JsonValue, n: int) -> tuple[Fixture, ...]:
    """Validate the ``fixtures`` list (``n`` chart patches).

    Every error names the file and the key path (``fixtures[0].lit_chart.white[3][1]``).
    """
    listed = ctx.items(value, ("fixtures",), "fixtures")
    fixtures = tuple(_parse_one(ctx, v, ("fixtures", i), n) for i, v in enumerate(listed))
    names = [f.name for f in fixtures]
    for i, name in enumerate(names):
        if name in names[:i]:
            raise ctx.error(("fixtures", i, "name"), f"fixture name {name!r} is used twice")
    return fixtures


def fixtures_to_dict(fixtures: tuple[Fixture, ...]) -> list[JsonObject]:
    """The inverse of :func:`parse_fixtures` (plain Python types)."""
    out = []
    for f in fixtures:
        entry: JsonObject = {
            "name": f.name,
            "channels": list(f.channels),
            "reference_drive": float(f.reference_drive),
            "max_drive": float(f.max_drive),
        }
        if f.pixel_mapped:
            entry["pixel_mapped"] = True
        entry["lit_chart"] = {c: floats(f.lit_chart[k]) for k, c in enumerate(f.channels)}
        if f.direct is not None:
            entry["direct"] = {c: floats(f.direct[k]) for k, c in enumerate(f.channels)}
        if f.dmx is not None:
            entry["dmx"] = f.dmx.to_dict()
        out.append(entry)
    return out
