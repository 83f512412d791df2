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
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.solve import predict_lit_chart

__all__ = [
    "Q_SOLVE_METHODS",
    "QFit",
    "QProblem",
    "q_least_squares",
    "solve_post_correction",
]


@dataclass(frozen=True)
class QProblem:
    """The data of eq. 5 for one environment.

    ``SRL`` is (n, 3, 3) as photographed (not divided by beta); ``target`` the (n, 3) p_j;
    ``weights`` (n,) is 1 for patches to fit and 0 for excluded ones (e.g. clipped).
    """

    SL: np.ndarray
    SRL: np.ndarray
    beta: float
    M: np.ndarray
    w_avg: np.ndarray
    target: np.ndarray
    white_patch: int = 18
    weights: np.ndarray | None = None

    @property
    def predicted(self) -> np.ndarray:
        """(n, 3) the lit chart under M alone, eq. 3: the x_j that Q maps to p_j."""
        return predict_lit_chart(self.SRL, self.beta, self.M, self.w_avg)

    @property
    def fit_weights(self) -> np.ndarray:
        n = self.target.shape[0]
        return np.ones(n) if self.weights is None else np.asarray(self.weights, dtype=np.float64)


@dataclass(frozen=True)
class QFit:
    """A solved post-correction; ``M`` set only by methods that also change the lighting."""

    Q: np.ndarray
    M: np.ndarray | None = None
    notes: Mapping[str, Any] = field(default_factory=dict)


def _weighted_least_squares(X: np.ndarray, P: np.ndarray, w: np.ndarray) -> np.ndarray:
    """argmin_Q sum_j w_j ||Q x_j - p_j||^2, via a QR-based least-squares solve."""
    sw = np.sqrt(w)[:, None]
    # Rows: x_j^T Q^T = p_j^T, i.e. X Q^T = P.
    QT, *_ = np.linalg.lstsq(X * sw, P * sw, rcond=None)
    return QT.T


def q_least_squares(problem: QProblem) -> QFit:
    """Q minimising eq. 5 of the paper over all (weighted) patches, in the least-squares sense.

    ``Q = argmin sum_j || (1/beta) Q [SRL]_j M w_avg - p_j ||^2``.
    """
    Q = _weighted_least_squares(problem.predicted, problem.target, problem.fit_weights)
    return QFit(Q=Q, notes={"model": "full 3x3 least squares (paper, eq. 5)"})


#: Q-solve methods by name; ``method=`` picks one.
Q_SOLVE_METHODS: dict[str, Callable[[QProblem], QFit]] = {
    "least-squares": q_least_squares,
}


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
