"""Numbers that tell a stage engineer whether a solve can be trusted.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, Fig. 11: mean absolute error per
channel relative to the target white patch, the metric used throughout ocio_vp's tables.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["error_relative_to_white"]


def error_relative_to_white(
    predicted: ArrayLike, target: ArrayLike, white_patch: int = 18, weights: ArrayLike | None = None
) -> np.ndarray:
    """Mean absolute error per channel, relative to the target white patch (paper, Fig. 11).

    Parameters
    ----------
    predicted, target
        (..., n, 3) chart values.
    white_patch
        Index of the white patch in ``target``.
    weights
        Optional (n,) weights (0 excludes a patch).

    Returns
    -------
    ndarray
        (..., 3) ``mean_j |predicted_j - target_j| / target_white``.

    Examples
    --------
    >>> target = np.ones((24, 3)); predicted = target * 1.02
    >>> error_relative_to_white(predicted, target).round(6).tolist()
    [0.02, 0.02, 0.02]
    """
    predicted = np.asarray(predicted, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    white = target[..., white_patch, :]
    error = np.abs(predicted - target) / white[..., None, :]
    w = np.ones(target.shape[-2]) if weights is None else np.asarray(weights, dtype=np.float64)
    return np.tensordot(w, error, axes=([0], [-2])) / w.sum()
