"""The ``joint`` Q-solve method: optimise the out-of-frustum matrix and Q together, within limits.

Eq. 5 is minimised over the drive ``d = M' w_avg`` and Q (scipy's SLSQP, from the sequential
solution), with the stage light's white point (CIEDE2000), its drive range and cond(Q) bounded
and its luminance kept; M' is the smallest change of M with that drive, and N stays
``[SL]^-1 Q^-1`` (eq. 7). docs/joint.md explains the limits, their defaults and the convention.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eqs. 3, 5, 7 and
Future Work. https://doi.org/10.1145/3543664.3543681
CIE 142-2001, Improvement to industrial colour-difference evaluation (CIEDE2000).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.calibration.equations import condition_number
from ocio_vp.correction.linear import fit_least_squares
from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.metrics import sample_camera_to_xyz
from ocio_vp.model.correction import MatrixCorrection

__all__ = [
    "DEFAULT_MAX_CONDITION",
    "DEFAULT_MAX_DELTA_E",
    "joint_matrix",
    "make_q_joint",
    "q_joint",
    "white_point_delta_e",
]

#: Default white-point limit, CIEDE2000 between the joint and the baseline stage light.
DEFAULT_MAX_DELTA_E = 2.0
#: Default bound on cond(Q) (N = [SL]^-1 Q^-1 amplifies errors by at most this).
DEFAULT_MAX_CONDITION = 100.0

#: Why there is no joint solve without a visible baseline light.
NO_BASELINE = (
    "the baseline stage light M w_avg has no luminance or no positive drive: the white-point "
    "and drive limits are undefined"
)
#: What every joint fit is.
JOINT_DESCRIPTION = (
    "out-of-frustum matrix and Q jointly minimising eq. 5 under white-point, drive and cond(Q) "
    "limits (paper, Future Work)"
)
_TOL = 1e-6  # relative slack when checking a limit / calling it active


def white_point_delta_e(light: ArrayLike, baseline: ArrayLike, *, camera_to_xyz: ArrayLike):
    """CIEDE2000 between the chromaticities of two camera-RGB lights (luminance ignored).

    Both are scaled to Y = 1 and ``baseline``'s chromaticity is the Lab reference white, so
    ``baseline`` itself is (100, 0, 0). ``light`` may be (..., 3).

    Examples
    --------
    >>> m = np.eye(3)
    >>> float(white_point_delta_e([2.0, 2.0, 2.0], [1.0, 1.0, 1.0], camera_to_xyz=m))
    0.0
    """
    import colour

    matrix = np.asarray(camera_to_xyz, dtype=np.float64)
    xyz_base = matrix @ np.asarray(baseline, dtype=np.float64)
    xyz = np.asarray(light, dtype=np.float64) @ matrix.T
    white_xy = colour.XYZ_to_xy(xyz_base / xyz_base[1])
    lab = colour.XYZ_to_Lab(xyz / xyz[..., 1:2], white_xy)
    return colour.delta_E(np.array([100.0, 0.0, 0.0]), lab, method="CIE 2000")


def joint_matrix(M: ArrayLike, w_avg: ArrayLike, drive: ArrayLike) -> np.ndarray:
    """The smallest (Frobenius) change of ``M`` with ``M' w_avg = drive`` (a rank-1 update).

    Examples
    --------
    >>> w = np.array([0.8, 1.0, 0.6]); d = np.array([0.7, 1.1, 0.5])
    >>> bool(np.allclose(joint_matrix(np.eye(3), w, d) @ w, d))
    True
    """
    M = np.asarray(M, dtype=np.float64)
    w = np.asarray(w_avg, dtype=np.float64)
    return M + np.outer(np.asarray(drive, dtype=np.float64) - M @ w, w) / float(w @ w)


def _forward_difference(f: Callable[[np.ndarray], float], z: np.ndarray, part: slice) -> np.ndarray:
    """(1, len(z)) gradient of ``f`` by forward differences over ``z[part]`` only (0 elsewhere)."""
    grad = np.zeros((1, z.size))
    f0 = f(z)
    for i in range(*part.indices(z.size)):
        step = 1.49e-8 * max(1.0, abs(z[i]))  # sqrt(machine epsilon)
        zi = z.copy()
        zi[i] += step
        grad[0, i] = (f(zi) - f0) / step
    return grad


def make_q_joint(
    *,
    camera_to_xyz: ArrayLike | None = None,
    max_delta_e: float = DEFAULT_MAX_DELTA_E,
    max_drive: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    max_iterations: int = 300,
) -> Callable[[QProblem], QFit]:
    """A Q-solve method (for :data:`ocio_vp.correction.registry.Q_SOLVE_METHODS`) that also returns M'.

    Parameters
    ----------
    camera_to_xyz
        (3, 3) camera RGB -> CIE XYZ for the white-point ΔE and the luminance; default the
        sample camera's (:func:`ocio_vp.metrics.sample_camera_to_xyz`).
    max_delta_e
        Largest CIEDE2000 between the joint and the baseline stage-light chromaticity.
    max_drive
        Largest LED drive of ``M' w_avg``; default the baseline's largest channel.
    max_condition
        Largest cond(Q).
    max_iterations
        SLSQP iteration limit.
    """
    if not max_delta_e >= 0 or not max_condition >= 1:
        raise ValueError(
            f"need max_delta_e >= 0, max_condition >= 1: {max_delta_e}, {max_condition}"
        )

    def q_joint_method(problem: QProblem) -> QFit:
        given = camera_to_xyz is not None
        matrix = np.asarray(camera_to_xyz if given else sample_camera_to_xyz(), dtype=np.float64)
        joint = _JointProblem(
            problem, matrix, max_delta_e=max_delta_e, max_drive=max_drive,
            max_condition=max_condition,
        )  # fmt: skip
        return _solve_joint(joint, max_iterations, "given" if given else "sample camera")

    return q_joint_method


class _JointProblem:
    """Eq. 5 over (d, Q) for one problem: the objective, the limits, SLSQP's constraints.

    The unknowns are ``z = [d / scale, Q.ravel()]`` (scaled drive, so all 12 are of order 1).
    """

    def __init__(
        self,
        problem: QProblem,
        matrix: np.ndarray,
        *,
        max_delta_e: float,
        max_drive: float | None,
        max_condition: float,
    ) -> None:
        self.matrix, self.max_delta_e, self.max_condition = matrix, max_delta_e, max_condition
        self.SL = np.asarray(problem.SL, dtype=np.float64)
        self.M = np.asarray(problem.M, dtype=np.float64)
        self.w_avg = np.asarray(problem.w_avg, dtype=np.float64)
        self.A = np.asarray(problem.SRL, dtype=np.float64) / float(problem.beta)  # x_j = A_j d
        # Light no drive here changes (the stage's other panel types), or None.
        self.fixed = None if problem.extra_light is None else np.asarray(problem.extra_light)
        self.P = np.asarray(problem.target, dtype=np.float64)
        self.w = problem.fit_weights
        self.d0 = self.M @ self.w_avg
        self.baseline_light = self.SL @ self.d0
        self.y_row = matrix[1] @ self.SL  # luminance of the stage light, linear in d
        self.y0 = float(self.y_row @ self.d0)
        self.top = float(np.max(self.d0)) if max_drive is None else float(max_drive)
        self.scale = max(float(np.max(np.abs(self.d0))), 1e-12)
        self.norm = float(np.sum(self.w) * np.sum(self.P[problem.white_patch] ** 2))

    def lit(self, d: np.ndarray) -> np.ndarray:
        """(n, 3) the lit chart for drive d: eq. 3, plus the fixed light where there is one."""
        return self.A @ d if self.fixed is None else self.A @ d + self.fixed

    def unpack(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return z[:3] * self.scale, z[3:].reshape(3, 3)

    def objective(self, z: np.ndarray) -> tuple[float, np.ndarray]:
        """Eq. 5 normalised by the white patch, and its exact gradient in z."""
        d, Q = self.unpack(z)
        A, w, norm = self.A, self.w, self.norm
        X = self.lit(d)  # (n, 3)
        R = X @ Q.T - self.P
        value = float(np.sum(w[:, None] * R * R)) / norm
        gQ = 2.0 * (R * w[:, None]).T @ X / norm
        gd = 2.0 * np.einsum("n,ni,nij->j", w, R @ Q, A) / norm
        return value, np.concatenate([gd * self.scale, gQ.ravel()])

    def delta_e(self, z: np.ndarray) -> float:
        """White-point CIEDE2000 of the stage light for drive z (1e3 where undefined)."""
        light = self.SL @ self.unpack(z)[0]
        if not float(self.matrix[1] @ light) > 0:
            return 1e3
        value = float(white_point_delta_e(light, self.baseline_light, camera_to_xyz=self.matrix))
        return value if np.isfinite(value) else 1e3

    def log_cond_margin(self, z: np.ndarray) -> float:
        # log keeps the scale sane; capped so a singular Q gives no inf - inf.
        cond = min(condition_number(self.unpack(z)[1]), 1e12)
        return float(np.log(self.max_condition) - np.log(cond))

    def limits(self, d: np.ndarray, Q: np.ndarray) -> dict[str, float]:
        return {
            "white_point_delta_e": float(self.delta_e(np.concatenate([d / self.scale, Q.ravel()]))),
            "drive_min": float(np.min(d)),
            "drive_max": float(np.max(d)),
            "cond_Q": condition_number(Q),
        }

    def feasible(self, values: dict[str, float]) -> bool:
        top = self.top
        return (
            values["white_point_delta_e"] <= self.max_delta_e + 1e-6
            and values["drive_min"] >= -_TOL * top
            and values["drive_max"] <= top * (1 + _TOL)
            and values["cond_Q"] <= self.max_condition * (1 + _TOL)
        )

    def constraints(self) -> list[dict]:
        """Luminance kept (eq.), white point and cond(Q) limits (ineq.); drive is a bound."""
        y_row, y0, scale = self.y_row, self.y0, self.scale
        return [
            {
                "type": "eq",
                "fun": lambda z: np.array([(float(y_row @ self.unpack(z)[0]) - y0) / y0]),
                "jac": lambda z: np.concatenate([y_row * scale / y0, np.zeros(9)])[None, :],
            },
            {
                "type": "ineq",
                "fun": lambda z: np.array([self.max_delta_e - self.delta_e(z)]),
                "jac": lambda z: -_forward_difference(self.delta_e, z, slice(0, 3)),
            },
            {
                "type": "ineq",
                "fun": lambda z: np.array([self.log_cond_margin(z)]),
                "jac": lambda z: _forward_difference(self.log_cond_margin, z, slice(3, 12)),
            },
        ]

    def active_limits(self, values: dict[str, float]) -> list[str]:
        """The limits the solution sits on."""
        active = []
        if values["white_point_delta_e"] >= self.max_delta_e * (1 - 1e-3) - 1e-9:
            active.append("white_point")
        if values["drive_min"] <= 1e-6 * self.top:
            active.append("drive_min")
        if values["drive_max"] >= self.top * (1 - 1e-6):
            active.append("drive_max")
        if values["cond_Q"] >= self.max_condition * (1 - 1e-3):
            active.append("cond_Q")
        return active


def _solve_joint(joint: _JointProblem, max_iterations: int, camera: str) -> QFit:
    """SLSQP from the sequential solution (M, least-squares Q); that one if nothing better."""
    # scipy is imported here, when a joint solve runs: the other methods do not need it.
    from scipy.optimize import minimize

    # The sequential Q as every method fits it: the chart lit by the drive the wall can emit.
    Q0 = fit_least_squares(joint.lit(np.clip(joint.d0, 0.0, None)), joint.P, joint.w)
    if not (joint.y0 > 0 and joint.top > 0):  # no visible baseline light: no white point to keep
        return _not_applied(Q0, NO_BASELINE, {"limits_met": False})
    top, scale = joint.top, joint.scale
    z0 = np.concatenate([joint.d0 / scale, Q0.ravel()])
    start_error = joint.objective(z0)[0]
    bounds = [(0.0, top / scale)] * 3 + [(None, None)] * 9
    z_init = z0.copy()
    z_init[:3] = np.clip(z_init[:3], 0.0, top / scale)  # SLSQP starts inside the bounds
    result = minimize(
        joint.objective,
        z_init,
        jac=True,
        method="SLSQP",
        bounds=bounds,
        constraints=joint.constraints(),
        options={"maxiter": max_iterations, "ftol": 1e-12},
    )
    d, Q = joint.unpack(result.x)
    start_limits = joint.limits(joint.d0, Q0)
    final_limits = joint.limits(d, Q)
    final_error = joint.objective(result.x)[0]
    start_ok = joint.feasible(start_limits)
    ok = np.all(np.isfinite(result.x)) and joint.feasible(final_limits)
    if ok and start_ok and final_error >= start_error * (1 - 1e-9):
        ok = False  # never worse than the sequential solve when that one is admissible
    notes = _joint_notes(joint, result, camera, start_error, start_limits)
    if not ok:
        reason = (
            "the sequential solution already meets the limits and the optimiser found "
            "nothing better"
            if start_ok
            else "no solution within the limits was found"
        )
        notes.update({"limits_met": start_ok, "lit_chart_error_eq5": start_error})
        return _not_applied(Q0, reason, notes)
    notes.update(
        {
            "joint_applied": True,
            "limits_met": True,
            "lit_chart_error_eq5": final_error,
            "lit_chart_error_reduction": 1.0 - final_error / start_error
            if start_error > 0
            else 0.0,
            "active_limits": joint.active_limits(final_limits),
            "drive": d.tolist(),
            **final_limits,
        }
    )
    return QFit(
        MatrixCorrection(Q),
        "joint",
        JOINT_DESCRIPTION,
        M=joint_matrix(joint.M, joint.w_avg, d),
        details=notes,
    )


def _not_applied(Q0: np.ndarray, reason: str, notes: dict) -> QFit:
    """The sequential solution, with why the joint one was not taken."""
    details = {"joint_applied": False, **notes, "lit_chart_error_reduction": 0.0}
    return QFit(
        MatrixCorrection(Q0),
        "joint",
        JOINT_DESCRIPTION,
        reason=reason,
        details=details | {"active_limits": []},
    )


def _joint_notes(
    joint: _JointProblem, result, camera: str, start_error: float, start_limits: dict
) -> dict:
    """What every joint fit reports: the limits, the convention, the sequential start, SLSQP."""
    return {
        "limits": {
            "max_white_point_delta_e2000": joint.max_delta_e,
            "drive_range": [0.0, joint.top],
            "max_cond_Q": joint.max_condition,
        },
        "scale_convention": "luminance of [SL] M' w_avg kept equal to the baseline's",
        "camera_to_xyz": camera,
        "sequential": {"lit_chart_error_eq5": start_error, **start_limits},
        "optimiser": {
            "method": "SLSQP",
            "iterations": int(result.nit),
            "success": bool(result.success),
            "message": str(result.message),
        },
    }


#: The registry's ``joint`` method: the defaults above, the sample camera's XYZ matrix.
q_joint = make_q_joint()
