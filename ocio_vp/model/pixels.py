"""A post-correction as a per-pixel function for footage: the same model, arranged for speed.

:meth:`~ocio_vp.model.correction.RootPolynomialCorrection.apply` (float64) is the reference.
:func:`pixel_function` evaluates the same formulas on a band of pixels in a chosen float type
(float32 for footage), each step one pass of numpy over the band: the domain's gauge
``max_i n_i . ((u_r, u_b) / sum(u) - centre)`` with ``u = U x`` becomes
``max_i (b_i . x) / (s . x)`` (the hull's edges folded into one (3, edges) matrix ``B``,
``s = U^T 1``), and the polynomial is computed for every pixel and blended as
``L + w (P - L)``. The tests bound the difference from the reference, well below half float's
rounding (what EXR footage stores).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ocio_vp.model.correction import (
    MatrixCorrection,
    ProtectedCorrection,
    RootPolynomialCorrection,
)
from ocio_vp.model.expansion import root_polynomial_term_powers

__all__ = ["PixelFunction", "pixel_function"]

#: ``f(X)``: a band of pixels as planes, (3, n) of the chosen float type (``X[0]`` the reds),
#: in; their correction as (3, n) planes of the same type out (a new array; ``X`` is kept).
PixelFunction = Callable[[np.ndarray], np.ndarray]


def pixel_function(correction, dtype: type = np.float32) -> PixelFunction:
    """The per-pixel function of ``correction`` in ``dtype`` (see the module's docstring).

    Pixels come as planes (3, n) rather than (n, 3) rows: every step is then a small matrix
    times the planes (one BLAS call) or an operation on contiguous rows, where numpy's
    reductions and broadcasts along a length-3 axis are several times slower.

    Examples
    --------
    >>> Q = np.array([[1.1, -0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.1, 0.9]])
    >>> f = pixel_function(MatrixCorrection(Q))
    >>> f(np.ones((3, 2), np.float32)).round(6).tolist()
    [[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]]
    """
    if isinstance(correction, MatrixCorrection):
        Q: np.ndarray = correction.Q.astype(dtype)
        return lambda X: Q @ X
    if isinstance(correction, RootPolynomialCorrection):
        return _root_polynomial(correction, dtype)
    if isinstance(correction, ProtectedCorrection):
        return _protected(correction, dtype)
    raise TypeError(f"no pixel function for {type(correction).__name__}")


def _fade_out(t: np.ndarray) -> np.ndarray:
    """``1 - smoothstep(t)`` in place on ``t`` (its own type): 1 at t <= 0, 0 at t >= 1."""
    np.clip(t, 0.0, 1.0, out=t)
    smooth = t * t
    t *= -2.0
    t += 3.0
    smooth *= t
    np.subtract(1.0, smooth, out=smooth)
    return smooth


def _polynomial(correction: RootPolynomialCorrection, dtype: type) -> PixelFunction:
    """``C e(x)``: the expansion's terms as planes, then one (3, terms) matrix product."""
    C: np.ndarray = correction.coefficients.astype(dtype)
    powers = root_polynomial_term_powers(correction.degree)

    def f(X: np.ndarray) -> np.ndarray:
        terms = np.empty((len(powers), X.shape[1]), dtype=X.dtype)
        terms[:3] = X
        for index, (exponents, k) in enumerate(powers[3:], start=3):
            p = terms[index]
            first = True
            for channel, power in enumerate(exponents):
                for _ in range(power):
                    if first:
                        np.copyto(p, X[channel])
                        first = False
                    else:
                        p *= X[channel]
            if k == 3:
                np.cbrt(p, out=p)
            else:
                root = np.sqrt(np.abs(p)) if k == 2 else np.abs(p) ** dtype(1.0 / k)
                np.copysign(root, p, out=p)
        return C @ terms

    return f


def _gauge_matrix(correction: RootPolynomialCorrection) -> np.ndarray:
    """(edges + 1, 3): rows ``b_i`` (the hull's edges) and, last, ``s``: the gauge of ``x`` is
    ``max_i (b_i . x) / (s . x)`` (:meth:`FitDomain.gauge` with its steps folded together)."""
    domain = correction.domain
    assert domain is not None  # the caller returns the plain polynomial without a domain
    U = domain.to_drive
    normals = domain.edge_normals  # (k, 2), each over its edge's reach
    s = U.sum(axis=0)
    B = np.outer(normals[:, 0], U[0]) + np.outer(normals[:, 1], U[2])
    B -= np.outer(normals @ domain.centre, s)
    return np.vstack([B, s])


def _root_polynomial(correction: RootPolynomialCorrection, dtype: type) -> PixelFunction:
    poly = _polynomial(correction, dtype)
    if correction.domain is None:
        return poly
    A: np.ndarray = correction.fallback.astype(dtype)
    G: np.ndarray = _gauge_matrix(correction).astype(dtype)
    start, end = correction.fade
    offset, scale = dtype(start), dtype(1.0 / (end - start))

    def f(X: np.ndarray) -> np.ndarray:
        linear = A @ X
        edges = G @ X
        total = edges[-1]
        t = edges[:-1].max(axis=0)
        positive = total > 0
        np.divide(t, total, out=t, where=positive)
        t[~positive] = np.inf  # no positive drive: outside, the fallback alone
        t -= offset
        t *= scale
        w = _fade_out(t)
        out = poly(X)
        out -= linear
        out *= w
        out += linear
        return out

    return f


def _protected(correction: ProtectedCorrection, dtype: type) -> PixelFunction:
    inner = pixel_function(correction.inner, dtype)
    U: np.ndarray = correction.domain.to_drive.astype(dtype)
    D: np.ndarray = correction.drive_matrix.astype(dtype)
    low, high = correction.bright
    start, end = correction.negative
    log_low, log_scale = dtype(np.log2(low)), dtype(1.0 / np.log2(high / low))
    neg_start, neg_scale = dtype(start), dtype(1.0 / (end - start))
    floor = dtype(correction.floor)
    tiny = np.finfo(dtype).tiny

    def f(X: np.ndarray) -> np.ndarray:
        v = (U @ X).max(axis=0)  # brightness: the largest drive-relative channel
        bright = v > 0
        t = np.log2(np.maximum(v, tiny, out=v), out=v)
        t -= log_low
        t *= log_scale
        g = _fade_out(t)
        g[~bright] = 1.0  # no positive drive: dark, not bright
        d = D @ X
        top = np.maximum(d.max(axis=0), floor)
        has_top = top > 0
        n = np.negative(d.min(axis=0))
        np.divide(n, top, out=n, where=has_top)
        n -= neg_start
        n *= neg_scale
        g_negative = _fade_out(n)
        g_negative[~has_top] = 0.0  # needs negative light only: an emitter
        g *= g_negative
        out = inner(X)
        out -= X
        out *= g
        out += X
        return out

    return f
