"""The skin figures of a solve (``diagnostics.skin``: :class:`ocio_vp.formats.skin.SkinFigures`).

Every figure is measured on the solve's own data: the problem's skin samples
(:mod:`ocio_vp.correction.skin`) and chart, the chosen post-correction and the paper's least
squares fitted to the same patches; with skin first also the default post-correction
(``auto``), the wall's LEDs in frame through each (emitter damage) and the chart colours each
in-frustum matrix ``N = M Q^-1`` drives outside the wall's range and the error of the chart
shown in frustum through each (the background, :func:`background_error`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ocio_vp.calibration.diagnostics import in_frustum_drive_range
from ocio_vp.calibration.equations import condition_number
from ocio_vp.correction.extrapolation import in_frame_led_damage
from ocio_vp.correction.linear import patch_errors
from ocio_vp.correction.problem import QProblem, fit_least_squares
from ocio_vp.formats.skin import SkinBand, SkinDefault, SkinFigures
from ocio_vp.metrics import camera_delta_E_2000, sample_camera_to_xyz, white_scale
from ocio_vp.model.correction import MatrixCorrection, PostCorrection
from ocio_vp.skin_data import ITA_BANDS

__all__ = [
    "Judged",
    "background_error",
    "chart_error",
    "clipped_background",
    "judged",
    "shown_error",
    "skin_errors",
    "skin_figures",
]

#: An in-frustum matrix is not formed from a Q less well conditioned than this (as N's solve).
_MAX_CONDITION = 1e8
#: "No worse" up to rounding: a figure may exceed the default's by this fraction of itself.
_ROUNDING = 1e-9


def _fraction(value: float) -> float | None:
    """An error relative to white: None where not defined."""
    return float(value) if np.isfinite(value) else None


def _background_outside(problem: QProblem, correction: PostCorrection) -> int:
    """Chart colours ``N = M Q^-1`` drives outside [0, 1] (-1 where Q has no inverse)."""
    Q = correction.matrix
    if not condition_number(Q) < _MAX_CONDITION:
        return -1
    N = np.asarray(problem.M, dtype=np.float64) @ np.linalg.inv(Q)
    drive = in_frustum_drive_range(
        np.asarray(problem.target, dtype=np.float64),
        M=problem.M,
        matrix=N,
        white_patch=problem.white_patch,
    )
    return int(drive.below_zero + drive.above_max)


def background_error(
    problem: QProblem, correction: PostCorrection, patches: np.ndarray | None = None
) -> float:
    """The in-frustum background's expected error, mean over the chart and R, G, B relative to
    white: the target chart shown as content through ``Q^-1`` and the calibrated wall
    (``d = M Q^-1(p) - M b``, the exact black-level offset where the black level ``b`` was
    measured), each drive clipped at 0 as the wall clips it, seen as ``[SL] d + b`` and
    corrected by ``Q``. With the wall as measured the only error is the clipping: chart colours
    outside the LEDs' gamut, which ``Q^-1`` moves. The top of the drive range is not modelled
    (where it lies depends on the exposure, unknown to the solve). NaN where Q has no inverse.
    ``patches``: only these (a boolean mask; the mean is then over them).
    """
    if not correction.invertible or not condition_number(correction.matrix) < _MAX_CONDITION:
        return float("nan")
    P = np.asarray(problem.target, dtype=np.float64)
    mask = np.ones(len(P), dtype=bool) if patches is None else np.asarray(patches, dtype=bool)
    return shown_error(problem, correction, correction.inverse(P[mask]), P[mask])


def shown_error(
    problem: QProblem, correction: PostCorrection, content: np.ndarray, P: np.ndarray
) -> float:
    """Mean error, relative to the target white, of colours ``P`` (k, 3) shown in frustum as
    ``content`` (k, 3) and corrected by ``correction``, as :func:`background_error` models it."""
    SL, M = np.asarray(problem.SL, dtype=np.float64), np.asarray(problem.M, dtype=np.float64)
    b = np.zeros(3) if problem.black_level is None else np.asarray(problem.black_level, float)
    shown = correction.apply(np.clip((content - b) @ M.T, 0.0, None) @ SL.T + b)
    scale = white_scale(np.asarray(problem.target, dtype=np.float64), problem.white_patch)
    return float(np.mean(np.abs(shown - P) / scale))


def clipped_background(problem: QProblem, correction: PostCorrection) -> np.ndarray:
    """(n,) bool: the chart colours whose in-frustum drive (as :func:`background_error` forms
    it) has a channel below 0 through ``correction``."""
    M = np.asarray(problem.M, dtype=np.float64)
    P = np.asarray(problem.target, dtype=np.float64)
    b = np.zeros(3) if problem.black_level is None else np.asarray(problem.black_level, float)
    return np.any((correction.inverse(P) - b) @ M.T < 0, axis=1)


def skin_errors(problem: QProblem, corrections: Sequence[PostCorrection]) -> np.ndarray:
    """(m, k) ΔE2000 of the problem's skin samples corrected by each of ``corrections`` against
    the location's, through the sample camera's matrix (a ValueError without skin samples)."""
    lit, skin = problem.skin_predicted, problem.skin
    if lit is None or skin is None:
        raise ValueError("no skin samples")
    white = np.asarray(problem.target, dtype=np.float64)[problem.white_patch]
    corrected = np.stack([c.apply(lit) for c in corrections])
    return camera_delta_E_2000(
        skin.target, corrected, camera_to_xyz=sample_camera_to_xyz(), white=white
    )


def chart_error(problem: QProblem, corrected: np.ndarray) -> float:
    """Mean ΔE2000 (:func:`~ocio_vp.correction.linear.patch_errors`) over the fitted patches of
    the lit chart corrected to ``corrected`` (n, 3), against the target."""
    P, w = np.asarray(problem.target, dtype=np.float64), problem.fit_weights
    return float(np.mean(patch_errors(corrected, P, w, problem.white_patch)[0][w > 0]))


@dataclass(frozen=True)
class Judged:
    """What a post-correction is judged on against the default with skin first: the background
    error (relative to white), the LEDs in frame (p95 ΔE2000), the skin samples and the chart
    (mean ΔE2000 each)."""

    background: float
    leds: float
    skin: float
    chart: float

    def no_worse(self, default: Judged, chart: float) -> bool:
        """Background and LEDs no worse than ``default``'s, skin no worse either, and the
        chart's mean ΔE2000 at most ``chart``."""
        return all(
            _no_worse(mine, theirs)
            for mine, theirs in zip(
                (self.background, self.leds, self.skin, self.chart),
                (default.background, default.leds, default.skin, chart),
                strict=True,
            )
        )

    def words(self, default: Judged) -> str:
        return (
            f"background {100 * self.background:.3g} % of white (default "
            f"{100 * default.background:.3g} %), LEDs in frame p95 ΔE2000 {self.leds:.3g} "
            f"(default {default.leds:.3g})"
        )


def _no_worse(value: float, bound: float) -> bool:
    return not np.isfinite(bound) or value <= bound + _ROUNDING * abs(bound)


def judged(problem: QProblem, correction: PostCorrection) -> Judged:
    """:class:`Judged` of ``correction`` on ``problem`` (a ValueError without skin samples)."""
    skin = float(np.mean(skin_errors(problem, [correction])[0]))
    white = np.asarray(problem.target, dtype=np.float64)[problem.white_patch]
    return Judged(
        background=background_error(problem, correction),
        leds=in_frame_led_damage(correction, problem.SL, white, sample_camera_to_xyz()),
        skin=skin,
        chart=chart_error(problem, correction.apply(problem.predicted)),
    )


def skin_figures(
    problem: QProblem,
    correction: PostCorrection,
    priority: str,
    default: tuple[str, PostCorrection] | None = None,
) -> SkinFigures | None:
    """:class:`~ocio_vp.formats.skin.SkinFigures` of ``correction`` on ``problem`` (None
    without skin samples); ``default``: the default's (model, correction) with skin first."""
    lit, skin = problem.skin_predicted, problem.skin
    if lit is None or skin is None or skin.count == 0:
        return None
    X, P, w = problem.predicted, np.asarray(problem.target, dtype=np.float64), problem.fit_weights
    corrections = (correction, MatrixCorrection(fit_least_squares(X, P, w)))
    errors = skin_errors(problem, corrections)
    active = w > 0
    chart = patch_errors(np.stack([c.apply(X) for c in corrections]), P, w, problem.white_patch)
    band = np.asarray(skin.band)
    bands = tuple(
        SkinBand(
            name,
            int(np.sum(band == name)),
            *(float(np.mean(e[band == name])) for e in errors[:2]),
        )
        for name, _ in ITA_BANDS
        if np.any(band == name)
    )
    comparison = None
    if default is not None:
        mine, theirs = judged(problem, correction), judged(problem, default[1])
        comparison = SkinDefault(
            model=default[0],
            expected=theirs.skin,
            led_damage=mine.leds,
            led_damage_default=theirs.leds,
            background_outside=_background_outside(problem, correction),
            background_outside_default=_background_outside(problem, default[1]),
            background=_fraction(mine.background),
            background_default=_fraction(theirs.background),
        )
    return SkinFigures(
        priority=priority,
        source=skin.source,
        samples=skin.count,
        expected=float(np.mean(errors[0])),
        least_squares=float(np.mean(errors[1])),
        chart=float(np.mean(chart[0][0][active])),
        chart_least_squares=float(np.mean(chart[0][1][active])),
        bands=bands,
        default=comparison,
    )
