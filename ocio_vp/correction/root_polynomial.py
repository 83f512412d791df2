"""Root-polynomial post-correction (Finlayson, Mackiewicz & Hurlbert 2015): the fit, bounded
to the chart's domain, and the exact inverse of the polynomial.

A root-polynomial Q maps camera RGB ``x`` to ``C e(x)`` (:mod:`ocio_vp.model.expansion`:
homogeneous of degree 1). Beyond the chart it only extrapolates (bright saturated inputs and
emitters lose or flip channels), so the method returns a
:class:`~ocio_vp.model.correction.RootPolynomialCorrection`: the polynomial inside the chart's
domain, fading to the least-squares 3x3 outside it, with the widest fade that folds nowhere
among reflective colours (:func:`ocio_vp.correction.extrapolation.choose_fade`).

References
----------
Finlayson, G. D., Mackiewicz, M., Hurlbert, A. (2015). Color Correction Using Root-Polynomial
Regression. IEEE Transactions on Image Processing 24(5), 1460-1470.
https://doi.org/10.1109/TIP.2015.2405336
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator

import numpy as np

from ocio_vp.correction.extrapolation import FADES, choose_fade, fade_label
from ocio_vp.correction.linear import LOO_KERNELS, loo_root_polynomial
from ocio_vp.correction.problem import Folds, QFit, QProblem, fit_least_squares
from ocio_vp.correction.skin import SkinRows, with_rows
from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.metrics import error_relative_to_white
from ocio_vp.model.correction import (
    FitDomain,
    MatrixCorrection,
    RootPolynomialCorrection,
    newton_inverse,
)
from ocio_vp.model.expansion import (
    ROOT_POLYNOMIAL_TERMS,
    apply_root_polynomial,
    root_polynomial_expansion,
    root_polynomial_jacobian,
    root_polynomial_term_powers,
    root_polynomial_terms,
)

__all__ = [
    "ROOT_POLYNOMIAL_TERMS",
    "apply_root_polynomial",
    "bounded_loo_predictions",
    "fit_root_polynomial",
    "invert_root_polynomial",
    "make_q_root_polynomial",
    "q_root_polynomial",
    "root_polynomial_expansion",
    "root_polynomial_jacobian",
    "root_polynomial_loo_predictions",
    "root_polynomial_term_powers",
    "root_polynomial_terms",
]

#: A fit whose design matrix has a singular value below this fraction of its largest is
#: rank-deficient: the patches do not constrain every term.
RANK_RELATIVE_TOLERANCE = 1e-10


def fit_root_polynomial(X: np.ndarray, P: np.ndarray, w: np.ndarray, degree: int = 2) -> np.ndarray:
    """(3, terms) C minimising ``sum_j w_j ||C e(x_j) - p_j||^2`` over patches with ``w_j > 0``.

    Raises
    ------
    InputError
        Too few fitted patches for the terms, a rank-deficient design, or a non-finite result.
    """
    if degree not in ROOT_POLYNOMIAL_TERMS:
        raise InputError(
            f"root-polynomial degree must be one of {sorted(ROOT_POLYNOMIAL_TERMS)}, got {degree}",
            key="--method",
        )
    terms = ROOT_POLYNOMIAL_TERMS[degree]
    keep = np.asarray(w, dtype=np.float64) > 0
    if int(keep.sum()) < terms:
        raise InputError(
            f"root-polynomial degree {degree} has {terms} terms per channel but only "
            f"{int(keep.sum())} chart patches are fitted; use a lower degree or more patches",
            key="--method",
        )
    sw = np.sqrt(np.asarray(w, dtype=np.float64)[keep])[:, None]
    E = root_polynomial_expansion(np.asarray(X, dtype=np.float64)[keep], degree) * sw
    singular = np.linalg.svd(E, compute_uv=False)
    if (
        not np.all(np.isfinite(singular))
        or not singular[-1] > RANK_RELATIVE_TOLERANCE * singular[0]
    ):
        raise InputError(
            f"root-polynomial degree {degree}: the fitted patches do not constrain all {terms} "
            "terms (rank-deficient design); use a lower degree or a chart with more colours",
            key="--method",
        )
    CT, *_ = np.linalg.lstsq(E, np.asarray(P, dtype=np.float64)[keep] * sw, rcond=None)
    if not np.all(np.isfinite(CT)):
        raise InputError(f"root-polynomial degree {degree}: non-finite fit", key="--method")
    return CT.T


def make_q_root_polynomial(degree: int = 2, skin_weight: float = 0.0) -> Callable[[QProblem], QFit]:
    """A registry method fitting a bounded root-polynomial Q of ``degree`` (module docstring).

    ``skin_weight`` > 0 fits the polynomial to the problem's skin samples too
    (:func:`ocio_vp.correction.skin.skin_rows`: their weight relative to the chart's); the
    fallback stays the chart's least squares, so emitters and saturated colours beyond the
    chart's domain are corrected as without skin.
    """

    def q_root_polynomial_method(problem: QProblem) -> QFit:
        X, P, w = problem.predicted, problem.target, problem.fit_weights
        rows = problem.skin_rows(skin_weight)
        C = fit_root_polynomial(*with_rows(X, P, w, rows), degree)
        A = fit_least_squares(X, P, w)
        domain = problem.domain
        fade, tried = choose_fade(C, A, domain)
        warnings = []
        if fade is None:
            fade = FADES[-1]
            warnings.append(
                f"the root-polynomial Q folds (maps two reflective colours to one) in "
                f"{min(tried.values()):.1%} of the reflective solid whatever its fade: "
                "prefer a 3x3 method for this environment"
            )
        correction = RootPolynomialCorrection(C, A, domain, fade)
        folds = Folds(correction, domain, tried[fade_label(fade)])
        anchored = "" if rows is None else f", fitted to {len(rows.x)} skin samples too"
        details: dict = {"folds_by_fade": tried}
        if rows is not None:
            details["skin_weight"] = skin_weight
        spare = int(np.count_nonzero(w > 0)) > ROOT_POLYNOMIAL_TERMS[degree]
        held = bounded_loo_predictions(problem, correction, rows) if spare else None
        return QFit(
            correction,
            f"root-polynomial-{degree}" + ("" if rows is None else "-skin"),
            f"root-polynomial regression of degree {degree} (Finlayson et al. 2015){anchored}, "
            "bounded to the chart's domain; Q is its 3x3 fallback",
            cross_validated_error=None
            if held is None or not np.all(np.isfinite(held))
            else error_relative_to_white(held, P, problem.white_patch, w),
            warnings=tuple(warnings),
            details=details,
            loo_predictions=held,
            folds=folds,
        )

    q_root_polynomial_method.__name__ = f"q_root_polynomial_{degree}"
    return q_root_polynomial_method


def root_polynomial_loo_predictions(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, degree: int = 2
) -> np.ndarray:
    """(n, 3) leave-one-patch-out predictions of the root-polynomial fit, in closed form
    (:func:`ocio_vp.correction.linear.loo_root_polynomial`, the kernel ``auto`` compares models
    with, after :func:`fit_root_polynomial`'s guards); patches with weight 0 get the full fit's
    prediction.

    Raises
    ------
    InputError
        The fit itself is impossible (see :func:`fit_root_polynomial`).
    """
    fit_root_polynomial(X, P, w, degree)  # its guards: too few or dependent patches
    X, P, w = (np.asarray(a, dtype=np.float64) for a in (X, P, w))
    return loo_root_polynomial(X, P, w, degree)


def bounded_loo_predictions(
    problem: QProblem, correction: RootPolynomialCorrection, rows: SkinRows | None = None
) -> np.ndarray:
    """(n, 3) leave-one-patch-out predictions of a bounded root-polynomial Q, in closed form.

    Patch j: the polynomial and the least-squares 3x3 fitted without it (hat-matrix identities,
    :func:`~ocio_vp.correction.linear.loo_root_polynomial`), blended by the weight of x_j in the
    domain of the other fitted patches, at the correction's fade. With skin ``rows`` fitted too,
    they stay in every leave-one-out fit (a skin sample made from patch j keeps a little of it).
    """
    X, P, w = problem.predicted, np.asarray(problem.target, dtype=np.float64), problem.fit_weights
    polynomial = loo_root_polynomial(*with_rows(X, P, w, rows), correction.degree)[: len(X)]
    linear = LOO_KERNELS["least-squares"](X, P, w, int(problem.white_patch))
    weights = np.zeros(len(X))
    for j, domain in _loo_domains(problem, w):
        bounded = RootPolynomialCorrection(
            correction.coefficients, correction.fallback, domain, correction.fade
        )
        weights[j] = bounded.weight(X[j])
    return linear + weights[:, None] * (polynomial - linear)


def _loo_domains(problem: QProblem, w: np.ndarray) -> Iterator[tuple[int, FitDomain]]:
    """(j, the domain of the fitted patches but j) for every fitted patch j.

    Only the hull depends on which patches are fitted (the drive scale and the centre come from
    the white patch), and leaving out a patch that is not a vertex of the full hull leaves the
    hull as it is: those patches share the full domain, and only the few vertices are refitted,
    so the cost grows with the chart, not with its square.
    """
    full = problem.domain
    fitted = np.flatnonzero(w > 0)
    u = problem.predicted[w > 0] @ full.to_drive.T  # as fit_domain computes the hull's points
    total = u.sum(axis=-1)
    chroma = np.full((len(u), 2), np.nan)
    chroma[total > 0] = u[total > 0][:, [0, 2]] / total[total > 0, None]
    points = np.round(chroma, 15)  # fit_domain's hull merges points equal to 15 decimals
    vertices = {tuple(v) for v in full.hull}
    counts: dict[tuple[float, float], int] = {}
    for point in map(tuple, points):
        counts[point] = counts.get(point, 0) + 1
    for j, point in zip(fitted, map(tuple, points), strict=True):
        if point in vertices and counts[point] == 1:
            others = w.copy()
            others[j] = 0.0
            yield int(j), dataclasses.replace(problem, weights=others).domain
        else:
            yield int(j), full


#: The registry's ``root-polynomial`` method: degree 2 (6 terms).
q_root_polynomial = make_q_root_polynomial(2)


def _linear_approximation(C: np.ndarray) -> np.ndarray:
    """The 3x3 least-squares fit of Q over a grid of non-negative colours (the Newton start)."""
    axis = np.linspace(0.0, 1.0, 6)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    return fit_least_squares(grid, apply_root_polynomial(C, grid), np.ones(len(grid)))


def invert_root_polynomial(
    coefficients: np.ndarray,
    rgb: np.ndarray,
    *,
    tolerance: float = 1e-13,
    max_iterations: int = 60,
    return_residual: bool = False,
):
    """Q^-1(rgb): the x with ``C e(x) = rgb``, for (..., 3) ``rgb``.

    Homogeneity makes this a problem on the colour's direction: ``rgb`` is divided by its
    largest absolute channel ``s``, ``Q(y) = rgb / s`` is solved by
    :func:`~ocio_vp.model.correction.newton_inverse` (analytic Jacobian) from the 3x3
    approximation's inverse, and ``x = s y``. Black maps to black. A colour whose iteration
    does not reach ``tolerance`` (relative to ``s``; outside the range where Q is injective)
    keeps its best iterate, which is always finite; ``return_residual=True`` also returns the
    (...,) relative residuals.

    Raises
    ------
    InputError
        When the 3x3 approximation of Q is singular (Q is not invertible).
    """
    C = np.asarray(coefficients, dtype=np.float64)
    A = _linear_approximation(C)
    if not np.linalg.cond(A) < 1e12:
        raise InputError(
            "root-polynomial Q is not invertible (singular 3x3 approximation)",
            key="root_polynomial.coefficients",
        )
    x = newton_inverse(
        lambda y: apply_root_polynomial(C, y),
        rgb,
        A,
        homogeneous=True,
        tolerance=tolerance,
        max_iterations=max_iterations,
        jacobian=lambda y: root_polynomial_jacobian(C, y),
        halvings=30,  # as this inverse always searched: near a fold, more colours converge
    )
    if not return_residual:
        return x
    size = np.max(np.abs(np.asarray(rgb, dtype=np.float64)), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        residual = np.max(np.abs(apply_root_polynomial(C, x) - rgb), axis=-1) / size
    return x, np.where(np.isfinite(size) & (size > 0), residual, 0.0)


def _post_correction(Q: np.ndarray, notes: dict | None) -> Callable[[np.ndarray], np.ndarray]:
    """The deprecated ``post_correction(Q, notes)``: the correction a solve's ``Q`` and method
    notes described (a root-polynomial, unbounded, when the notes carry one, else Q)."""
    model = (notes or {}).get("root_polynomial")
    if model is not None:
        return RootPolynomialCorrection(model["coefficients"], Q).apply
    return MatrixCorrection(Q).apply


#: Names that left this module (:mod:`ocio_vp.deprecation`).
DEPRECATED = {
    "post_correction": (
        "Solution.post_correction.apply (ocio_vp.model: correction_from_dict)",
        lambda: _post_correction,
    )
}
__getattr__ = deprecated_names(__name__, DEPRECATED)
