"""Leave-one-patch-out validation of registry methods."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ocio_vp.correction.registry import solve_post_correction
from ocio_vp.metrics import error_relative_to_white

__all__ = ["CLOSED_FORM_METHODS", "cross_validated_error"]

#: Methods cheap enough (closed forms) to cross-validate by re-solving once per patch.
CLOSED_FORM_METHODS = frozenset(
    {"least-squares", "white-preserving", "regularised", "diagonal", "identity", "auto"}
)


def cross_validated_error(problem: Any, method: str) -> np.ndarray:
    """(3,) leave-one-patch-out error of a registry method (white-relative, per channel).

    Every fitted patch is predicted by ``method`` solved on the other patches, through the M
    that fit returns (joint methods) or the calibrated M.
    """
    weights = problem.fit_weights
    target = np.asarray(problem.target, dtype=np.float64)
    held = target.copy()
    for j in np.flatnonzero(weights > 0):
        w = weights.copy()
        w[j] = 0.0
        sub = dataclasses.replace(problem, weights=w)
        fit = solve_post_correction(sub, method=method)
        if fit.M is not None:
            sub = dataclasses.replace(sub, M=np.asarray(fit.M, dtype=np.float64))
        held[j] = np.asarray(fit.Q, dtype=np.float64) @ sub.predicted[j]
    return error_relative_to_white(held, target, problem.white_patch, weights)
