"""An optional soft clip of the wall drive (``solve --soft-clip KNEE``), in numpy.

Per channel, on linear drive (1.0 = the panel's full drive as measured), after M (outside the
frustum) or N + offset (inside) and before the linearity LUT and the signal encoding::

    f(d) = d                                        d <= k
    f(d) = 1 - (1 - k) exp(-(d - k) / (1 - k))      d >  k

``k`` is the knee (0 < k < 1). Its properties, why :data:`FULL_TOLERANCE` is met, and how the
config carries ``f`` and its inverse (capped at :data:`INVERSE_CAP`) are in docs/headroom.md.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ocio_vp.formats.linearity import Linearity, SoftClip, assumed_linearity

if TYPE_CHECKING:
    from ocio_vp.formats.solution import Solution

__all__ = [
    "FULL_TOLERANCE",
    "INVERSE_CAP",
    "SOFT_CLIP_CURVE",
    "check_knee",
    "forward",
    "full_drive",
    "inverse",
    "soft_clip_knee",
    "with_soft_clip",
]

#: How close to full drive the curve must come by the largest drive content asks for.
FULL_TOLERANCE = 1.0 / 1023.0
#: The largest signal the config's inverse takes (above it, the inverse returns its value here).
INVERSE_CAP = 1.0 - 2.0**-12
#: What solution.json says the curve is.
SOFT_CLIP_CURVE = "d <= knee: d; d > knee: 1 - (1 - knee) exp(-(d - knee) / (1 - knee))"


def check_knee(knee: float) -> None:
    """Raise ValueError unless ``0 < knee < 1`` (a finite fraction of full drive)."""
    if not (math.isfinite(knee) and 0.0 < knee < 1.0):
        raise ValueError(f"expected a knee in (0, 1) (a fraction of full drive), got {knee:g}")


def forward(drive: np.ndarray, knee: float) -> np.ndarray:
    """The soft clip ``f(drive)`` (float64; see the module docstring)."""
    check_knee(knee)
    d = np.asarray(drive, dtype=np.float64)
    span = 1.0 - knee
    above = 1.0 - span * np.exp(-np.maximum(d - knee, 0.0) / span)
    return np.where(d > knee, above, d)


def inverse(signal: np.ndarray, knee: float) -> np.ndarray:
    """``f^-1`` on ``signal < 1`` (float64); ``inf`` at 1.0 and above, where ``f`` has no
    inverse (the config caps its input at :data:`INVERSE_CAP` first)."""
    check_knee(knee)
    y = np.asarray(signal, dtype=np.float64)
    span = 1.0 - knee
    with np.errstate(divide="ignore", invalid="ignore"):
        above = knee - span * np.log(np.maximum(1.0 - y, 0.0) / span)
    return np.where(y > knee, above, y)


def full_drive(knee: float) -> float:
    """The drive from which ``f`` is within :data:`FULL_TOLERANCE` of 1.0."""
    check_knee(knee)
    span = 1.0 - knee
    return knee + span * max(math.log(span / FULL_TOLERANCE), 0.0)


def soft_clip_knee(linearity: Linearity | None) -> float | None:
    """The knee recorded in a ``linearity`` block, or None (off; files without one)."""
    if linearity is None or linearity.soft_clip is None:
        return None
    return linearity.soft_clip.knee


def with_soft_clip(solution: Solution, knee: float | None) -> Solution:
    """A copy of ``solution`` whose ``linearity`` block (and every panel type's) records the
    soft clip; ``knee`` None returns ``solution`` unchanged."""
    if knee is None:
        return solution
    check_knee(knee)
    block = SoftClip(
        knee=float(knee),
        curve=SOFT_CLIP_CURVE,
        full_drive=round(full_drive(knee), 6),
        inverse_cap=INVERSE_CAP,
    )

    def clipped(linearity: Linearity | None) -> Linearity:
        return (linearity or assumed_linearity()).updated(soft_clip=block)

    panels = solution.panels
    if panels:
        panels = {
            name: dataclasses.replace(panel, linearity=clipped(panel.linearity))
            for name, panel in panels.items()
        }
    return dataclasses.replace(solution, linearity=clipped(solution.linearity), panels=panels)
