"""Post-correction (Q) solve methods, dispatched through a registry.

Every method takes a :class:`QProblem` (everything eq. 5 of the paper mentions) and returns a
:class:`QFit`. A method may also return an out-of-frustum matrix of its own (joint methods);
the caller then derives N from *that* matrix. Add a method by writing a function and adding it
to :data:`Q_SOLVE_METHODS`; callers never change.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eq. 5.
https://doi.org/10.1145/3543664.3543699
"""

from __future__ import annotations

import difflib
from collections.abc import Callable

import numpy as np

from ocio_vp.correction.auto import q_auto
from ocio_vp.correction.joint import q_joint
from ocio_vp.correction.linear import (
    ROOT_POLYNOMIAL_DEGREES,
    fit_least_squares,
    q_diagonal,
    q_identity,
    q_regularised,
    q_white_preserving,
)
from ocio_vp.correction.perceptual import q_perceptual

# Method modules import these two from ocio_vp.correction.problem (not from here) to avoid import cycles.
from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.correction.root_polynomial import make_q_root_polynomial
from ocio_vp.errors import InputError

__all__ = [
    "NON_LINEAR_METHODS",
    "Q_SOLVE_METHODS",
    "QFit",
    "QProblem",
    "q_least_squares",
    "solve_post_correction",
]


def q_least_squares(problem: QProblem) -> QFit:
    """Q minimising eq. 5 of the paper over all (weighted) patches, in the least-squares sense.

    ``Q = argmin sum_j || (1/beta) Q [SRL]_j M w_avg - p_j ||^2``.
    """
    Q = fit_least_squares(problem.predicted, problem.target, problem.fit_weights)
    return QFit(
        Q=Q, notes={"model": "least-squares", "description": "full 3x3 least squares (eq. 5)"}
    )


#: Q-solve methods by name; ``method=`` picks one.
Q_SOLVE_METHODS: dict[str, Callable[[QProblem], QFit]] = {
    "least-squares": q_least_squares,
    "white-preserving": q_white_preserving,
    "regularised": q_regularised,
    "diagonal": q_diagonal,
    "identity": q_identity,
    "auto": q_auto,
    "perceptual": q_perceptual,
    "joint": q_joint,
    # Non-linear; QFit.Q is the 3x3 approximation, the model is in notes["root_polynomial"].
    "root-polynomial": make_q_root_polynomial(2),
    "root-polynomial-3": make_q_root_polynomial(3),
}


#: Methods whose Q may be non-linear (root-polynomial): their configs carry baked 3D LUTs.
NON_LINEAR_METHODS = frozenset({"auto", *ROOT_POLYNOMIAL_DEGREES})


def solve_post_correction(problem: QProblem, *, method: str = "least-squares") -> QFit:
    """Solve Q for ``problem`` with the named method from :data:`Q_SOLVE_METHODS`.

    Raises
    ------
    InputError
        For an unknown method; the message lists the valid ones.
    """
    try:
        solver = Q_SOLVE_METHODS[method]
    except KeyError:
        valid = ", ".join(Q_SOLVE_METHODS)
        close = difflib.get_close_matches(method, list(Q_SOLVE_METHODS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(
            f"unknown Q-solve method {method!r}{hint}; valid: {valid}", key="--method"
        ) from None
    fit = solver(problem)
    Q = np.asarray(fit.Q, dtype=np.float64)
    if Q.shape != (3, 3) or not np.all(np.isfinite(Q)):
        raise InputError(
            f"the {method!r} solve produced no finite 3x3 Q (shape {Q.shape}); the chart "
            "measurements cannot constrain it",
            key="--method",
        )
    return fit
