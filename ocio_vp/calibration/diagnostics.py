"""Numbers that tell a stage engineer whether a solve can be trusted.

Every function is pure (arrays in, arrays or plain numbers out) and never returns NaN or Inf for
finite input: a white patch with a dark channel is floored (see :func:`white_scale`) rather than
divided by zero.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, Fig. 11: mean absolute error per
channel relative to the target white patch, the metric used throughout ocio_vp's tables.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Protocol, TypedDict

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.calibration.equations import condition_number, in_frustum_drive, predict_lit_chart
from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.formats.diagnostics import ClippedCharts, Diagnostics, DriveRange, IdentityCheck
from ocio_vp.metrics import error_relative_to_white, patch_label, white_scale


class ChartProblem(Protocol):
    """The chart solve the diagnostics judge (a :class:`ocio_vp.correction.problem.QProblem`;
    ``correction/`` sits above this package)."""

    @property
    def SL(self) -> np.ndarray: ...
    @property
    def SRL(self) -> np.ndarray: ...
    @property
    def M(self) -> np.ndarray: ...
    @property
    def beta(self) -> float: ...
    @property
    def w_avg(self) -> np.ndarray: ...
    @property
    def target(self) -> np.ndarray: ...
    @property
    def white_patch(self) -> int: ...
    @property
    def extra_light(self) -> np.ndarray | None: ...

    @property
    def fit_weights(self) -> np.ndarray: ...


class FitReport(Protocol):
    """What a Q method reported (a :class:`ocio_vp.correction.problem.QFit`)."""

    @property
    def model(self) -> str: ...
    @property
    def reason(self) -> str | None: ...
    @property
    def cross_validated_error(self) -> np.ndarray | None: ...
    @property
    def target_rank(self) -> int | None: ...
    @property
    def warnings(self) -> tuple[str, ...]: ...


__all__ = [
    "ClippedDriveFields",
    "OutOfFrustumDrive",
    "StabilityFields",
    "SummaryErrors",
    "black_level_bounce",
    "clipped_drive_lit",
    "clipped_patches",
    "identity_check",
    "in_frustum_drive_range",
    "is_identity",
    "offset_is_negligible",
    "out_of_frustum_drive",
    "residuals_per_patch",
    "stability_diagnostics",
    "summary_errors",
]


def residuals_per_patch(
    predicted: ArrayLike,
    target: ArrayLike,
    white_patch: int = DEFAULT_WHITE_PATCH,
    weights: ArrayLike | None = None,
) -> np.ndarray:
    """(n, 3) signed residuals ``predicted - target`` relative to the target white."""
    predicted = np.asarray(predicted, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    return (predicted - target) / white_scale(target, white_patch, weights)


@dataclass(frozen=True)
class OutOfFrustumDrive:
    """The lighting drive ``M w_avg`` (eq. 3), its channels below zero and the drive the wall
    emits (clipped at 0)."""

    drive: np.ndarray
    negative_channels: list[int]
    clipped_drive: np.ndarray


class ClippedDriveFields(TypedDict):
    """The :class:`~ocio_vp.formats.diagnostics.Diagnostics` fields of the clipped drive."""

    charts_clipped_drive: ClippedCharts | None
    lit_chart_error_baseline_clipped_drive: np.ndarray | None
    lit_chart_error_clipped_drive: np.ndarray | None


class StabilityFields(ClippedDriveFields):
    """The stability fields of :class:`~ocio_vp.formats.diagnostics.Diagnostics`
    (:func:`stability_diagnostics`)."""

    model: str | None
    model_reason: str | None
    rank_target: int | None
    cross_validated_error: np.ndarray | None
    residuals_per_patch: np.ndarray
    out_of_frustum_negative_channels: list[int]
    in_frustum_drive_range: DriveRange
    black_level_bounce: np.ndarray | None
    clipped_patches: list[int]
    N_equals_M: bool
    identity_check: IdentityCheck | None


def out_of_frustum_drive(M: ArrayLike, w_avg: ArrayLike) -> OutOfFrustumDrive:
    """The lighting drive ``M w_avg`` (eq. 3) and the channels the wall cannot emit (< 0).

    A negative channel means the environment's light is outside the LED gamut: the wall clips
    it to 0 and the lit chart departs from eq. 3's prediction.
    """
    drive = np.asarray(M, dtype=np.float64) @ np.asarray(w_avg, dtype=np.float64)
    negative = [int(c) for c in np.flatnonzero(drive < 0)]
    return OutOfFrustumDrive(drive, negative, np.clip(drive, 0, None))


def in_frustum_drive_range(
    target: ArrayLike,
    *,
    M: ArrayLike,
    matrix: ArrayLike,
    offset: ArrayLike | None = None,
    white_patch: int = DEFAULT_WHITE_PATCH,
    max_drive: float = 1.0,
) -> DriveRange:
    """How many chart colours the in-frustum matrix would drive outside ``[0, max_drive]``.

    The chart (the target p_j, as background content) is first scaled so that its white patch
    through M peaks at ``max_drive`` (the brightest neutral the wall shows at that exposure);
    then each patch's drive ``matrix c + offset`` is checked per channel.
    """
    target = np.asarray(target, dtype=np.float64)
    M = np.asarray(M, dtype=np.float64)
    peak = float(np.max(M @ target[white_patch]))
    scale = max_drive / peak if peak > 0 else 1.0
    scaled_offset = None if offset is None else np.asarray(offset, dtype=np.float64) * scale
    drive = in_frustum_drive(target * scale, matrix=matrix, offset=scaled_offset)
    below = np.any(drive < 0, axis=1)
    above = np.any(drive > max_drive, axis=1)
    return DriveRange(
        below_zero=int(below.sum()),
        above_max=int(above.sum()),
        patches_outside=[int(j) for j in np.flatnonzero(below | above)],
        max_drive=max_drive,
        content_scale=scale,
    )


def black_level_bounce(black_level: ArrayLike, SL: ArrayLike) -> np.ndarray:
    """(3,) the panels' bounced light relative to the wall's white: ``b / ([SL] [1, 1, 1])``.

    This is the paper's Section 3.4 ratio ``b_camera / w_camera``: panel albedo times how
    bright the environment is relative to the wall's full white.
    """
    w_camera = np.asarray(SL, dtype=np.float64).sum(axis=1)
    w_camera = np.where(np.abs(w_camera) > 0, w_camera, 1.0)
    return np.asarray(black_level, dtype=np.float64) / w_camera


def clipped_patches(SRL: ArrayLike, target: ArrayLike, clip_level: float | None) -> list[int]:
    """Patches with any value (lit by any LED channel, or in the target) at ``clip_level``."""
    if clip_level is None:
        return []
    SRL = np.asarray(SRL, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    clipped = np.any(SRL >= clip_level, axis=(1, 2)) | np.any(target >= clip_level, axis=1)
    return [int(j) for j in np.flatnonzero(clipped)]


#: cond([SL]) above this earns a warning: an LED channel is almost dark or two look alike, so
#: 0.1 % noise in the primaries' plate moves M by more than 10 %.
WARN_CONDITION_SL = 1e2

#: ``||Q [SL] N - I||_max <= IDENTITY_BOUND_FACTOR * eps * cond(Q) * cond([SL])`` (see
#: :func:`ocio_vp.calibration.equations.solve_N` and docs/stability.md).
IDENTITY_BOUND_FACTOR = 32.0


def identity_check(Q: ArrayLike, SL: ArrayLike, N: ArrayLike | None) -> IdentityCheck | None:
    """How exactly eq. 7, ``Q [SL] N = I``, holds, against its rounding-error bound."""
    if N is None:
        return None
    Q, SL, N = (np.asarray(a, dtype=np.float64) for a in (Q, SL, N))
    error = float(np.max(np.abs(Q @ SL @ N - np.eye(3))))
    bound = IDENTITY_BOUND_FACTOR * np.finfo(np.float64).eps
    bound *= condition_number(Q) * condition_number(SL)
    return IdentityCheck(max_abs_error=error, bound=float(bound))


def clipped_drive_lit(
    problem: ChartProblem, Q: ArrayLike, drive: OutOfFrustumDrive
) -> ClippedDriveFields:
    """The lit chart as the wall really lights it when ``M w_avg`` has a negative channel.

    The wall cannot emit negative light: it clips the drive to 0, so the chart is lit by eq. 3
    with ``clip(M w_avg, 0)``. Returns the diagnostics keys ``charts_clipped_drive``
    (``lit_baseline`` and ``lit_corrected`` = ``lit_baseline @ Q.T``, (n, 3) each),
    ``lit_chart_error_baseline_clipped_drive`` and ``lit_chart_error_clipped_drive``; all None
    when the drive is not clipped (the eq. 3 charts are then what the wall shows).
    """
    if not drive.negative_channels:
        return ClippedDriveFields(
            charts_clipped_drive=None,
            lit_chart_error_baseline_clipped_drive=None,
            lit_chart_error_clipped_drive=None,
        )
    lit = predict_lit_chart(problem.SRL, problem.beta, np.eye(3), drive.clipped_drive)
    if problem.extra_light is not None:  # the stage's other panel types
        lit = lit + problem.extra_light
    charts = ClippedCharts(lit_baseline=lit, lit_corrected=lit @ np.asarray(Q, dtype=np.float64).T)
    args = (problem.target, problem.white_patch, problem.fit_weights)
    return ClippedDriveFields(
        charts_clipped_drive=charts,
        lit_chart_error_baseline_clipped_drive=error_relative_to_white(lit, *args),
        lit_chart_error_clipped_drive=error_relative_to_white(charts.lit_corrected, *args),
    )


def stability_diagnostics(
    problem: ChartProblem,
    fit: FitReport,
    *,
    method: str,
    M: np.ndarray,
    Q: np.ndarray,
    N: np.ndarray | None,
    offset: np.ndarray | None,
    black_level: np.ndarray | None,
    corrected: np.ndarray,
    clipped: list[int],
    cross_validated: np.ndarray | None = None,
) -> tuple[StabilityFields, list[str]]:
    """The stability part of ``solution.json`` diagnostics, and the warnings it raises.

    Keys: ``model`` and ``model_reason`` (what was fitted and why), ``cond_SL`` warnings,
    ``rank_target``, ``cross_validated_error`` (per channel, leave one patch out: the fit's own
    or ``cross_validated``),
    ``residuals_per_patch`` (n, 3, white-relative), ``out_of_frustum_negative_channels``,
    ``lit_chart_error[_baseline]_clipped_drive`` and ``charts_clipped_drive`` (clipped drive),
    ``in_frustum_drive_range``, ``black_level_bounce``, ``clipped_patches``,
    ``N_equals_M`` and ``identity_check``.
    """
    target = np.asarray(problem.target, dtype=np.float64)
    white, weights = problem.white_patch, problem.fit_weights
    warnings: list[str] = [str(w) for w in fit.warnings]  # the method's own
    cv = cross_validated if fit.cross_validated_error is None else fit.cross_validated_error
    drive = out_of_frustum_drive(M, problem.w_avg)
    in_matrix = M if N is None else N
    in_range = in_frustum_drive_range(
        target, M=problem.M, matrix=in_matrix, offset=offset, white_patch=white
    )
    in_range_M = in_frustum_drive_range(
        target, M=problem.M, matrix=problem.M, offset=offset, white_patch=white
    )
    in_range = dataclasses.replace(
        in_range, below_zero_with_M=in_range_M.below_zero, above_max_with_M=in_range_M.above_max
    )
    cond_SL = condition_number(problem.SL)
    if not cond_SL <= WARN_CONDITION_SL:
        warnings.append(
            f"cond([SL]) = {cond_SL:.3g}: an LED channel is almost dark or two primaries look "
            "alike to the camera; M (and N) amplify noise in the primaries' plate by this factor"
        )
    if clipped:
        warnings.append(
            f"{len(clipped)} chart patch(es) clipped and left out of the fit: "
            + ", ".join(patch_label(j, len(target)) for j in clipped)
            + "; shoot the chart plates darker to use them"
        )
    # Chart colours N drives below zero are a fact of the LEDs' gamut, not a warning: the
    # terminal names them as a note from ``in_frustum_drive_range`` (commands/summary.py).
    block = StabilityFields(
        **clipped_drive_lit(problem, Q, drive),
        model=fit.model or method,
        model_reason=fit.reason,
        rank_target=fit.target_rank,
        # None for an iterative method that does not report its own leave-one-out error:
        # re-solving it once per patch would multiply the solve time by n.
        cross_validated_error=None if cv is None else np.asarray(cv, dtype=np.float64),
        residuals_per_patch=residuals_per_patch(corrected, target, white, weights),
        out_of_frustum_negative_channels=drive.negative_channels,
        in_frustum_drive_range=in_range,
        black_level_bounce=None
        if black_level is None
        else black_level_bounce(black_level, problem.SL),
        clipped_patches=clipped,
        N_equals_M=N is not None and bool(np.array_equal(N, M)),
        identity_check=identity_check(Q, problem.SL, N),
    )
    return block, warnings


@dataclass(frozen=True)
class SummaryErrors:
    """The per-channel errors (relative to white, (3,)) every table shows (:func:`summary_errors`):
    ``lit_baseline``/``lit``: the chart lit by the wall through M alone / after Q, with the
    drive the wall can emit; ``shown_baseline``/``shown``: the in-frustum background through M
    / through N, the offset and Q; ``cross_validated``: leave-one-patch-out after Q (None when
    the method does not give it). None where an older file lacks one."""

    lit_baseline: np.ndarray | None
    lit: np.ndarray | None
    shown_baseline: np.ndarray | None
    shown: np.ndarray | None
    cross_validated: np.ndarray | None


def summary_errors(diagnostics: Diagnostics) -> SummaryErrors:
    """The errors ``solve``, ``demo`` and the report all show, so one environment shows one
    set of numbers: where ``M w_avg`` has a negative channel the wall clips it to 0, and the
    clipped-drive lit-chart errors are the ones shown."""
    d = diagnostics
    clipped = d.lit_chart_error_clipped_drive is not None
    baseline = d.lit_chart_error_baseline_clipped_drive if clipped else None
    return SummaryErrors(
        lit_baseline=d.lit_chart_error_baseline if baseline is None else baseline,
        lit=d.lit_chart_error_clipped_drive if clipped else d.lit_chart_error,
        shown_baseline=d.displayed_chart_error_baseline,
        shown=d.displayed_chart_error,
        cross_validated=d.cross_validated_error,
    )


#: A black-level offset whose light ``[SL] offset`` stays below this fraction of the wall's
#: white ``[SL] [1, 1, 1]`` is left out of the OCIO config (kept in solution.json): 1e-5 of
#: full white is under half a code value of a 16-bit linear signal.
NEGLIGIBLE_OFFSET = 1e-5


def offset_is_negligible(offset: ArrayLike | None, SL: ArrayLike) -> bool:
    """True when an in-frustum drive offset cannot be seen (see :data:`NEGLIGIBLE_OFFSET`)."""
    if offset is None:
        return True
    SL = np.asarray(SL, dtype=np.float64)
    seen = np.abs(SL @ np.asarray(offset, dtype=np.float64))
    return bool(np.max(seen) <= NEGLIGIBLE_OFFSET * np.max(np.abs(SL.sum(axis=1))))


def is_identity(Q: ArrayLike) -> bool:
    """True when Q is exactly the identity (``auto``'s identity model, or ``method="identity"``)."""
    return bool(np.array_equal(np.asarray(Q, dtype=np.float64), np.eye(3)))
