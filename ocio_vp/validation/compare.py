"""Validation: the chart shown on the wall through its config, filmed, against what it should be.

Filmed and post-corrected, every patch should read its content ``c`` again (``Q([SL] M
Q^-1(c)) = c``, the paper's eqs. 7-8), judged in CIE ΔE2000 with the intended white patch as
reference white. Patches the wall cannot show (in-frustum light outside ``[0, 1]``) are listed
with the error the calibration itself expects there (:func:`expected_camera`) and left out of the
verdict: **pass** when the p95 over the shown patches is at most :data:`DEFAULT_THRESHOLD`.
What is compared and why: docs/validation.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.choices import DEFAULT_VALIDATION_THRESHOLD
from ocio_vp.errors import InputError
from ocio_vp.formats.solution import Solution
from ocio_vp.patterns.sequence import PatternSequence
from ocio_vp.patterns.validation import in_frustum_light
from ocio_vp.plates.take import TakeReading
from ocio_vp.wall.softclip import forward as soft_clip
from ocio_vp.wall.softclip import soft_clip_knee

__all__ = [
    "DEFAULT_THRESHOLD",
    "GAMUT_TOLERANCE",
    "PatchResult",
    "ValidationResult",
    "compare_take",
    "expected_camera",
    "in_frustum_light",
    "post_correct",
]

#: Pass when the 95th percentile of ΔE2000 over the shown patches is at most this.
DEFAULT_THRESHOLD = DEFAULT_VALIDATION_THRESHOLD
#: In-frustum light this far outside [0, 1] (fraction of full drive) counts as not shown.
GAMUT_TOLERANCE = 1e-3


def post_correct(solution: Solution) -> Callable[[np.ndarray], np.ndarray]:
    """The post-correction the solve prescribes for footage, as a function of camera RGB
    (``solution.correction``: the typed model, :mod:`ocio_vp.model`)."""
    return solution.correction.apply


def expected_camera(solution: Solution, light: np.ndarray) -> np.ndarray:
    """(n, 3) camera RGB the calibration itself predicts for in-frustum ``light``: the wall
    applies the solve's soft clip if it has one (``solve --soft-clip``), clips to [0, 1],
    [SL] films it, plus the bounce the offset was solved to cancel (``b = -[SL] offset`` for
    the exact offset, ``-offset w_camera`` for the paper's)."""
    knee = soft_clip_knee(solution.linearity)
    if knee is not None:
        light = soft_clip(light, knee)
    SL = np.asarray(solution.SL, dtype=np.float64)
    offset = solution.in_frustum_offset
    if solution.black_level_method == "paper":
        bounce = -offset * (SL @ np.ones(3))
    else:
        bounce = -(SL @ offset)
    return np.clip(light, 0.0, 1.0) @ SL.T + bounce


@dataclass(frozen=True)
class PatchResult:
    """One chart patch: intended and measured (post-corrected) camera RGB, and ΔE2000."""

    index: int
    name: str
    intended: np.ndarray
    measured: np.ndarray
    corrected: np.ndarray
    delta_e: float
    shown: bool
    frames: int
    expected_delta_e: float


@dataclass(frozen=True)
class ValidationResult:
    """The comparison over every chart patch, the statistics and the verdict."""

    environment: str
    stage: str
    patches: tuple[PatchResult, ...]
    threshold: float
    post_corrected: bool
    predicted_mean: float | None
    xyz_description: str
    display_matrix: np.ndarray

    @property
    def judged(self) -> tuple[PatchResult, ...]:
        return tuple(p for p in self.patches if p.shown)

    def _values(self) -> np.ndarray:
        return np.array([p.delta_e for p in self.judged])

    @property
    def mean(self) -> float:
        return float(np.mean(self._values()))

    @property
    def p95(self) -> float:
        return float(np.percentile(self._values(), 95))

    @property
    def worst(self) -> PatchResult:
        return max(self.judged, key=lambda p: p.delta_e)

    @property
    def passed(self) -> bool:
        return self.p95 <= self.threshold


def _predicted_mean(solution: Solution, xyz: np.ndarray, white: int) -> float | None:
    """Mean ΔE2000 the solve itself predicts for the chart shown in-frustum (its model)."""
    from ocio_vp.metrics import chart_errors

    charts = solution.diagnostics.charts
    if charts is None:
        return None
    shown, target = charts.displayed_corrected, charts.target
    if shown.shape != target.shape:
        return None
    return float(
        np.mean(chart_errors(shown, target, camera_to_xyz=xyz, white_patch=white).delta_E_2000)
    )


def compare_take(
    solution: Solution,
    sequence: PatternSequence,
    reading: TakeReading,
    *,
    threshold: float = DEFAULT_THRESHOLD,
) -> ValidationResult:
    """Compare a measured validation take with what the calibration intends (module docstring).

    Raises
    ------
    InputError
        When the sequence holds no chart, or every patch is outside the wall's range.
    """
    from ocio_vp.metrics import chart_errors, patch_label
    from ocio_vp.report.data import camera_to_display

    charts = sorted(sequence.of_kind("chart"), key=lambda p: p.index or 0)
    if not charts:
        raise InputError(
            "the sequence shows no chart: write it with ocio-vp patterns --validate",
            source=sequence.source,
        )
    intended = np.array([p.content for p in charts], dtype=np.float64)
    measured = np.array([reading.patches[p.name].mean for p in charts])
    corrected = post_correct(solution)(measured) if solution.N is not None else measured
    white = solution.diagnostics.white_patch
    white = white if 0 <= white < len(charts) else int(np.argmax(intended.sum(axis=1)))
    display = camera_to_display([solution], [intended])
    errors = chart_errors(
        corrected, intended, camera_to_xyz=display.camera_to_xyz, white_patch=white
    )
    light = in_frustum_light(solution, intended)
    shown = np.all((light >= -GAMUT_TOLERANCE) & (light <= 1 + GAMUT_TOLERANCE), axis=1)
    expected = expected_camera(solution, light)
    expected = post_correct(solution)(expected) if solution.N is not None else expected
    limit = chart_errors(expected, intended, camera_to_xyz=display.camera_to_xyz, white_patch=white)
    if not np.any(shown):
        raise InputError(
            "no chart patch is within the wall's range at this exposure", source=sequence.source
        )
    patches = tuple(
        PatchResult(
            index=int(p.index or 0),
            name=patch_label(j, len(charts)),
            intended=intended[j],
            measured=measured[j],
            corrected=corrected[j],
            delta_e=float(errors.delta_E_2000[j]),
            shown=bool(shown[j]),
            frames=len(reading.patches[p.name].frames),
            expected_delta_e=float(limit.delta_E_2000[j]),
        )
        for j, p in enumerate(charts)
    )
    return ValidationResult(
        environment=solution.environment,
        stage=solution.stage,
        patches=patches,
        threshold=float(threshold),
        post_corrected=solution.N is not None,
        predicted_mean=_predicted_mean(solution, display.camera_to_xyz, white),
        xyz_description=display.description,
        display_matrix=np.asarray(display.matrix, dtype=np.float64),
    )
