"""The ``linearity`` block of ``solution.json`` as typed records, data only (``wall/`` computes
with them and imports this module, not the reverse): :func:`ocio_vp.wall.linearity.fit_linearity`
makes it from the measured ramps, later steps add the wall encoding, the pre-correction LUT and
the soft clip. A block read back is written with the keys it had, in their order.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocio_vp.formats.jsontypes import JsonValue
from ocio_vp.formats.records import Record, read_record

__all__ = [
    "MEASURED_KEYS",
    "ChannelBlack",
    "ChannelNoise",
    "Linearity",
    "LinearityChannel",
    "LutFile",
    "ShadowDeviation",
    "SoftClip",
    "WallEncodingBlock",
    "assumed_linearity",
    "read_linearity",
]


#: The keys of a measured block, in file order (the later steps add theirs after them).
MEASURED_KEYS = (
    "measured",
    "model",
    "summary",
    "notes",
    "warnings",
    "tolerance",
    "relative_tolerance",
    "max_deviation",
    "projection",
    "channels",
    "lut",
)


@dataclass(frozen=True)
class ChannelBlack(Record):
    """What was subtracted as black: where it came from, its camera RGB and its level
    (fraction of the top step)."""

    source: str
    camera: np.ndarray
    level: float


@dataclass(frozen=True)
class ChannelNoise(Record):
    """The ramp's noise: ``floor`` (fraction of the top step), ``relative`` (of the level),
    where it came from, and the level below which steps are not detected."""

    floor: float
    relative: float
    source: str
    detection_limit: float


@dataclass(frozen=True)
class ShadowDeviation(Record):
    """The worst deviation from linear relative to the level (``r/d - 1``), with its
    uncertainty and the drive it is at."""

    relative: float
    uncertainty: float
    drive: float


@dataclass(frozen=True)
class LinearityChannel(Record):
    """One LED channel's fitted response (``channels.<name>``): the knots of the monotone
    model, the response at every step, how far from linear and whether the LUT corrects it,
    the black and noise, the steps left out or pooled, and the checks against ``primaries``."""

    drive: np.ndarray
    response: np.ndarray
    measured_response: np.ndarray
    max_deviation: float
    shadow_deviation: ShadowDeviation | None
    corrected: bool
    black: ChannelBlack
    noise: ChannelNoise
    below_floor: list[int]
    merged: list[list[int]]
    at_top: list[int]
    projection_residual: float
    top_step_vs_primary: float


@dataclass(frozen=True)
class LutFile(Record):
    """The pre-correction LUT the config uses (``lut``): its sidecar file, size, input
    domain, and how linear the modelled panel is through it (``max_error`` and per band)."""

    file: str
    entries: int
    domain: str
    max_error: float
    bands: list[dict[str, float]]
    definition: str


@dataclass(frozen=True)
class WallEncodingBlock(Record):
    """The wall's signal encoding as recorded (``wall_encoding``): its name and, for PQ, the
    peak (:class:`ocio_vp.wall.encoding.WallEncoding` is the encoding itself)."""

    OMIT_NONE = ("peak_nits",)

    name: str
    peak_nits: float | None = None


@dataclass(frozen=True)
class SoftClip(Record):
    """The soft clip of the wall's highlights (:mod:`ocio_vp.wall.softclip`)."""

    knee: float
    curve: str
    full_drive: float
    inverse_cap: float


@dataclass(frozen=True)
class Linearity(Record):
    """The ``linearity`` block: the measured fit (``measured`` true: its summary, notes,
    warnings, tolerances and each channel), or a linear response assumed; the pre-correction
    LUT when a channel needs one, the wall's signal encoding and the soft clip when set.

    ``present`` lists the block's keys in file order (a block keeps the keys it was made or
    read with); :meth:`updated` adds keys after them, as the later steps do.
    """

    OMIT_NONE = (*MEASURED_KEYS[2:], "wall_encoding", "soft_clip")

    measured: bool
    model: str
    summary: str | None = None
    notes: list[str] | None = None
    warnings: list[str] | None = None
    tolerance: float | None = None
    relative_tolerance: float | None = None
    max_deviation: float | None = None
    projection: str | None = None
    channels: dict[str, LinearityChannel] | None = None
    lut: LutFile | None = None
    wall_encoding: WallEncodingBlock | None = None
    soft_clip: SoftClip | None = None
    present: tuple[str, ...] | None = field(default=None, compare=False)
    #: Keys this version does not know, kept as read (written back unchanged).
    extra: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def corrected(self) -> bool:
        """Whether any channel needs the pre-correction LUT."""
        return any(c.corrected for c in (self.channels or {}).values())

    def updated(
        self,
        *,
        lut: LutFile | None = None,
        wall_encoding: WallEncodingBlock | None = None,
        soft_clip: SoftClip | None = None,
    ) -> Linearity:
        """A copy with the blocks given set (a key the block lacks goes after its keys)."""
        given = (("lut", lut), ("wall_encoding", wall_encoding), ("soft_clip", soft_clip))
        keys = self.present or tuple(self.to_dict())
        added = (k for k, v in given if v is not None and k not in keys)
        return dataclasses.replace(
            self,
            lut=self.lut if lut is None else lut,
            wall_encoding=self.wall_encoding if wall_encoding is None else wall_encoding,
            soft_clip=self.soft_clip if soft_clip is None else soft_clip,
            present=(*keys, *added),
        )


def assumed_linearity() -> Linearity:
    """The block of a wall without measured ramps: a linear response assumed."""
    return Linearity(measured=False, model="linear (assumed)", present=("measured", "model"))


def read_linearity(data: JsonValue, key: str = "linearity") -> Linearity | None:
    """The block as read from ``solution.json`` (None when absent); InputError naming ``key``
    when a value has the wrong type."""
    return None if data is None else read_record(Linearity, data, key)
