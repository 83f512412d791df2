"""The ``perceptual`` Q-solve method: minimise the mean ΔE2000 (or ΔE ITP) of the lit chart.

Eq. 5 weighs a dark patch's visible hue shift less than a bright patch's invisible one. This
method starts from its least-squares Q and lets scipy minimise the mean of colour-science's
``delta_E`` ("CIE 2000" or "ITP") between the corrected lit chart ``Q x_j`` and the target
``p_j`` (weighted patches only), normalised on the target white, through a camera RGB -> XYZ
matrix (the sample camera's unless given: a stand-in good enough to weigh errors perceptually,
not a characterisation of *your* camera).

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, eq. 5 (the least-squares start).
CIE 142-2001, CIEDE2000; ITU-R BT.2124-0 (2019), ΔE ITP.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.deprecation import deprecated_names
from ocio_vp.metrics import ITP_WHITE_NITS, sample_camera_to_xyz
from ocio_vp.model.correction import MatrixCorrection

__all__ = [
    "PERCEPTUAL_METRICS",
    "make_q_perceptual",
    "mean_delta_e",
    "normalising_white",
    "patch_delta_e",
    "q_perceptual",
]

#: ``metric=`` values: colour-science's ``delta_E`` method names.
PERCEPTUAL_METRICS = ("CIE 2000", "ITP")

_STEP = 1e-6  # finite-difference step on Q's entries (which are ~1)


def _encoder(
    target: np.ndarray, camera_to_xyz: np.ndarray, white_patch: int, metric: str
) -> Callable[[np.ndarray], np.ndarray]:
    """A function camera RGB (n, 3) -> Lab or ICtCp, normalised on the target's white."""
    import colour

    xyz_white = camera_to_xyz @ target[white_patch]
    if not xyz_white[1] > 0:
        raise ValueError("the target white patch has no luminance: ΔE is undefined")
    scale = 1.0 / xyz_white[1]
    if metric == "CIE 2000":
        white_xy = colour.XYZ_to_xy(xyz_white * scale)
        return lambda rgb: colour.XYZ_to_Lab(rgb @ (camera_to_xyz.T * scale), white_xy)
    if metric == "ITP":
        factor = camera_to_xyz.T * (scale * ITP_WHITE_NITS)
        return lambda rgb: colour.XYZ_to_ICtCp(rgb @ factor, method="ITU-R BT.2100-2 PQ")
    raise ValueError(f"metric must be one of {PERCEPTUAL_METRICS}, got {metric!r}")


def normalising_white(
    luminance: ArrayLike, white_patch: int, weights: ArrayLike | None = None
) -> int:
    """The patch ΔE is normalised on: ``white_patch``, or, when it is excluded (weight 0) or
    has no ``luminance``, the fitted patch of highest luminance (ValueError if none is fitted).
    """
    luminance = np.asarray(luminance, dtype=np.float64)
    w = np.ones(len(luminance)) if weights is None else np.asarray(weights, dtype=np.float64)
    if w[white_patch] > 0 and luminance[white_patch] > 0:
        return white_patch
    return int(np.argmax(np.where(w > 0, luminance, -np.inf)))


def patch_delta_e(
    predicted: ArrayLike,
    target: ArrayLike,
    *,
    camera_to_xyz: ArrayLike | None = None,
    white_patch: int = DEFAULT_WHITE_PATCH,
    weights: ArrayLike | None = None,
    metric: str = "CIE 2000",
) -> np.ndarray:
    """(..., n) ΔE (``metric``) of each patch of ``predicted`` against ``target`` (camera RGB).

    ``predicted`` is (n, 3) or a stack of predictions (..., n, 3) of the same (n, 3) target
    (candidate models), in one call. Normalised on the target white patch, or where that is
    excluded (weight 0) or has no luminance, on the fitted patch of highest luminance.
    ``camera_to_xyz`` defaults to :func:`~ocio_vp.metrics.sample_camera_to_xyz`.
    """
    import colour

    target = np.asarray(target, dtype=np.float64)
    matrix = sample_camera_to_xyz() if camera_to_xyz is None else np.asarray(camera_to_xyz, float)
    white = normalising_white(target @ matrix[1], white_patch, weights)
    encode = _encoder(target, matrix, white, metric)
    return np.asarray(
        colour.delta_E(encode(target), encode(np.asarray(predicted, float)), method=metric)
    )


def mean_delta_e(
    predicted: ArrayLike,
    target: ArrayLike,
    *,
    camera_to_xyz: ArrayLike,
    white_patch: int = DEFAULT_WHITE_PATCH,
    metric: str = "CIE 2000",
    weights: ArrayLike | None = None,
) -> float:
    """Weighted mean of :func:`patch_delta_e`: ``predicted`` against ``target``, (n, 3) each."""
    de = patch_delta_e(
        predicted, target, camera_to_xyz=camera_to_xyz, white_patch=white_patch, metric=metric
    )
    w = np.ones(len(de)) if weights is None else np.asarray(weights, float)
    return float(np.sum(w * de) / np.sum(w))


def make_q_perceptual(
    *, camera_to_xyz: ArrayLike | None = None, metric: str = "CIE 2000", max_iterations: int = 400
) -> Callable[[QProblem], QFit]:
    """A Q-solve method (for :data:`ocio_vp.correction.registry.Q_SOLVE_METHODS`) minimising mean ΔE.

    Parameters
    ----------
    camera_to_xyz
        (3, 3) camera RGB -> CIE XYZ; default :func:`~ocio_vp.metrics.sample_camera_to_xyz`.
    metric
        ``"CIE 2000"`` (CIEDE2000 in Lab) or ``"ITP"`` (ITU-R BT.2124).
    max_iterations
        Limit of scipy's L-BFGS-B iterations.
    """
    if metric not in PERCEPTUAL_METRICS:
        raise ValueError(f"metric must be one of {PERCEPTUAL_METRICS}, got {metric!r}")

    def q_perceptual_method(problem: QProblem) -> QFit:
        import colour
        from scipy.optimize import minimize

        matrix = sample_camera_to_xyz() if camera_to_xyz is None else np.asarray(camera_to_xyz)
        X = np.asarray(problem.predicted, dtype=np.float64)
        P = np.asarray(problem.target, dtype=np.float64)
        w = problem.fit_weights
        start = fit_least_squares(X, P, w).copy()  # start: eq. 5's weighted least squares
        encode = _encoder(P, matrix, problem.white_patch, metric)
        reference = encode(P)
        total = float(np.sum(w))

        # All 19 matrices of a central-difference gradient go through colour in one call.
        steps = np.concatenate([np.zeros((1, 9)), _STEP * np.eye(9), -_STEP * np.eye(9)])

        def mean_de(qs: np.ndarray) -> np.ndarray:
            lit = np.einsum("kij,nj->kni", qs.reshape(-1, 3, 3), X)
            de = colour.delta_E(reference, encode(lit), method=metric)
            values = de @ w / total
            return np.where(np.isfinite(values), values, 1e6)  # outside the metric's domain

        def objective(q: np.ndarray) -> tuple[float, np.ndarray]:
            values = mean_de(q[None, :] + steps)
            return float(values[0]), (values[1:10] - values[10:]) / (2 * _STEP)

        first = float(mean_de(start.reshape(1, 9))[0])
        result = minimize(
            objective,
            start.ravel(),
            jac=True,
            method="L-BFGS-B",
            options={"maxiter": max_iterations},
        )
        Q = result.x.reshape(3, 3)
        final = float(result.fun)
        if not (np.isfinite(final) and final <= first and np.all(np.isfinite(Q))):
            Q, final = start, first  # never worse than the paper's solve
        return QFit(
            MatrixCorrection(Q),
            "perceptual",
            f"minimum mean ΔE {metric} from the least-squares start (eq. 5)",
            details={
                "metric": metric,
                "mean_delta_e_start": first,
                "mean_delta_e": final,
                "iterations": int(result.nit),
                "converged": bool(result.success),
                "camera_to_xyz": "given" if camera_to_xyz is not None else "sample camera",
            },
        )

    return q_perceptual_method


#: The registry's ``perceptual`` method: mean ΔE2000 with the sample camera's matrix.
q_perceptual = make_q_perceptual()

#: Names served for one more release (ocio_vp.deprecation): the sample camera's matrix is now
#: read from the package's committed file instead of fitted here.
DEPRECATED = {
    "default_camera_to_xyz": (
        "ocio_vp.metrics.sample_camera_to_xyz",
        "ocio_vp.metrics:sample_camera_to_xyz",
    )
}
__getattr__ = deprecated_names(__name__, DEPRECATED)
