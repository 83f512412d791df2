"""The wall drive's soft clip (:mod:`ocio_vp.wall.softclip`) as OCIO transform records, both ways.

The curve ``f(d) = 1 - (1 - k) exp(-(d - k) / (1 - k))`` above the knee ``k``, the identity
below, is exactly OCIO's ``LogCameraTransform`` inverted, with base e, ``logSideSlope =
-(1 - k)``, ``logSideOffset = k``, ``linSideSlope = -1 / (1 - k)``, ``linSideOffset = 1 / (1 - k)``
and ``linSideBreak = k`` (the linear segment OCIO derives below the break is the identity): no
table, no interpolation error. The other direction caps the signal at
:data:`~ocio_vp.wall.softclip.INVERSE_CAP` (the inverse diverges at 1), then runs it forward.
"""

from __future__ import annotations

import math

from ocio_vp.formats.linearity import Linearity
from ocio_vp.ocio.description import Transform, clamp
from ocio_vp.wall.softclip import INVERSE_CAP, check_knee, soft_clip_knee

__all__ = ["soft_clip_text", "soft_clip_transforms"]


def _curve(knee: float, *, inverse: bool) -> Transform:
    span = 1.0 - knee
    values = {
        "Base": math.e,
        "LinSideBreakValue": knee,
        "LogSideSlopeValue": -span,
        "LogSideOffsetValue": knee,
        "LinSideSlopeValue": -1.0 / span,
        "LinSideOffsetValue": 1.0 / span,
    }
    params = tuple((k, v if k == "Base" else (v,) * 3) for k, v in values.items())
    return Transform("LogCameraTransform", params, inverse=inverse)


def soft_clip_transforms(knee: float) -> tuple[list[Transform], list[Transform]]:
    """(drive -> clipped drive, clipped drive -> drive) transform records for ``knee``."""
    check_knee(knee)
    cap = clamp(max_in=INVERSE_CAP, max_out=INVERSE_CAP)
    return [_curve(knee, inverse=True)], [cap, _curve(knee, inverse=False)]


def soft_clip_text(linearity: Linearity | None) -> str:
    """What a wall colour space's description adds for a soft clip ("" without one)."""
    knee = soft_clip_knee(linearity)
    if knee is None:
        return ""
    return (
        f", then a soft clip of each channel's drive from {knee:g} of full drive on "
        f"(1 - {1 - knee:g} exp(-(d - {knee:g}) / {1 - knee:g}) above it, approaching full drive)"
    )
