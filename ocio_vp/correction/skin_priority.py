"""``--priority skin``: the post-correction fitted with faces first.

The default (``auto``) already fits its root-polynomial candidate to the problem's skin samples
(:mod:`ocio_vp.correction.skin`) with a small weight and never takes a model that renders them
worse than least squares. With skin first the weight is :data:`PRIORITY_SKIN_WEIGHT`: the
bounded root-polynomial of degree 2 fitted to the chart and the skin samples, each skin sample
scaled by its luminance to the power -2/3 (CIE L* is about ``Y^(1/3)``: skin of every
lightness counts alike). Its fallback outside the chart's domain stays the chart's least
squares, so emitters, highlights and saturated colours are corrected as by the default. Where
the root-polynomial is not safe (it folds, flips or collapses a bright saturated input, or the
chart does not constrain its terms) a 3x3 is fitted to the same rows instead. The chart's
error is bounded (:data:`CHART_BUDGET` times least squares'); a target chart of rank below 3
(monochromatic light) has no colour to put first and is solved as the default solves it.
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.auto import bounded_candidate, q_auto
from ocio_vp.correction.linear import patch_errors, problem_arrays, target_rank
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.correction.skin import with_rows
from ocio_vp.errors import InputError
from ocio_vp.model.correction import MatrixCorrection

__all__ = ["CHART_BUDGET", "PRIORITY_SKIN_WEIGHT", "q_skin_priority"]

#: Weight of the skin samples with skin first (relative to the chart's energy). Chosen on the
#: training skin (half fitted, half judged) and the tuning cameras at 0.2 % and 1 % noise:
#: 0.5 rendered that skin 0.65-0.77x least squares with general reflectances ~0.94x; 1.0 gained
#: at 0.2 % noise and lost it at 1 % (docs/skin.md).
PRIORITY_SKIN_WEIGHT = 0.5
#: The chart's mean ΔE2000 after the fit may be at most this times least squares'.
CHART_BUDGET = 1.15
#: Least squares' chart ΔE2000 below this is rounding: the stage reproduces the light exactly.
EXACT = 1e-6


def q_skin_priority(problem: QProblem) -> QFit:
    """The skin-first post-correction (module docstring); an InputError without skin samples.

    Examples
    --------
    Without skin samples there is nothing to put first:

    >>> SL = np.eye(3)
    >>> problem = QProblem(SL=SL, SRL=np.ones((24, 3, 3)), beta=1.0, M=SL,
    ...                    w_avg=np.ones(3), target=np.ones((24, 3)))
    >>> q_skin_priority(problem)
    Traceback (most recent call last):
    ...
    ocio_vp.errors.InputError: --priority: skin: the chart gives no skin samples ...
    """
    if problem.skin is None or problem.skin.count == 0:
        raise InputError(
            "skin: the chart gives no skin samples (a ColorChecker 24, skin_patches named in "
            "the measurements file, or patches of skin colour are needed)",
            key="--priority",
        )
    X, P, w, white = problem_arrays(problem)
    rank, _ = target_rank(P, w, X)
    if rank < 3:
        fit = q_auto(problem)
        reason = f"skin priority not applied: the target chart has rank {rank}; {fit.reason}"
        return QFit(
            fit.correction, fit.model, fit.description, reason=reason, target_rank=rank,
            cross_validated_error=fit.cross_validated_error, details=fit.details,
        )  # fmt: skip
    active = w > 0
    Q_ls = fit_least_squares(X, P, w)
    chart_ls = float(np.mean(patch_errors(X @ Q_ls.T, P, w, white)[0][active]))
    if chart_ls < EXACT:
        fit = q_auto(problem)  # the stage reproduces the light: no colour, skin or other, to fix
        return QFit(
            fit.correction, fit.model, fit.description, reason=f"faces first: {fit.reason}",
            cross_validated_error=fit.cross_validated_error, target_rank=rank,
            details=fit.details,
        )  # fmt: skip
    candidate, why = bounded_candidate(problem, "root-polynomial", PRIORITY_SKIN_WEIGHT)
    if candidate is not None:
        fit = candidate
    else:
        rows = problem.skin_rows(PRIORITY_SKIN_WEIGHT)
        fit = QFit(
            MatrixCorrection(fit_least_squares(*with_rows(X, P, w, rows))),
            "skin-weighted",
            "3x3 least squares over the chart and the skin samples",
        )
    chart = float(np.mean(patch_errors(fit.correction.apply(X), P, w, white)[0][active]))
    if not chart <= CHART_BUDGET * chart_ls:
        return QFit(
            MatrixCorrection(Q_ls),
            "least-squares",
            "full 3x3 least squares (eq. 5)",
            reason=(
                f"faces first, but the skin fit's chart error {chart:.3g} is above "
                f"{CHART_BUDGET:g}x least squares' {chart_ls:.3g}: least squares kept"
            ),
            target_rank=rank,
        )
    notes = [] if why is None else [why]
    reason = (
        f"faces first: {fit.description} (skin weight {PRIORITY_SKIN_WEIGHT:g}); chart mean "
        f"ΔE2000 {chart:.3g} against least squares' {chart_ls:.3g} (at most {CHART_BUDGET:g}x)"
    )
    return QFit(
        fit.correction,
        fit.model,
        fit.description,
        reason="; ".join([reason, *notes]),
        cross_validated_error=fit.cross_validated_error,
        target_rank=rank,
        details={**fit.details, "skin_weight": PRIORITY_SKIN_WEIGHT, "chart_budget": CHART_BUDGET},
    )
