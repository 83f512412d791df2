"""The linear post-correction models (identity, diagonal, regularised, least squares,
white-preserving, reduced-rank ``rank-r``), each fitting ``Q x_j ~ p_j`` (eq. 5) with patch
weights ``w_j`` (0 = excluded), their leave-one-patch-out predictions in closed form (rank-one
downdates of the normal equations) and ``auto``'s rule (:func:`choose_model`). The models and
the rule are described in docs/stability.md.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ocio_vp.correction.perceptual import patch_delta_e
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.metrics import white_scale
from ocio_vp.model.correction import MatrixCorrection
from ocio_vp.model.expansion import ROOT_POLYNOMIAL_TERMS, root_polynomial_expansion

__all__ = [
    "AUTO_LADDER",
    "AUTO_LADDER_NARROW",
    "AUTO_SE_FACTOR",
    "AUTO_TIE",
    "LINE_SPECTRUM_TOLERANCE",
    "LOO_KERNELS",
    "MODEL_KERNELS",
    "NARROW_TARGET",
    "RANK_RELATIVE_TOLERANCE",
    "REGULARISATION_GRID",
    "ROOT_POLYNOMIAL_DEGREES",
    "choose_model",
    "choose_shrinkage",
    "colour_spread",
    "fit_least_squares",
    "fit_model",
    "is_narrow",
    "ladder_predictions",
    "loo_predictions",
    "loo_root_polynomial",
    "patch_errors",
    "problem_arrays",
    "q_diagonal",
    "q_identity",
    "q_regularised",
    "q_white_preserving",
    "target_rank",
]

#: ``auto`` replaces least squares by another model only when that model's mean leave-one-out
#: ΔE2000 is lower by more than this many standard errors of the paired per-patch differences
#: (docs/accuracy.md measures the choice on colours off the chart).
AUTO_SE_FACTOR = 1.0
#: Mean leave-one-out ΔE2000 differences up to this are ties (rounding, not colour), which go to
#: the simplest model.
AUTO_TIE = 1e-6

#: A colour direction of the target chart carrying less than this fraction of its largest
#: singular value, relative to the lit chart's (:func:`target_rank`), is treated as absent.
RANK_RELATIVE_TOLERANCE = 1e-3
#: A target chart whose *second* relative singular value is below this has one colour: a line
#: spectrum whose other directions carry only measurement noise (docs/stability.md).
LINE_SPECTRUM_TOLERANCE = 0.2

#: A target chart whose colours spread less than this fraction of the lit chart's
#: (:func:`colour_spread`: a line-spectrum light the wall cannot reproduce) is a *narrow*
#: target: ``auto`` then also weighs reduced-rank models (rank-1, rank-2) against the others.
NARROW_TARGET = 0.78

#: Shrinkage strengths tried by ``regularised``, relative to ``trace(X^T W X) / 3``.
REGULARISATION_GRID = (0.0, *np.logspace(-4, 2, 13).tolist())

#: ``auto``'s candidates, simplest first. ``white-preserving`` is not one: pinning Q to a single
#: patch makes Q and N inherit that patch's noise (docs/stability.md), so it is never "simpler".
#: ``root-polynomial`` is degree 2 (6 terms per channel); degree 3 (13 terms) over-fits 24
#: patches (docs/accuracy.md).
AUTO_LADDER = ("identity", "diagonal", "regularised", "least-squares", "root-polynomial")
#: The ladder for a narrow target (:data:`NARROW_TARGET`).
AUTO_LADDER_NARROW = (
    "identity",
    "diagonal",
    "rank-1",
    "rank-2",
    "regularised",
    "least-squares",
    "root-polynomial",
)
#: Root-polynomial models by registry name: their degree.
ROOT_POLYNOMIAL_DEGREES = {"root-polynomial": 2, "root-polynomial-3": 3}

Kernel = Callable[[np.ndarray, np.ndarray, np.ndarray, int], np.ndarray]


# ---------------------------------------------------------------------------------------------
# Normal equations, whole and with one patch removed.


def normal_equations(X: np.ndarray, P: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, ...]:
    """``G = X^T W X`` (d, d) and ``B = X^T W P`` (d, k)."""
    return np.einsum("j,jc,jd->cd", w, X, X), np.einsum("j,jc,jd->cd", w, X, P)


def weighted_outer(weight: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(m, d, k) ``weight a b^T`` per row: a patch's part of the normal equations."""
    return weight[:, None, None] * a[:, :, None] * b[:, None, :]


def _downdated(X: np.ndarray, P: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, ...]:
    """(n, d, d) and (n, d, k): the normal equations without patch j, for every j."""
    G, B = normal_equations(X, P, w)
    return G[None] - weighted_outer(w, X, X), B[None] - weighted_outer(w, X, P)


def _solve(G: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``G^-1 B`` for (batches of) symmetric G; the pseudo-inverse where G is singular."""
    scale = np.max(np.abs(G), axis=(-2, -1), keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    Gs = G / scale
    singular = np.linalg.cond(Gs) > 1e12
    if not np.any(singular):
        return np.linalg.solve(Gs, B / scale)
    return np.linalg.pinv(Gs, hermitian=True) @ (B / scale)


def _loo(Qt: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(n, 3) held-out predictions ``Q_(-j) x_j`` from (n, d, 3) transposed fits."""
    return np.einsum("jc,jcd->jd", X, Qt)


# ---------------------------------------------------------------------------------------------
# Kernels: (X (n,3) lit chart x_j, P (n,3) target p_j, w (n,) weights, white index) -> Q (3,3).


def _fit_identity(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    return np.eye(3)


def _gains(num: np.ndarray, den: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """Per-channel gains ``num / den``; 1 where a channel carries (next to) no signal."""
    safe = den > 1e-12 * peak
    return np.where(safe, num / np.where(safe, den, 1.0), 1.0)


def _diagonal_terms(X: np.ndarray, P: np.ndarray, w: np.ndarray):
    num = np.einsum("j,jc,jc->c", w, X, P)
    den = np.einsum("j,jc,jc->c", w, X, X)
    return num, den, np.max(den) if den.size else 0.0


def _fit_diagonal(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """Per-channel gains by least squares over every fitted patch (a white balance that no
    single noisy patch sets); a channel with no signal keeps gain 1."""
    num, den, peak = _diagonal_terms(X, P, w)
    return np.diag(_gains(num, den, peak))


def _loo_diagonal_gains(X: np.ndarray, P: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(n, 3) the diagonal model's gains fitted without patch j."""
    num, den, peak = _diagonal_terms(X, P, w)
    return _gains(num - w[:, None] * X * P, den - w[:, None] * X * X, peak)


def _fit_white_preserving(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """Least squares subject to ``Q x_w = p_w``: each row q_c = q0_c + Z y_c, Z spans x_w's null."""
    x_w = X[white]
    norm = float(x_w @ x_w)
    if not w[white] > 0 or not norm > 0:
        return fit_least_squares(X, P, w)
    Z, Q0 = _white_basis(X[white], P[white])
    sw = np.sqrt(w)[:, None]
    Y, *_ = np.linalg.lstsq((X @ Z) * sw, (P - X @ Q0.T) * sw, rcond=None)  # (2, 3)
    return Q0 + (Z @ Y).T


def _white_basis(x_w: np.ndarray, p_w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Z (3, 2) orthonormal basis of {q : x_w . q = 0}, and Q0 with ``Q0 x_w = p_w``."""
    _, _, vt = np.linalg.svd(x_w[None, :])
    return vt[1:].T, np.outer(p_w, x_w) / float(x_w @ x_w)


def _ridge(X: np.ndarray, P: np.ndarray, w: np.ndarray, alpha: float) -> np.ndarray:
    """Least squares + ``alpha tr(X^T W X)/3 ||Q - D||_F^2``, D the diagonal fit."""
    G, B = normal_equations(X, P, w)
    D = _fit_diagonal(X, P, w, 0)
    lam = alpha * np.trace(G) / 3.0
    return _solve(G + lam * np.eye(3), B + lam * D).T


def _loo_ridge(X: np.ndarray, P: np.ndarray, w: np.ndarray, alphas: np.ndarray) -> np.ndarray:
    """(g, n, 3) held-out predictions of the ridge model for each strength in ``alphas``."""
    Gj, Bj = _downdated(X, P, w)
    D = _loo_diagonal_gains(X, P, w)[:, :, None] * np.eye(3)  # (n, 3, 3)
    lam = (
        np.asarray(alphas)[:, None, None, None]
        * (np.trace(Gj, axis1=1, axis2=2) / 3.0)[None, :, None, None]
    )
    Qt = _solve(Gj[None] + lam * np.eye(3), Bj[None] + lam * D[None])
    return np.einsum("jc,gjcd->gjd", X, Qt)


def patch_errors(held: np.ndarray, P: np.ndarray, w: np.ndarray, white: int):
    """(..., n) per-patch error of predictions (n, 3) or a stack of them (..., n, 3), and its
    unit: ΔE2000 through the default camera matrix, or, where no fitted patch has a luminance
    to normalise by (a target the camera matrix sees as black), the mean absolute error per
    channel relative to white. A stack goes through colour-science in one call."""
    try:
        return patch_delta_e(held, P, white_patch=white, weights=w), "ΔE2000"
    except ValueError:
        relative = np.abs(held - P) / white_scale(P, white, w)
        return relative.mean(axis=-1), "error relative to white"


def choose_shrinkage(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> float:
    """The grid strength with the lowest mean leave-one-out ΔE2000 (ties: more shrinkage)."""
    active = w > 0
    if not np.trace(normal_equations(X, P, w)[0]) > 0 or np.count_nonzero(active) < 2:
        return float("inf")
    grid = np.asarray(REGULARISATION_GRID)
    held = _loo_ridge(X, P, w, grid)  # (g, n, 3): every strength's held-out predictions
    scores = np.mean(patch_errors(held, P, w, white)[0][:, active], axis=1)
    scores = np.where(np.isfinite(scores), scores, np.inf)
    return float(grid[np.flatnonzero(scores <= np.min(scores) + AUTO_TIE)[-1]])


def _fit_regularised(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int, alpha: float | None = None
) -> np.ndarray:
    """The ridge fit at ``alpha`` (:func:`choose_shrinkage`'s when None); the diagonal fit
    where no strength is defined."""
    alpha = choose_shrinkage(X, P, w, white) if alpha is None else alpha
    return _ridge(X, P, w, alpha) if np.isfinite(alpha) else _fit_diagonal(X, P, w, white)


def _fit_reduced_rank(X: np.ndarray, P: np.ndarray, w: np.ndarray, rank: int) -> np.ndarray:
    """Reduced-rank regression: project the least-squares fit onto its top ``rank`` outputs."""
    Q = fit_least_squares(X, P, w)
    fitted = (X @ Q.T) * np.sqrt(w)[:, None]
    _, _, vt = np.linalg.svd(fitted, full_matrices=False)
    V = vt[:rank].T
    return V @ V.T @ Q


MODEL_KERNELS: dict[str, Kernel] = {
    "identity": _fit_identity,
    "diagonal": _fit_diagonal,
    "white-preserving": _fit_white_preserving,
    "regularised": _fit_regularised,
    "least-squares": fit_least_squares,
}


# ---------------------------------------------------------------------------------------------
# Closed-form leave-one-out: (X, P, w, white) -> (n, 3) held-out predictions Q_(-j) x_j. A
# patch with weight 0 gets the full fit's prediction (which is its held-out prediction).


def _loo_identity(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    return X.copy()


def _loo_diagonal(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    return X * _loo_diagonal_gains(X, P, w)


def _loo_least_squares(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    return _loo(_solve(*_downdated(X, P, w)), X)


def _loo_regularised(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int, alpha: float | None = None
) -> np.ndarray:
    """Held out at the strength ``alpha`` chosen on all patches (:func:`choose_shrinkage`'s
    when None; the choice itself is not re-made)."""
    alpha = choose_shrinkage(X, P, w, white) if alpha is None else alpha
    if not np.isfinite(alpha):
        return _loo_diagonal(X, P, w, white)
    return _loo_ridge(X, P, w, np.array([alpha]))[0]


def _loo_white_preserving(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """Each patch but the white from the constrained fit without it; the white patch from
    the least-squares fit without it (what the kernel does with the white excluded)."""
    held = _loo_least_squares(X, P, w, white)
    if not (w[white] > 0 and float(X[white] @ X[white]) > 0):
        return held
    Z, Q0 = _white_basis(X[white], P[white])
    A, B = X @ Z, P - X @ Q0.T
    Gj, Bj = _downdated(A, B, w)
    Y = _solve(Gj, Bj)  # (n, 2, 3)
    constrained = X @ Q0.T + np.einsum("jc,jcd->jd", A, Y)
    keep = np.arange(len(X)) != white
    held[keep] = constrained[keep]
    return held


def _loo_reduced_rank(X: np.ndarray, P: np.ndarray, w: np.ndarray, rank: int) -> np.ndarray:
    Gj, Bj = _downdated(X, P, w)
    Qt = _solve(Gj, Bj)  # (n, 3, 3) = Q_(-j)^T
    S = np.einsum("jac,jcd,jdb->jab", np.swapaxes(Qt, 1, 2), Gj, Qt)  # fitted^T W fitted
    _, vectors = np.linalg.eigh(S)
    V = vectors[:, :, ::-1][:, :, :rank]  # top ``rank`` output directions
    projector = V @ np.swapaxes(V, 1, 2)
    return np.einsum("jab,jb->ja", projector, _loo(Qt, X))


LOO_KERNELS: dict[str, Kernel] = {
    "identity": _loo_identity,
    "diagonal": _loo_diagonal,
    "white-preserving": _loo_white_preserving,
    "regularised": _loo_regularised,
    "least-squares": _loo_least_squares,
}


def loo_root_polynomial(X: np.ndarray, P: np.ndarray, w: np.ndarray, degree: int) -> np.ndarray:
    """Held-out predictions of the weighted root-polynomial fit (Finlayson et al. 2015).

    Linear in its parameters, so the hat-matrix identity holds: patch j's held-out prediction
    is ``p_j - r_j / (1 - h_jj)`` (r_j the full fit's residual, h_jj its leverage), from one
    SVD of the weighted expansion (better conditioned than the normal equations). A patch
    that alone decides a term (h_jj ~ 1) falls back to the normal equations.
    """
    E = root_polynomial_expansion(np.asarray(X, dtype=np.float64), degree).reshape(len(X), -1)
    sw = np.sqrt(w)[:, None]
    U, s, vt = np.linalg.svd(E * sw, full_matrices=False)
    keep = s > 1e-13 * s[0]
    U, s, vt = U[:, keep], s[keep], vt[keep]
    CT = vt.T @ ((U.T @ (P * sw)) / s[:, None])  # (terms, 3) the full weighted fit
    fitted = E @ CT
    leverage = np.sum(U * U, axis=1)
    held = np.where(w[:, None] > 0, P - (P - fitted) / (1 - leverage)[:, None], fitted)
    alone = (w > 0) & (1 - leverage < 1e-8)
    if np.any(alone):
        held[alone] = _loo(_solve(*_downdated(E, P, w)), E)[alone]
    return held


def loo_predictions(name: str, X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int):
    """(n, 3) leave-one-patch-out predictions of the model ``name`` (closed form)."""
    if name.startswith("rank-"):
        return _loo_reduced_rank(X, P, w, int(name.removeprefix("rank-")))
    if name in ROOT_POLYNOMIAL_DEGREES:
        return loo_root_polynomial(X, P, w, ROOT_POLYNOMIAL_DEGREES[name])
    return LOO_KERNELS[name](X, P, w, white)


def ladder_predictions(ladder, X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int):
    """``({name: (n, 3) held-out predictions}, alpha)`` for the models of ``ladder``.

    ``regularised`` is held out at the shrinkage ``alpha`` chosen on all patches (chosen once);
    a root-polynomial model is left out when its terms leave no patch to spare.
    """
    alpha = choose_shrinkage(X, P, w, white) if "regularised" in ladder else float("inf")
    fitted = int(np.count_nonzero(w > 0))
    held = {}
    for name in ladder:
        if name in ROOT_POLYNOMIAL_DEGREES:
            if fitted <= ROOT_POLYNOMIAL_TERMS[ROOT_POLYNOMIAL_DEGREES[name]]:
                continue
        if name == "regularised":
            held[name] = _loo_regularised(X, P, w, white, alpha)
        else:
            held[name] = loo_predictions(name, X, P, w, white)
    return held, alpha


def fit_model(name: str, X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int, alpha=None):
    """The 3x3 Q of a linear model of :data:`AUTO_LADDER_NARROW` (``alpha``: the shrinkage of
    ``regularised``, chosen by :func:`choose_shrinkage` when None)."""
    if name.startswith("rank-"):
        return _fit_reduced_rank(X, P, w, int(name.removeprefix("rank-")))
    if name == "regularised":
        return _fit_regularised(X, P, w, white, alpha)
    return MODEL_KERNELS[name](X, P, w, white)


def colour_spread(chart: np.ndarray) -> float:
    """How far a chart's colours spread beyond one direction: the second singular value over
    the first, of the patches scaled to unit length (so no single bright patch dominates)."""
    size = np.linalg.norm(chart, axis=1, keepdims=True)
    s = np.linalg.svd(chart / np.where(size > 0, size, 1.0), compute_uv=False)
    return float(s[1] / s[0]) if s[0] > 0 else 0.0


def is_narrow(X: np.ndarray, P: np.ndarray, w: np.ndarray) -> bool:
    """Whether the target's colours spread much less than the lit chart's (a line-spectrum
    light the wall cannot reproduce: :data:`NARROW_TARGET`)."""
    active = np.asarray(w) > 0
    return bool(colour_spread(P[active]) < NARROW_TARGET * colour_spread(X[active]))


def target_rank(
    P: np.ndarray, w: np.ndarray, X: np.ndarray | None = None
) -> tuple[int, np.ndarray]:
    """Numerical rank of the (weighted) target chart and its relative singular values.

    With the lit chart ``X``, each relative singular value is the target's over the lit chart's
    (``(s_P[i] / s_P[0]) / (s_X[i] / s_X[0])``, at most 1), so that only a light with much less
    colour than the wall counts as rank-deficient; a second one below
    :data:`LINE_SPECTRUM_TOLERANCE` makes the rank 1 (docs/stability.md).

    Raises
    ------
    InputError
        When the fitted patches of the target chart are all black.
    """
    sw = np.sqrt(w)[:, None]
    s = np.linalg.svd(P * sw, compute_uv=False)
    if not s[0] > 0:
        raise InputError("the target chart is black on every fitted patch", key="target_chart")
    relative = s / s[0]
    if X is not None:
        t = np.linalg.svd(X * sw, compute_uv=False)
        if t[0] > 0:
            lit = t / t[0]
            relative = np.minimum(relative / np.where(lit > 0, lit, np.inf), 1.0)
            relative[0] = 1.0
    if relative[1] < LINE_SPECTRUM_TOLERANCE:
        return 1, relative
    return int(np.sum(relative >= RANK_RELATIVE_TOLERANCE)), relative


def problem_arrays(problem: QProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(X, P, w, white)`` of a problem; an InputError with fewer than 3 fitted patches."""
    X = problem.predicted
    P = np.asarray(problem.target, dtype=np.float64)
    w = problem.fit_weights
    if np.count_nonzero(w > 0) < 3:
        raise InputError(
            f"only {np.count_nonzero(w > 0)} chart patches are usable (not clipped): need at "
            "least 3 to fit Q",
            key="target_chart",
        )
    return X, P, w, int(problem.white_patch)


def _method(name: str, description: str) -> Callable[[QProblem], QFit]:
    kernel = MODEL_KERNELS[name]

    def solve(problem: QProblem) -> QFit:
        X, P, w, white = problem_arrays(problem)
        return QFit(MatrixCorrection(kernel(X, P, w, white)), name, description)

    solve.__name__ = "q_" + name.replace("-", "_")
    solve.__doc__ = f"Q by the {name!r} model: {description}."
    return solve


q_identity = _method("identity", "Q = I, no post-correction")
q_diagonal = _method("diagonal", "white balance only: per-channel gains fitted to every patch")
q_white_preserving = _method(
    "white-preserving",
    "the white patch maps exactly, the other 6 degrees of freedom by least squares",
)


def q_regularised(problem: QProblem) -> QFit:
    """Least squares shrunk toward the white-balance (diagonal) Q; strength by LOO ΔE2000."""
    X, P, w, white = problem_arrays(problem)
    alpha = choose_shrinkage(X, P, w, white)
    return QFit(
        MatrixCorrection(_fit_regularised(X, P, w, white, alpha)),
        "regularised",
        "least squares + alpha*trace(X^T W X)/3*||Q - D||^2, D = white balance, alpha with the "
        "lowest leave-one-patch-out ΔE2000",
        details={"shrinkage": alpha},
    )


def choose_model(
    scores: dict[str, np.ndarray],
    factor: float = AUTO_SE_FACTOR,
    reference: str = "least-squares",
):
    """``auto``'s rule on per-patch leave-one-out ΔE (same patches; ladder order, simplest first).

    The ``reference`` (the paper's least squares) is kept unless another model is *clearly*
    better: its mean is lower by more than ``factor`` standard errors of the paired per-patch
    differences. Among the reference and the clearly better models the lowest mean wins;
    models within :data:`AUTO_TIE` of it are tied and the simplest of them is taken (a chart
    the stage reproduces exactly gives ``identity``).

    Returns ``(chosen, table)``; ``table[name]`` has the model's ``mean``, its ``difference``
    from the reference's mean and that difference's ``standard_error``.

    Examples
    --------
    A simpler model 0.05 better on average, but with paired differences spreading by 0.5, is
    not clearly better; 0.5 better with the same spread is:

    >>> d = np.array([0.45, -0.55] * 12)
    >>> choose_model({"simple": 1.0 + d, "least-squares": np.ones(24)})[0]
    'least-squares'
    >>> choose_model({"simple": 0.55 + d, "least-squares": np.ones(24)})[0]
    'simple'
    """
    means = {name: float(np.mean(s)) for name, s in scores.items()}
    base = scores[reference]
    table = {}
    for name, s in scores.items():
        difference = s - base
        se = float(np.std(difference, ddof=1) / np.sqrt(len(s))) if len(s) > 1 else 0.0
        table[name] = {
            "mean": means[name],
            "difference": means[name] - means[reference],
            "standard_error": se,
        }
    eligible = [
        name
        for name, row in table.items()
        if name == reference
        or abs(row["difference"]) <= AUTO_TIE
        or row["difference"] < -factor * row["standard_error"]
    ]
    lowest = min(means[name] for name in eligible)
    chosen = next(name for name in eligible if means[name] <= lowest + AUTO_TIE)
    return chosen, table


def _loo_cv_error(name: str, X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int):
    """(3,) leave-one-patch-out chart error per channel, relative to white (the old function)."""
    from ocio_vp.metrics import error_relative_to_white

    return error_relative_to_white(loo_predictions(name, X, P, w, white), P, white, w)


#: Names served for one more release (ocio_vp.deprecation).
DEPRECATED = {
    "loo_cv_error": (
        "ocio_vp.metrics.error_relative_to_white(loo_predictions(name, X, P, w, white), P, "
        "white, w)",
        lambda: _loo_cv_error,
    )
}
__getattr__ = deprecated_names(__name__, DEPRECATED)
