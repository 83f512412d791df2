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

__all__ = ["ContentScale", "content_scale"]

CHANNELS = ("red", "green", "blue")
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

    def headroom_stops(self, drive: np.ndarray) -> list[float]:
        return [-math.log2(d) if d > 0 else math.inf for d in drive]

    def to_dict(self) -> dict:
        return {
            "content_space": self.content_space,
            "content_white_camera_rgb": self.white_camera.tolist(),
            "outer_drive": self.outer_drive.tolist(),
            "inner_drive": self.inner_drive.tolist(),
            "outer_headroom_stops": self.headroom_stops(self.outer_drive),
            "inner_headroom_stops": self.headroom_stops(self.inner_drive),
            "peak_content": self.peak_content,
            "clips": self.clips,
            "drive_1_nits": self.peak_nits,
            "content_white_nits": self.white_nits,
        }

    def lines(self) -> list[str]:
        """The terminal's lines: the mapping, the drives and headroom, a warning if it clips."""

        def drives(drive: np.ndarray) -> str:
            stops = self.headroom_stops(drive)
            return ", ".join(
                f"{c[0].upper()} {100 * d:.0f}% ({s:+.2f} stops)"
                for c, d, s in zip(CHANNELS, drive, stops, strict=True)
            )

        head = (
            f"content scale, {self.environment}: content white (1.0 in {self.content_space}) "
            f"needs drive {drives(self.outer_drive)} of the measured peak outside the frustum, "
            f"{drives(self.inner_drive)} inside"
        )
        if self.peak_nits is not None:
            head += (
                f"; drive 1.0 = {self.peak_nits:g} nits, content white = "
                f"{self.white_nits:.0f} nits{self.luminance_note}"
            )
        out = [head]
        if self.clips:
            channel = _worst_channel(self)
            out.append(
                f"warning: {self.environment}: content white needs {100 * self.worst_drive:.0f}% "
                f"of the panel's peak in {channel}: content above {self.peak_content:.3g} clips "
                f"there; scale the content by {self.peak_content:.3g} or less (or light brighter "
                "panels)"
            )
        return out


def _worst_channel(scale: ContentScale) -> str:
    both = np.maximum(scale.outer_drive, scale.inner_drive)
    return CHANNELS[int(np.argmax(both))]


def _white_camera(camera: str | None) -> tuple[np.ndarray, str, np.ndarray | None]:
    """(camera RGB of content white, the content space's name, the camera's Y row or None)."""
    if not camera:
        return np.ones(3), "camera native RGB", None
    import colour

    target = colour.RGB_COLOURSPACES[camera]
    to_camera = colour.matrix_RGB_to_RGB(
        colour.RGB_COLOURSPACES[CONTENT_SPACE], target, chromatic_adaptation_transform="CAT02"
    )
    return to_camera @ np.ones(3), CONTENT_SPACE_NAME, np.asarray(target.matrix_RGB_to_XYZ)[1]


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
    encoding = ((solution.linearity or {}).get("wall_encoding")) or {}
    peak = white = None
    note = ""
    if encoding.get("name") == "pq":
        peak = float(encoding.get("peak_nits", 1000.0))
        SL = np.asarray(solution.SL, dtype=np.float64)
        if y_row is None:
            y_row, note = (
                np.array([0.0, 1.0, 0.0]),
                " (camera green as luminance: gamut not stated)",
            )
        white = peak * float(y_row @ c) / float(y_row @ (SL @ np.ones(3)))
    return ContentScale(
        solution.environment, space, c, M @ c, inner @ c + offset, peak, white, note
    )
