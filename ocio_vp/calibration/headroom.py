"""Content scale and headroom: what scene-linear content 1.0 asks of the wall.

Drive 1.0 is the level at which the primaries were measured (the panel's peak as calibrated).
Content white, (1, 1, 1) in the content's working space (Unreal's ``Linear Rec.709 (sRGB)``
when the camera gamut is known, else the camera's native RGB), is the camera RGB ``c``; the
wall drives it with ``M c`` outside the frustum and ``N c + offset`` inside (LeGendre et al.
2022, eqs. 2 and 8). Each channel's headroom is ``-log2(drive)`` stops: negative headroom means
content white already needs more than the panel has in that channel, and content brighter
than ``1 / max(drive)`` clips there. On a PQ wall drive 1.0 is ``peak_nits`` cd/m2 and content
white is ``peak_nits * Y(c) / Y(SL 1)`` (the camera gamut's luminance row; without a gamut the
camera's green stands in for luminance, and the text says so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ocio_vp.formats.solution import Solution
from ocio_vp.metrics import rgb_to_rgb_cat02
from ocio_vp.wall.encoding import WallEncoding
from ocio_vp.wall.linearity import CHANNELS
from ocio_vp.wall.softclip import soft_clip_knee

__all__ = ["ContentScale", "content_scale", "content_scale_lines"]

#: Unreal's working space, the content source of the Unreal export when the gamut is known.
CONTENT_SPACE = "ITU-R BT.709"
CONTENT_SPACE_NAME = "Linear Rec.709 (sRGB)"


@dataclass(frozen=True)
class ContentScale:
    """What content white needs of the wall (see the module docstring)."""

    environment: str
    content_space: str
    white_camera: np.ndarray
    outer_drive: np.ndarray
    inner_drive: np.ndarray
    peak_nits: float | None = None
    white_nits: float | None = None
    luminance_note: str = ""
    #: The wall's soft clip (``solve --soft-clip``): the fraction of full drive where it starts.
    soft_clip: float | None = None

    @property
    def worst_drive(self) -> float:
        return float(max(self.outer_drive.max(), self.inner_drive.max()))

    @property
    def clips(self) -> bool:
        """Whether content white needs more drive than the panel has."""
        return self.worst_drive > 1.0

    @property
    def peak_content(self) -> float:
        """The content value (grey) whose drive first reaches 1.0 in some channel."""
        return 1.0 / self.worst_drive if self.worst_drive > 0 else math.inf

    @property
    def knee_content(self) -> float | None:
        """The content value (grey) whose drive first reaches the soft clip's knee (None
        without a soft clip): above it the wall compresses."""
        if self.soft_clip is None:
            return None
        return self.soft_clip * self.peak_content

    @property
    def negative_channels(self) -> list[str]:
        """Channels where content white needs drive below zero, outside or inside the frustum."""
        both = np.minimum(self.outer_drive, self.inner_drive)
        return [c for c, d in zip(CHANNELS, both, strict=True) if d < 0]

    def headroom_stops(self, drive: np.ndarray) -> list[float | None]:
        """Stops of headroom per channel; None where content white needs no positive drive
        (zero, or negative: light the wall cannot take away, so that channel shows 0)."""
        return [-math.log2(d) if d > 0 else None for d in drive]

    def to_dict(self) -> dict:
        clip = {} if self.soft_clip is None else {"soft_clip_knee": self.soft_clip}
        return {
            "content_space": self.content_space,
            "content_white_camera_rgb": self.white_camera.tolist(),
            "outer_drive": self.outer_drive.tolist(),
            "inner_drive": self.inner_drive.tolist(),
            "outer_headroom_stops": self.headroom_stops(self.outer_drive),
            "inner_headroom_stops": self.headroom_stops(self.inner_drive),
            "peak_content": self.peak_content if math.isfinite(self.peak_content) else None,
            "clips": self.clips,
            "drive_1_nits": self.peak_nits,
            "content_white_nits": self.white_nits,
            **clip,
        }

    def row(self) -> str:
        """One terminal line: the drive content white needs per channel, outside / inside the
        frustum in % of the measured peak, the content value that reaches the peak and the
        worst channel's headroom; on a PQ wall the nits of drive 1.0 and of content white."""
        pairs = " ".join(
            f"{c[0].upper()} {100 * o:.0f}/{100 * i:.0f}"
            for c, o, i in zip(CHANNELS, self.outer_drive, self.inner_drive, strict=True)
        )
        stops = -math.log2(self.worst_drive) if self.worst_drive > 0 else math.inf
        text = (
            f"{self.environment}: {pairs}; peak at content {self.peak_content:.3g} "
            f"({stops:+.2f} stops in {_worst_channel(self)})"
        )
        if self.white_nits is not None:
            text += f"; content white {self.white_nits:.0f} nits{self.luminance_note}"
        if self.soft_clip is not None:
            text += (
                f"; soft clip from {100 * self.soft_clip:.0f}% of full drive (content "
                f"{self.knee_content:.3g}) on"
            )
        return text

    def lines(self) -> list[str]:
        """The header and :meth:`row` (as :func:`content_scale_lines` prints one)."""
        return [header(self.content_space, self.peak_nits), "  " + self.row()]


def header(content_space: str, peak_nits: float | None = None) -> str:
    """What the content-scale rows mean (on a PQ wall, with the nits of drive 1.0)."""
    nits = "" if peak_nits is None else f"; drive 1.0 = {peak_nits:g} nits"
    return (
        f"content scale: content white = 1.0 in {content_space}; the drive it needs in % of the "
        f"measured peak, outside/inside the frustum, and the content value that reaches the "
        f"peak{nits}:"
    )


def content_scale_lines(scales: list[ContentScale]) -> tuple[list[str], list[str]]:
    """(stdout lines, stderr lines): a header, one row per environment, and one warning naming
    the environments where content white needs more drive than the panel has."""
    if not scales:
        return [], []
    out = [header(scales[0].content_space, scales[0].peak_nits), *("  " + s.row() for s in scales)]
    warnings = [_negative_warning(s) for s in scales if s.negative_channels]
    clipping = [s for s in scales if s.clips]
    if not clipping:
        return out, warnings
    worst = max(clipping, key=lambda s: s.worst_drive)
    names = ", ".join(s.environment for s in clipping)
    above = "clips there"
    if all(s.soft_clip is not None for s in clipping):
        above = "is compressed towards full drive by the soft clip, not reproduced"
    warning = (
        f"warning: {names}: content white needs more drive than the panel has (worst "
        f"{worst.environment}: {100 * worst.worst_drive:.0f}% in {_worst_channel(worst)}): content "
        f"above each row's peak {above}; scale the content down to it"
    )
    return out, [warning, *warnings]


def _negative_warning(scale: ContentScale) -> str:
    channels = " and ".join(scale.negative_channels)
    return (
        f"warning: {scale.environment}: content white needs negative drive in {channels}: the "
        "wall cannot take light away, so that channel shows 0 and white is tinted; the LEDs "
        "cannot reach this environment's white (see the note on the LEDs' gamut); render content "
        "white inside the LEDs' gamut, or accept the tint"
    )


def _worst_channel(scale: ContentScale) -> str:
    both = np.maximum(scale.outer_drive, scale.inner_drive)
    return CHANNELS[int(np.argmax(both))]


def _white_camera(camera: str | None) -> tuple[np.ndarray, str, np.ndarray | None]:
    """(camera RGB of content white, the content space's name, the camera's Y row or None)."""
    if not camera:
        return np.ones(3), "camera native RGB", None
    import colour

    y_row = np.asarray(colour.RGB_COLOURSPACES[camera].matrix_RGB_to_XYZ)[1]
    return rgb_to_rgb_cat02(CONTENT_SPACE, camera) @ np.ones(3), CONTENT_SPACE_NAME, y_row


def content_scale(solution: Solution) -> ContentScale:
    """The :class:`ContentScale` of a solved environment."""
    c, space, y_row = _white_camera(solution.camera_colorspace)
    M = np.asarray(solution.M, dtype=np.float64)
    inner = M if solution.N is None else np.asarray(solution.N, dtype=np.float64)
    offset = (
        np.zeros(3)
        if solution.black_level_offset is None
        else np.asarray(solution.black_level_offset)
    )
    encoding = WallEncoding.of(solution.linearity)
    peak = white = None
    note = ""
    if encoding.peak_nits is not None:  # PQ: the wall's white in cd/m2
        peak = encoding.peak_nits
        SL = np.asarray(solution.SL, dtype=np.float64)
        if y_row is None:
            y_row, note = (
                np.array([0.0, 1.0, 0.0]),
                " (camera green as luminance: gamut not stated)",
            )
        white = peak * float(y_row @ c) / float(y_row @ (SL @ np.ones(3)))
    knee = soft_clip_knee(solution.linearity)
    return ContentScale(
        solution.environment, space, c, M @ c, inner @ c + offset, peak, white, note, knee
    )
