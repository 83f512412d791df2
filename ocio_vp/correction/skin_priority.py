"""``--priority skin``: a 3x3 post-correction fitted to the chart and the skin samples together.

Faces first: the paper's eq. 5 over the chart, plus the problem's skin samples
(:mod:`ocio_vp.correction.skin`) with a weight, each skin sample scaled by its luminance to the
power -2/3 (CIE L* is about ``Y^(1/3)``, so an error in a dark face weighs what the same ΔE in a
light one does: skin of every lightness counts). The weight is the largest of
:data:`SKIN_WEIGHTS` whose chart error stays within :data:`CHART_BUDGET` times least squares'
(general reflectances are allowed a bounded cost, never an unbounded one). The solve's
``details`` say what skin and the chart cost against least squares; the solve compares it with
the default (``auto``) as well (:mod:`ocio_vp.pipeline`).
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.linear import patch_errors, problem_arrays
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.correction.skin import skin_delta_e
from ocio_vp.errors import InputError
from ocio_vp.model.correction import MatrixCorrection

__all__ = ["CHART_BUDGET", "SKIN_WEIGHTS", "fit_skin_weighted", "q_skin_priority"]

#: Weights of the skin samples against the chart (their scaled energy relative to the chart's),
#: largest first; the first within :data:`CHART_BUDGET` is taken.
SKIN_WEIGHTS = (4.0, 2.0, 1.0, 0.5, 0.25)
#: The chart's mean ΔE2000 after the skin-weighted fit may be at most this times least squares'.
CHART_BUDGET = 1.15


def fit_skin_weighted(
    X: np.ndarray,
    P: np.ndarray,
    w: np.ndarray,
    Xs: np.ndarray,
    Ps: np.ndarray,
    Ys: np.ndarray,
    weight: float,
) -> np.ndarray:
    """argmin_Q Σ_j w_j ||Q x_j - p_j||² + λ Σ_s y_s^(-4/3) ||Q x_s - p_s||² (skin samples s).

    ``Ys`` (k,) is each skin sample's luminance relative to white; λ makes the skin rows'
    scaled target energy ``weight`` times the chart's.
    """
    scale = np.clip(Ys, 1e-3, None) ** (-2.0 / 3.0)
    chart_energy = float(np.sum(w[:, None] * P**2))
    skin_energy = float(np.sum((scale[:, None] * Ps) ** 2))
    lam = weight * chart_energy / skin_energy if skin_energy > 0 else 0.0
    rows_x = np.vstack([X, Xs])
    rows_p = np.vstack([P, Ps])
    row_w = np.concatenate([w, lam * scale**2])
    return fit_least_squares(rows_x, rows_p, row_w)


def q_skin_priority(problem: QProblem) -> QFit:
    """A 3x3 Q fitted to chart and skin (module docstring); an InputError without skin samples.

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
    Xs, Ps = problem.skin_predicted, problem.skin.target
    from ocio_vp.correction.perceptual import default_camera_to_xyz

    camera = default_camera_to_xyz()
    Ys = (Ps @ camera[1]) / float(P[white] @ camera[1])
    Q_ls = fit_least_squares(X, P, w)
    active = w > 0
    chart_ls = float(np.mean(patch_errors(X @ Q_ls.T, P, w, white)[0][active]))
    chosen, Q, chart = 0.0, Q_ls, chart_ls
    for weight in SKIN_WEIGHTS:
        Q_w = fit_skin_weighted(X, P, w, Xs, Ps, Ys, weight)
        error = float(np.mean(patch_errors(X @ Q_w.T, P, w, white)[0][active]))
        if np.all(np.isfinite(Q_w)) and error <= CHART_BUDGET * chart_ls:
            chosen, Q, chart = weight, Q_w, error
            break
    skin = skin_delta_e(np.stack([Xs @ Q.T, Xs @ Q_ls.T]), Ps, P[white], camera)
    details = {
        "skin_weight": chosen,
        "chart_budget": CHART_BUDGET,
        "chart_delta_e": chart,
        "chart_delta_e_least_squares": chart_ls,
        "skin_delta_e": float(np.mean(skin[0])),
        "skin_delta_e_least_squares": float(np.mean(skin[1])),
    }
    reason = (
        f"faces first: least squares over the chart and {problem.skin.count} skin samples "
        f"(weight {chosen:g}); skin mean ΔE2000 {np.mean(skin[0]):.3g} against least squares' "
        f"{np.mean(skin[1]):.3g}, chart {chart:.3g} against {chart_ls:.3g} (at most "
        f"{CHART_BUDGET:g}x)"
        if chosen
        else "faces first, but every skin weight costs the chart more than "
        f"{CHART_BUDGET:g}x least squares: least squares kept"
    )
    return QFit(
        MatrixCorrection(Q),
        "skin-priority" if chosen else "least-squares",
        "3x3 least squares over chart and skin (faces first)" if chosen else "least squares",
        reason=reason,
        details=details,
    )
