"""Post-correction models beyond the paper's full least squares, and ``auto`` that picks one.

Every model fits ``Q`` so that ``Q x_j ~ p_j`` (eq. 5 of the paper; ``x_j`` is the lit chart
under M, eq. 3) with patch weights ``w_j`` (0 = excluded, e.g. clipped):

==================  ====  ==================================================================
model               dof   what it fits
==================  ====  ==================================================================
identity            0     ``Q = I``: the stage's LEDs already light the scene like the real one
diagonal            3     white balance: per-channel gains, least squares over all patches
regularised         3..9  least squares shrunk toward the diagonal model: the most shrinkage
                          whose LOO error is within half auto's tolerance of the best strength
least-squares       9     the paper's eq. 5
white-preserving    6     full Q with ``Q x_w = p_w`` exactly, the rest least squares (not in
                          auto's ladder: one patch's noise goes straight into Q and N)
rank-r              5, 8  reduced-rank least squares, for a (nearly) monochromatic target
==================  ====  ==================================================================

``auto`` measures every model's leave-one-patch-out cross-validated error and keeps the
simplest whose error is within ``best * (1 + AUTO_TOLERANCE_RELATIVE) + AUTO_TOLERANCE_ABSOLUTE``
of the best (a model just inside the limit is blended with the next one, :func:`soft_choice`,
so that Q moves continuously with the data); when the target chart has numerical rank below 3
it fits a reduced-rank Q instead (N is then not solved). See docs/stability.md for the reasoning and the measured figures.

The errors are the paper's (Fig. 11): mean absolute error per channel relative to the target
white patch, averaged over channels (:func:`ocio_vp.calibration.diagnostics.error_relative_to_white`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.errors import InputError
from ocio_vp.metrics import error_relative_to_white, white_scale

__all__ = [
    "AUTO_LADDER",
    "AUTO_TOLERANCE_ABSOLUTE",
    "AUTO_TOLERANCE_RELATIVE",
    "BLEND_BAND",
    "MODEL_KERNELS",
    "RANK_RELATIVE_TOLERANCE",
    "REGULARISATION_GRID",
    "fit_least_squares",
    "loo_cv_error",
    "q_auto",
    "q_diagonal",
    "q_identity",
    "q_regularised",
    "q_white_preserving",
    "soft_choice",
    "target_rank",
]

#: ``auto`` keeps the simplest model whose cross-validated error is at most
#: ``best * (1 + relative) + absolute``: 5 % of the best error plus 0.2 % of the target white,
#: well below a visible difference on a chart (docs/stability.md), above LOO's own jitter.
AUTO_TOLERANCE_RELATIVE = 0.05
AUTO_TOLERANCE_ABSOLUTE = 0.002

#: A colour direction of the target chart carrying less than this fraction of its largest
#: singular value is treated as absent (low-pressure sodium: ~1e-16; high-pressure sodium: 0.04).
RANK_RELATIVE_TOLERANCE = 0.01

#: ``regularised`` takes the strongest shrinkage whose inner leave-one-out error is within
#: ``best * (1 + relative) + absolute`` of the best strength's: half ``auto``'s tolerance, so the
#: shrunk model usually stays within ``auto``'s tolerance when cross-validated from outside.
SHRINKAGE_TOLERANCE = (AUTO_TOLERANCE_RELATIVE / 2, AUTO_TOLERANCE_ABSOLUTE / 2)

#: Shrinkage strengths tried by ``regularised``, relative to ``trace(X^T W X) / 3``.
REGULARISATION_GRID = (0.0, *np.logspace(-4, 2, 7).tolist())

#: Width of the band under ``auto``'s limit, as a fraction of it, where a model shares its weight
#: with the models after it (:func:`soft_choice`): 1 at the band's floor, 0 at the limit.
BLEND_BAND = 0.05

#: ``auto``'s candidates, simplest first. ``white-preserving`` is not one: pinning Q to a single
#: patch makes Q and N inherit that patch's noise (docs/stability.md), so it is never "simpler".
AUTO_LADDER = ("identity", "diagonal", "regularised", "least-squares")

Kernel = Callable[[np.ndarray, np.ndarray, np.ndarray, int], np.ndarray]


# ---------------------------------------------------------------------------------------------
# Kernels: (X (n,3) lit chart x_j, P (n,3) target p_j, w (n,) weights, white index) -> Q (3,3).


def fit_least_squares(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int = 0) -> np.ndarray:
    """argmin_Q sum_j w_j ||Q x_j - p_j||^2 (eq. 5), via an SVD least-squares solve."""
    sw = np.sqrt(w)[:, None]
    QT, *_ = np.linalg.lstsq(X * sw, P * sw, rcond=None)  # rows: x_j^T Q^T = p_j^T
    return QT.T


def _fit_identity(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    return np.eye(3)


def _fit_diagonal(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """Per-channel gains by least squares over every fitted patch (a white balance that no
    single noisy patch sets); a channel with no signal keeps gain 1."""
    num = np.einsum("j,jc,jc->c", w, X, P)
    den = np.einsum("j,jc,jc->c", w, X, X)
    safe = den > 0
    return np.diag(np.where(safe, num / np.where(safe, den, 1.0), 1.0))


def _fit_white_preserving(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """Least squares subject to ``Q x_w = p_w``: each row q_c = q0_c + Z y_c, Z spans x_w's null."""
    x_w = X[white]
    norm = float(x_w @ x_w)
    if not w[white] > 0 or not norm > 0:
        return fit_least_squares(X, P, w)
    _, _, vt = np.linalg.svd(x_w[None, :])
    Z = vt[1:].T  # (3, 2) orthonormal basis of {q : x_w . q = 0}
    Q0 = np.outer(P[white], x_w) / norm  # rows q0_c with x_w . q0_c = p_w,c
    sw = np.sqrt(w)[:, None]
    A = (X @ Z) * sw
    B = (P - X @ Q0.T) * sw
    Y, *_ = np.linalg.lstsq(A, B, rcond=None)  # (2, 3)
    return Q0 + (Z @ Y).T


def _ridge_batch(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, D: np.ndarray, lam: np.ndarray
) -> np.ndarray:
    """Q minimising sum w_j ||Q x_j - p_j||^2 + lam ||Q - D||_F^2, batched over leading axes of
    ``w`` (..., n), ``D`` (..., 3, 3) and ``lam`` (...)."""
    G = np.einsum("...j,jc,jd->...cd", w, X, X) + lam[..., None, None] * np.eye(3)
    B = np.einsum("...j,jc,jd->...cd", w, X, P) + lam[..., None, None] * np.swapaxes(D, -1, -2)
    return np.swapaxes(np.linalg.pinv(G) @ B, -1, -2)


def _choose_shrinkage(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> float:
    """The grid strength with the lowest leave-one-out error (ties go to more shrinkage)."""
    scale = float(np.einsum("j,jc,jc->", w, X, X)) / 3.0
    active = np.flatnonzero(w > 0)
    if not scale > 0 or active.size < 2:
        return float("inf")
    grid = np.asarray(REGULARISATION_GRID)
    w_loo = np.repeat(w[None, :], active.size, axis=0)
    w_loo[np.arange(active.size), active] = 0.0
    D = np.stack([_fit_diagonal(X, P, wj, white) for wj in w_loo])  # (k, 3, 3)
    Q = _ridge_batch(X, P, w_loo[None], D[None], grid[:, None] * scale)  # (g, k, 3, 3)
    held = np.einsum("gkcd,kd->gkc", Q, X[active])
    denom = white_scale(P, white, w)
    errors = np.mean(np.abs(held - P[active]) / denom, axis=(1, 2))
    # Like Breiman's one-standard-error rule: the most shrinkage whose error is within
    # SHRINKAGE_TOLERANCE of the best, because shrinkage toward D is what keeps N stable.
    limit = errors.min() * (1 + SHRINKAGE_TOLERANCE[0]) + SHRINKAGE_TOLERANCE[1]
    return float(grid[np.flatnonzero(errors <= limit)[-1]])


def _fit_regularised(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    D = _fit_diagonal(X, P, w, white)
    alpha = _choose_shrinkage(X, P, w, white)
    if not np.isfinite(alpha):
        return D
    scale = float(np.einsum("j,jc,jc->", w, X, X)) / 3.0
    sw = np.sqrt(w)[:, None]
    root = np.sqrt(alpha * scale)
    A = np.vstack([X * sw, root * np.eye(3)])
    B = np.vstack([P * sw, root * D.T])
    QT, *_ = np.linalg.lstsq(A, B, rcond=None)
    return QT.T


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
# Model assessment.


def loo_cv_error(
    kernel: Kernel, X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int
) -> np.ndarray:
    """(3,) leave-one-patch-out cross-validated chart error of a model, per channel.

    Each active patch is predicted by the model fitted without it; the error is
    :func:`ocio_vp.calibration.diagnostics.error_relative_to_white` of those held-out predictions.
    """
    active = np.flatnonzero(w > 0)
    held = np.zeros_like(P)
    for j in active:
        wj = w.copy()
        wj[j] = 0.0
        held[j] = kernel(X, P, wj, white) @ X[j]
    return error_relative_to_white(held, P, white, w)


def target_rank(P: np.ndarray, w: np.ndarray) -> tuple[int, np.ndarray]:
    """Numerical rank of the (weighted) target chart and its relative singular values.

    Raises
    ------
    InputError
        When the fitted patches of the target chart are all black.
    """
    s = np.linalg.svd(P * np.sqrt(w)[:, None], compute_uv=False)
    if not s[0] > 0:
        raise InputError("the target chart is black on every fitted patch", key="target_chart")
    relative = s / s[0]
    return int(np.sum(relative >= RANK_RELATIVE_TOLERANCE)), relative


def _data(problem: QProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
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
        X, P, w, white = _data(problem)
        return QFit(Q=kernel(X, P, w, white), notes={"model": name, "description": description})

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
    """Least squares shrunk toward the white-balance (diagonal) Q; strength by LOO CV."""
    X, P, w, white = _data(problem)
    alpha = _choose_shrinkage(X, P, w, white)
    return QFit(
        Q=_fit_regularised(X, P, w, white),
        notes={
            "model": "regularised",
            "description": "least squares + alpha*trace(X^T W X)/3*||Q - D||^2, D = white balance",
            "shrinkage": alpha,
        },
    )


def soft_choice(errors: dict[str, float], limit: float) -> dict[str, float]:
    """Weights of ``auto``'s models: the hard "simplest within the limit", made continuous.

    Down the ladder, each model takes ``clip((limit - error) / (BLEND_BAND * limit), 0, 1)`` of
    the weight still unassigned; the best model takes what is left. A model clear of the band
    (error <= (1 - BLEND_BAND) limit) takes everything, so clear cases stay a single model
    (e.g. exactly Q = I), and every model with weight has error <= limit.
    """
    best = min(errors, key=errors.__getitem__)
    band = BLEND_BAND * limit
    remaining, weights = 1.0, {}
    for name in AUTO_LADDER:
        if name == best:
            break
        share = remaining * min(max((limit - errors[name]) / band, 0.0), 1.0)
        if share > 0:
            weights[name] = share
            remaining -= share
        if remaining <= 0:
            return weights
    weights[best] = weights.get(best, 0.0) + remaining
    return weights


def q_auto(problem: QProblem) -> QFit:
    """The simplest model the scene needs (see the module docstring and docs/stability.md).

    The notes say which model was chosen (``model``; ``a+b`` with ``blend`` weights when
    :func:`soft_choice` blends), why (``reason``), every candidate's cross-validated error
    (``cv_error``), the ``limit``, the tolerance and the target chart's rank.

    Examples
    --------
    A chart lit exactly as the stage lights it needs no correction:

    >>> SL = np.array([[0.9, 0.1, 0.0], [0.2, 0.8, 0.1], [0.0, 0.1, 0.9]])
    >>> rho = np.random.default_rng(0).uniform(0.05, 0.9, (24, 3, 1))
    >>> SRL = 0.25 * rho * SL
    >>> problem = QProblem(SL=SL, SRL=SRL, beta=0.25, M=np.linalg.inv(SL),
    ...                    w_avg=SL.sum(axis=1), target=SRL.sum(axis=2) / 0.25)
    >>> q_auto(problem).notes["model"]
    'identity'
    """
    X, P, w, white = _data(problem)
    rank, singular = target_rank(P, w)
    tolerance = {"relative": AUTO_TOLERANCE_RELATIVE, "absolute": AUTO_TOLERANCE_ABSOLUTE}
    notes: dict = {
        "target_rank": rank,
        "target_singular_values": singular,
        "rank_relative_tolerance": RANK_RELATIVE_TOLERANCE,
        "tolerance": tolerance,
    }
    if rank < 3:
        name = f"rank-{rank}"

        def kernel(X, P, w, white):
            return _fit_reduced_rank(X, P, w, rank)

        cv = loo_cv_error(kernel, X, P, w, white)
        notes["cross_validated_error"] = cv
        notes |= {
            "model": name,
            "reason": (
                f"the target chart has rank {rank} (singular values relative to the largest: "
                f"{', '.join(f'{v:.2g}' for v in singular)}; below {RANK_RELATIVE_TOLERANCE:g} "
                "counts as absent): a near-monochromatic light, so Q is fitted with rank "
                f"{rank} and cannot be inverted; N is not solved"
            ),
            "cv_error": {name: float(np.mean(cv))},
        }
        return QFit(Q=kernel(X, P, w, white), notes=notes)

    per_channel = {name: loo_cv_error(MODEL_KERNELS[name], X, P, w, white) for name in AUTO_LADDER}
    errors = {name: float(np.mean(cv)) for name, cv in per_channel.items()}
    best_name = min(errors, key=errors.__getitem__)
    limit = errors[best_name] * (1 + AUTO_TOLERANCE_RELATIVE) + AUTO_TOLERANCE_ABSOLUTE
    chosen = next(name for name in AUTO_LADDER if errors[name] <= limit)
    Q = MODEL_KERNELS[chosen](X, P, w, white)
    notes |= {"model": chosen, "cv_error": errors, "limit": limit}
    reason = (
        f"simplest model whose leave-one-patch-out error {100 * errors[chosen]:.3g}% is within "
        f"{100 * limit:.3g}% (best: {best_name} {100 * errors[best_name]:.3g}%, +"
        f"{100 * AUTO_TOLERANCE_RELATIVE:g}% relative +{100 * AUTO_TOLERANCE_ABSOLUTE:g}% of white)"
    )
    cv = per_channel[chosen]
    weights = soft_choice(errors, limit)
    if len(weights) > 1:
        # Near the limit a hard switch would make Q (and N) jump under measurement noise, so
        # the models straddling it are blended, continuously in the errors.
        def blend(X, P, w, white):
            return sum(v * MODEL_KERNELS[k](X, P, w, white) for k, v in weights.items())

        Q = blend(X, P, w, white)
        cv = loo_cv_error(blend, X, P, w, white)
        notes |= {"model": "+".join(weights), "blend": weights}
        reason += "; near the limit, so blended " + ", ".join(
            f"{k} {v:.2f}" for k, v in weights.items()
        )
    notes |= {"reason": reason, "cross_validated_error": cv}
    if "regularised" in weights:
        notes["shrinkage"] = _choose_shrinkage(X, P, w, white)
    return QFit(Q=Q, notes=notes)
