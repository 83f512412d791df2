"""Leave-one-patch-out validation of registry methods."""

from __future__ import annotations

import dataclasses

import numpy as np

from ocio_vp.correction.linear import loo_predictions
from ocio_vp.correction.problem import QProblem
from ocio_vp.correction.registry import Q_SOLVE_METHODS, solve_post_correction
from ocio_vp.metrics import error_relative_to_white

__all__ = ["CLOSED_FORM_METHODS", "cross_validated_error", "held_out_predictions"]

#: Methods cheap enough (closed forms) to cross-validate on every solve.
CLOSED_FORM_METHODS = frozenset(
    name for name, record in Q_SOLVE_METHODS.items() if record.held_out is not None
)


def held_out_predictions(problem: QProblem, method: str) -> np.ndarray:
    """(n, 3) every fitted patch predicted by ``method`` solved without it.

    In closed form for the linear models (:data:`ocio_vp.correction.linear.LOO_KERNELS`,
    linear in the number of patches); otherwise by re-solving once per patch, through the M that
    the fit returns (joint methods) or the calibrated M.
    """
    weights = problem.fit_weights
    target = np.asarray(problem.target, dtype=np.float64)
    kernel = Q_SOLVE_METHODS[method].held_out
    if kernel is not None:
        X = problem.predicted
        return loo_predictions(kernel, X, target, weights, int(problem.white_patch))
    held = target.copy()
    for j in np.flatnonzero(weights > 0):
        w = weights.copy()
        w[j] = 0.0
        sub = dataclasses.replace(problem, weights=w)
        fit = solve_post_correction(sub, method=method)
        if fit.M is not None:
            sub = dataclasses.replace(sub, M=np.asarray(fit.M, dtype=np.float64))
        held[j] = np.asarray(fit.Q, dtype=np.float64) @ sub.predicted[j]
    return held


def cross_validated_error(problem: QProblem, method: str) -> np.ndarray:
    """(3,) leave-one-patch-out error of a registry method (white-relative, per channel)."""
    held = held_out_predictions(problem, method)
    target = np.asarray(problem.target, dtype=np.float64)
    return error_relative_to_white(held, target, problem.white_patch, problem.fit_weights)
