"""The root-polynomial expansion (Finlayson, Mackiewicz & Hurlbert 2015) and its application.

The terms of degree d (degree 2: ``r, g, b, sqrt(rg), sqrt(gb), sqrt(rb)``; degree 3 adds the
cube roots of ``r^2 g`` etc. and ``rgb``: 13 terms) are those of colour-science's
:func:`colour.characterisation.polynomial_expansion_Finlayson2015` (same terms, same order,
tested against it), one numpy expression per term, without colour-science's per-call
overhead. Roots are sign-preserving (``sign(t) |t|^(1/k)``): negative inputs (noise around
black) give finite, continuous values and zero maps to zero.

References
----------
Finlayson, G. D., Mackiewicz, M., Hurlbert, A. (2015). Color Correction Using Root-Polynomial
Regression. IEEE Transactions on Image Processing 24(5), 1460-1470.
https://doi.org/10.1109/TIP.2015.2405336
"""

from __future__ import annotations

import numpy as np

from ocio_vp.errors import InputError

__all__ = [
    "ROOT_POLYNOMIAL_TERMS",
    "apply_root_polynomial",
    "root_polynomial_expansion",
    "root_polynomial_jacobian",
    "root_polynomial_term_powers",
    "root_polynomial_terms",
]

#: Number of root-polynomial terms per degree (colour-science supports degrees 1-4).
ROOT_POLYNOMIAL_TERMS = {1: 3, 2: 6, 3: 13, 4: 22}

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
        p = np.ones(rgb.shape[:-1])
        for channel, power in zip(channels, powers, strict=True):
            for _ in range(power):
                p = p * channel
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
