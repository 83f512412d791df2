"""Root-polynomial post-correction (Finlayson, Mackiewicz & Hurlbert 2015) and its exact inverse.

A root-polynomial Q maps camera RGB ``x`` to ``C e(x)``, where ``e`` is the root-polynomial
expansion of degree d (degree 2: ``r, g, b, sqrt(rg), sqrt(gb), sqrt(rb)``; degree 3 adds the
cube roots of ``r^2 g`` etc. and ``rgb``: 13 terms) and ``C`` is (3, terms). Every term is
homogeneous of degree 1, so ``Q(k x) = k Q(x)`` for ``k > 0``: exposure-invariant like a matrix.
The expansion is the one of colour-science's
:func:`colour.characterisation.polynomial_expansion_Finlayson2015` (same terms, same order,
tested against it), written here as one numpy expression per term so that baking a LUT or
post-correcting a frame does not pay colour-science's per-call overhead. Its roots are
sign-preserving (``sign(t) |t|^(1/k)``), so negative inputs (noise around black) give finite,
continuous values and zero maps to zero.

How it travels through the pipeline: ``QFit.Q`` stays a 3x3 — the weighted least-squares 3x3 on
the same patches, the best linear approximation — because M, N, the reports and the exports are
built on a matrix. The non-linear model itself is in ``QFit.notes["root_polynomial"]``
(``{"degree": d, "coefficients": (3, terms) list}``), which ``solution.json`` carries in
``diagnostics.method_notes``; :func:`post_correction` turns a matrix and those notes back into
the function to apply. The OCIO config carries the model itself as LUTs
(:mod:`ocio_vp.ocio.root_polynomial`), ``ocio-vp apply`` and the Resolve DCTL compute it
exactly, and the fit's ``warnings`` note says where the 3x3 approximation remains.

The inverse (:func:`invert_root_polynomial`) is solved on each colour's direction (the colour
divided by its largest absolute channel, then scaled back: homogeneity), by damped Newton
iterations started from the 3x3 approximation's inverse, all colours at once (batched 3x3
solves with the analytic Jacobian, :func:`root_polynomial_jacobian`).

References
----------
Finlayson, G. D., Mackiewicz, M., Hurlbert, A. (2015). Color Correction Using Root-Polynomial
Regression. IEEE Transactions on Image Processing 24(5), 1460-1470.
https://doi.org/10.1109/TIP.2015.2405336
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ocio_vp.correction.linear import loo_root_polynomial
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.errors import InputError
from ocio_vp.metrics import error_relative_to_white

__all__ = [
    "ROOT_POLYNOMIAL_TERMS",
    "apply_root_polynomial",
    "fit_root_polynomial",
    "invert_root_polynomial",
    "make_q_root_polynomial",
    "post_correction",
    "q_root_polynomial",
    "root_polynomial_expansion",
    "root_polynomial_jacobian",
    "root_polynomial_loo_predictions",
    "root_polynomial_term_powers",
    "root_polynomial_terms",
]

#: Number of root-polynomial terms per degree (colour-science supports degrees 1-4).
ROOT_POLYNOMIAL_TERMS = {1: 3, 2: 6, 3: 13, 4: 22}

#: A fit whose design matrix has a singular value below this fraction of its largest is
#: rank-deficient: the patches do not constrain every term.
RANK_RELATIVE_TOLERANCE = 1e-10

#: The warning a root-polynomial fit carries: where the model travels as a matrix.
CONFIG_APPROXIMATION_WARNING = (
    "root-polynomial Q: Q and N in solution.json are its best 3x3 approximation (the model is "
    "in diagnostics.method_notes.root_polynomial); the OCIO config carries the model as baked "
    "LUTs when N is solved (else the 3x3 too), apply and the Resolve DCTL compute it exactly, "
    "and only Nuke's disabled ColorMatrix fallback is the 3x3"
)


#: Each term of the expansion as (exponents of r, g, b; root): the term is
#: ``sign(p) |p|^(1/root)`` with ``p = r^a g^b b^c``, in colour-science's order.
_TERMS = (
    ((1, 0, 0), 1), ((0, 1, 0), 1), ((0, 0, 1), 1),
    ((1, 1, 0), 2), ((0, 1, 1), 2), ((1, 0, 1), 2),
    ((1, 2, 0), 3), ((0, 1, 2), 3), ((1, 0, 2), 3),
    ((2, 1, 0), 3), ((0, 2, 1), 3), ((2, 0, 1), 3), ((1, 1, 1), 3),
    ((3, 1, 0), 4), ((3, 0, 1), 4), ((1, 3, 0), 4),
    ((0, 3, 1), 4), ((1, 0, 3), 4), ((0, 1, 3), 4),
    ((2, 1, 1), 4), ((1, 2, 1), 4), ((1, 1, 2), 4),
)  # fmt: skip


_ROOT_SIGNS = {1: "", 2: "√", 3: "∛", 4: "∜"}


def root_polynomial_term_powers(degree: int) -> list[tuple[tuple[int, int, int], int]]:
    """Each term as ((a, b, c), k): ``sign(p) |p|^(1/k)`` with ``p = r^a g^b b^c``.

    >>> root_polynomial_term_powers(2)[3]
    ((1, 1, 0), 2)
    """
    return list(_TERMS[: ROOT_POLYNOMIAL_TERMS[degree]])


def root_polynomial_terms(degree: int) -> list[str]:
    """The expansion's terms, as a person reads them.

    >>> root_polynomial_terms(2)
    ['r', 'g', 'b', '√(rg)', '√(gb)', '√(rb)']
    >>> root_polynomial_terms(3)[6:8]
    ['∛(rg²)', '∛(gb²)']
    """
    names = []
    for powers, root in _TERMS[: ROOT_POLYNOMIAL_TERMS[degree]]:
        product = "".join(
            c + {1: "", 2: "²", 3: "³"}[p] for c, p in zip("rgb", powers, strict=True) if p
        )
        names.append(product if root == 1 else f"{_ROOT_SIGNS[root]}({product})")
    return names


def _signed_root(p: np.ndarray, root: int) -> np.ndarray:
    if root == 1:
        return p
    if root == 2:
        return np.copysign(np.sqrt(np.abs(p)), p)
    if root == 3:
        return np.cbrt(p)
    return np.copysign(np.abs(p) ** (1.0 / root), p)


def root_polynomial_expansion(rgb: np.ndarray, degree: int) -> np.ndarray:
    """(..., terms) root-polynomial expansion of (..., 3) ``rgb``, float64.

    >>> root_polynomial_expansion(np.array([4.0, 1.0, 9.0]), 2).tolist()
    [4.0, 1.0, 9.0, 2.0, 3.0, 6.0]
    >>> root_polynomial_expansion(np.array([-4.0, 1.0, 0.0]), 2).tolist()
    [-4.0, 1.0, 0.0, -2.0, 0.0, -0.0]
    """
    if degree not in ROOT_POLYNOMIAL_TERMS:
        raise ValueError(f"root-polynomial degree must be 1-4, got {degree}")
    rgb = np.asarray(rgb, dtype=np.float64)
    channels = (rgb[..., 0], rgb[..., 1], rgb[..., 2])
    out = np.empty((*rgb.shape[:-1], ROOT_POLYNOMIAL_TERMS[degree]))
    for index, (powers, root) in enumerate(_TERMS[: ROOT_POLYNOMIAL_TERMS[degree]]):
        p = None
        for channel, power in zip(channels, powers, strict=True):
            for _ in range(power):
                p = channel if p is None else p * channel
        out[..., index] = _signed_root(p, root)
    return out


def root_polynomial_jacobian(coefficients: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """(n, 3, 3) Jacobian of Q = C e(x) at (n, 3) ``rgb`` (row: output channel, column: d/dx_k).

    Each term ``t = sign(p)|p|^(1/k)`` has ``dt/dx_c = (a_c / k) t / x_c``; where a channel the
    term uses is 0 the derivative is infinite (the square root's slope) and is returned as is
    (callers fall back to another step there).
    """
    C = np.asarray(coefficients, dtype=np.float64)
    x = np.asarray(rgb, dtype=np.float64).reshape(-1, 3)
    terms = root_polynomial_expansion(x, _degree_of(C))
    dterms = np.zeros((*terms.shape, 3))
    with np.errstate(divide="ignore", invalid="ignore"):
        for index, (powers, root) in enumerate(_TERMS[: C.shape[1]]):
            for channel, power in enumerate(powers):
                if power and root == 1:
                    dterms[:, index, channel] = 1.0
                elif power:
                    dterms[:, index, channel] = power / root * terms[:, index] / x[:, channel]
    return np.matmul(C, dterms)  # (3, t) @ (n, t, 3)


def _degree_of(coefficients: np.ndarray) -> int:
    terms = coefficients.shape[-1]
    for degree, n in ROOT_POLYNOMIAL_TERMS.items():
        if n == terms and coefficients.shape == (3, n):
            return degree
    raise InputError(
        f"root-polynomial coefficients must be (3, terms) with terms in "
        f"{sorted(ROOT_POLYNOMIAL_TERMS.values())}, got shape {coefficients.shape}",
        key="root_polynomial.coefficients",
    )


def apply_root_polynomial(coefficients: np.ndarray, rgb: np.ndarray) -> np.ndarray:
    """Q(rgb) = C e(rgb) for (..., 3) ``rgb``; the degree follows from C's shape (3, terms)."""
    C = np.asarray(coefficients, dtype=np.float64)
    return root_polynomial_expansion(rgb, _degree_of(C)) @ C.T


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


def make_q_root_polynomial(degree: int = 2) -> Callable[[QProblem], QFit]:
    """A registry method fitting a root-polynomial Q of ``degree`` (see the module docstring)."""

    def q_root_polynomial_method(problem: QProblem) -> QFit:
        X, P, w = problem.predicted, problem.target, problem.fit_weights
        C = fit_root_polynomial(X, P, w, degree)
        Q = fit_least_squares(X, P, w)
        cv = _loo_error(X, P, w, degree, problem.white_patch)
        return QFit(
            Q=Q,
            notes={
                "model": f"root-polynomial-{degree}",
                "description": f"root-polynomial regression of degree {degree} "
                "(Finlayson et al. 2015); Q is its best 3x3 approximation",
                "root_polynomial": {
                    "degree": degree,
                    "terms": root_polynomial_terms(degree),
                    "coefficients": C.tolist(),
                },
                "warnings": [CONFIG_APPROXIMATION_WARNING],
                **({} if cv is None else {"cross_validated_error": cv}),
            },
        )

    q_root_polynomial_method.__name__ = f"q_root_polynomial_{degree}"
    return q_root_polynomial_method


def root_polynomial_loo_predictions(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, degree: int = 2
) -> np.ndarray:
    """(n, 3) leave-one-patch-out predictions of the root-polynomial fit, in closed form.

    The fit is weighted least squares, linear in its parameters, so removing patch j changes
    its residual to ``r_j / (1 - h_j)`` (``h_j`` the hat matrix's diagonal): one fit instead of
    one per patch. The kernel is :func:`ocio_vp.correction.linear.loo_root_polynomial`, the one
    ``auto`` compares models with; a patch that alone decides a term is refitted without it, and
    patches with weight 0 get the full fit's prediction.

    Raises
    ------
    InputError
        The fit itself is impossible (see :func:`fit_root_polynomial`).
    """
    fit_root_polynomial(X, P, w, degree)  # its guards: too few or dependent patches
    return loo_root_polynomial(
        np.asarray(X, dtype=np.float64),
        np.asarray(P, dtype=np.float64),
        np.asarray(w, dtype=np.float64),
        degree,
    )


def _loo_error(X, P, w, degree: int, white: int) -> np.ndarray | None:
    """(3,) leave-one-patch-out error (white-relative); None with no patch to spare."""
    if int(np.count_nonzero(np.asarray(w) > 0)) <= ROOT_POLYNOMIAL_TERMS[degree]:
        return None
    held = root_polynomial_loo_predictions(X, P, w, degree)
    if not np.all(np.isfinite(held)):
        return None
    return error_relative_to_white(held, P, white, w)


#: The registry's ``root-polynomial`` method: degree 2 (6 terms).
q_root_polynomial = make_q_root_polynomial(2)


def post_correction(
    Q: np.ndarray, notes: Mapping[str, Any] | None
) -> Callable[[np.ndarray], np.ndarray]:
    """The post-correction a solve describes: root-polynomial when ``notes`` carry one, else Q.

    ``notes`` is ``QFit.notes`` or ``solution.json``'s ``diagnostics.method_notes``.
    """
    model = (notes or {}).get("root_polynomial")
    if model is not None:
        C = np.asarray(model["coefficients"], dtype=np.float64)
        return lambda rgb: apply_root_polynomial(C, rgb)
    matrix = np.asarray(Q, dtype=np.float64)
    return lambda rgb: np.asarray(rgb, dtype=np.float64) @ matrix.T


def _linear_approximation(C: np.ndarray) -> np.ndarray:
    """The 3x3 least-squares fit of Q over a grid of non-negative colours (the Newton start)."""
    axis = np.linspace(0.0, 1.0, 6)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    return fit_least_squares(grid, apply_root_polynomial(C, grid), np.ones(len(grid)))


def _newton_step(C: np.ndarray, A: np.ndarray, y: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Newton direction -J^-1 r; the 3x3 approximation's where J is singular or not finite."""
    J = root_polynomial_jacobian(C, y)
    with np.errstate(invalid="ignore", over="ignore"):
        det = np.linalg.det(np.where(np.isfinite(J), J, 0.0))
    bad = ~np.all(np.isfinite(J), axis=(1, 2)) | (np.abs(det) < 1e-12 * abs(np.linalg.det(A)))
    J[bad] = A
    return -np.linalg.solve(J, r[..., None])[..., 0]


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
    largest absolute channel ``s``, ``Q(y) = rgb / s`` is solved by damped Newton iterations
    from the 3x3 approximation's inverse (each step halved until the residual falls), and
    ``x = s y``. Black maps to black. A colour whose iteration does not reach ``tolerance``
    (relative to ``s``; outside the range where Q is injective) keeps its best iterate, which
    is always finite; ``return_residual=True`` also returns the (...,) relative residuals.

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
    c = np.asarray(rgb, dtype=np.float64)
    flat = c.reshape(-1, 3)
    s = np.max(np.abs(flat), axis=1)
    live = np.isfinite(s) & (s > 0)
    t = np.zeros_like(flat)
    t[live] = flat[live] / s[live, None]
    y = t @ np.linalg.inv(A).T
    r = apply_root_polynomial(C, y) - t
    norm = np.max(np.abs(r), axis=1)
    stalled = np.zeros(len(flat), dtype=bool)  # no step lowers the residual: the best iterate
    for _ in range(max_iterations):
        todo = live & ~stalled & (norm > tolerance)
        if not todo.any():
            break
        dy = _newton_step(C, A, y[todo], r[todo])
        stalled[_line_search(C, t, y, r, norm, todo, dy)] = True
    x = np.where(live[:, None], y * np.where(live, s, 0.0)[:, None], 0.0).reshape(c.shape)
    if return_residual:
        return x, np.where(live, norm, 0.0).reshape(c.shape[:-1])
    return x


def _line_search(C, t, y, r, norm, todo, dy, halvings: int = 30) -> np.ndarray:
    """Move y[todo] along dy by the largest 2^-k step (k < ``halvings``) that lowers the
    residual (in place); returns the indices where no step did.

    The full step is tried first; where it fails, every shorter step is evaluated at once
    (one batched call instead of one per halving) and the longest one that helps is taken.
    """
    index = np.flatnonzero(todo)
    trial = y[index] + dy
    r_trial = apply_root_polynomial(C, trial) - t[index]
    n_trial = np.max(np.abs(r_trial), axis=1)
    better = np.isfinite(n_trial) & (n_trial < norm[index])
    done = index[better]
    y[done], r[done], norm[done] = trial[better], r_trial[better], n_trial[better]
    rest, dy = index[~better], dy[~better]
    if len(rest) == 0:
        return rest
    alpha = 2.0 ** -np.arange(1, halvings)
    trials = y[rest][:, None, :] + alpha[None, :, None] * dy[:, None, :]  # (m, k, 3)
    r_trials = apply_root_polynomial(C, trials.reshape(-1, 3)).reshape(trials.shape)
    r_trials -= t[rest][:, None, :]
    n_trials = np.max(np.abs(r_trials), axis=2)
    ok = np.isfinite(n_trials) & (n_trials < norm[rest][:, None])
    found = ok.any(axis=1)
    k = np.argmax(ok, axis=1)[found]  # the longest step that helps
    done = rest[found]
    rows = np.flatnonzero(found)
    y[done], r[done], norm[done] = trials[rows, k], r_trials[rows, k], n_trials[rows, k]
    return rest[~found]
