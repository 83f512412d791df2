"""Post-correction (Q) solve methods, dispatched through a registry of typed records.

Every method takes a :class:`QProblem` (everything eq. 5 of the paper mentions) and returns a
:class:`QFit` holding the post-correction itself (:mod:`ocio_vp.model.correction`). A method
may also return an out-of-frustum matrix of its own (joint methods); the caller then derives N
from *that* matrix. Each method is one :class:`QMethod` record: its fit, whether it is always
linear, and its leave-one-patch-out predictions where they have a closed form. Add a method by
writing a function and a record in :data:`Q_SOLVE_METHODS` (and its name in
:data:`ocio_vp.choices.Q_METHODS`, which the command line lists); callers never change.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eq. 5.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.choices import Q_METHODS
from ocio_vp.correction.auto import q_auto
from ocio_vp.correction.joint import q_joint
from ocio_vp.correction.linear import (
    LOO_KERNELS,
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
from ocio_vp.model.correction import MatrixCorrection

__all__ = [
    "NON_LINEAR_METHODS",
    "Q_SOLVE_METHODS",
    "QFit",
    "QMethod",
    "QProblem",
    "q_least_squares",
    "solve_post_correction",
]


def q_least_squares(problem: QProblem) -> QFit:
    """Q minimising eq. 5 of the paper over all (weighted) patches, in the least-squares sense.

    ``Q = argmin sum_j || (1/beta) Q [SRL]_j M w_avg - p_j ||^2``.
    """
    Q = fit_least_squares(problem.predicted, problem.target, problem.fit_weights)
    return QFit(MatrixCorrection(Q), "least-squares", "full 3x3 least squares (eq. 5)")


@dataclass(frozen=True)
class QMethod:
    """One Q-solve method: its ``fit``, whether its correction is always a 3x3 (``linear``),
    and ``held_out``: the name of its closed-form leave-one-patch-out kernel
    (:data:`ocio_vp.correction.linear.LOO_KERNELS`), None where the method reports its own or
    only re-solving once per patch would give it."""

    name: str
    fit: Callable[[QProblem], QFit]
    linear: bool
    held_out: str | None = None

    def __call__(self, problem: QProblem) -> QFit:
        return self.fit(problem)


def _record(name: str, fit: Callable[[QProblem], QFit], linear: bool = True) -> QMethod:
    return QMethod(name, fit, linear, name if name in LOO_KERNELS else None)


#: Q-solve methods by name, in :data:`ocio_vp.choices.Q_METHODS` order; ``method=`` picks one.
Q_SOLVE_METHODS: dict[str, QMethod] = {
    record.name: record
    for record in (
        _record("least-squares", q_least_squares),
        _record("white-preserving", q_white_preserving),
        _record("regularised", q_regularised),
        _record("diagonal", q_diagonal),
        _record("identity", q_identity),
        _record("auto", q_auto, linear=False),
        _record("perceptual", q_perceptual),
        _record("joint", q_joint),
        _record("root-polynomial", make_q_root_polynomial(2), linear=False),
        _record("root-polynomial-3", make_q_root_polynomial(3), linear=False),
    )
}
if tuple(Q_SOLVE_METHODS) != Q_METHODS:  # the command line lists ocio_vp.choices' names
    raise RuntimeError("ocio_vp.choices.Q_METHODS and the Q-solve registry disagree")

#: Methods whose Q may be non-linear (root-polynomial): their configs carry baked 3D LUTs.
NON_LINEAR_METHODS = frozenset(name for name, r in Q_SOLVE_METHODS.items() if not r.linear)


def solve_post_correction(problem: QProblem, *, method: str = "least-squares") -> QFit:
    """Solve Q for ``problem`` with the named method from :data:`Q_SOLVE_METHODS`.

    Raises
    ------
    InputError
        For an unknown method; the message lists the valid ones.
    """
    try:
        record = Q_SOLVE_METHODS[method]
    except KeyError:
        valid = ", ".join(Q_SOLVE_METHODS)
        close = difflib.get_close_matches(method, list(Q_SOLVE_METHODS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(
            f"unknown Q-solve method {method!r}{hint}; valid: {valid}", key="--method"
        ) from None
    fit = record.fit(problem)
    Q = np.asarray(fit.Q, dtype=np.float64)
    if Q.shape != (3, 3) or not np.all(np.isfinite(Q)):
        raise InputError(
            f"the {method!r} solve produced no finite 3x3 Q (shape {Q.shape}); the chart "
            "measurements cannot constrain it",
            key="--method",
        )
    return fit
