"""The spectral predictor: what the simulated stage really produces for a solve.

The paper's "theory" column (eq. 3 done spectrally, LED drive clipped at 0 and reported, and
the in-frustum background with the panel bounce).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.calibration.equations import in_frustum_drive, predict_displayed_chart, solve_M
from ocio_vp.formats.solution import Solution
from ocio_vp.simulator.stage import (
    EnvironmentLight,
    SpectralStage,
    black_level_reading,
    camera_rgb,
    environment_spectrum,
)

__all__ = ["StagePrediction", "predict_solution", "predict_stage"]


@dataclass(frozen=True)
class StagePrediction:
    """The stage's real output for one environment and one set of matrices (camera RGB).

    ``lit`` (n, 3): the chart lit by the out-of-frustum wall (eq. 3 done spectrally, with the
    emitted drive ``drive_emitted = clip(M w_avg, 0)``); ``lit_corrected = Q lit``.
    ``displayed`` (n, 3): ``content`` shown in-frustum through N (or M) plus the offset,
    clipped to >= 0, seen by the camera plus the bounce ``black_level``; and
    ``displayed_corrected = Q displayed``. ``*_clipped`` say where drive was clipped.
    """

    target: np.ndarray
    lit: np.ndarray
    lit_corrected: np.ndarray
    displayed: np.ndarray
    displayed_corrected: np.ndarray
    drive: np.ndarray
    drive_emitted: np.ndarray
    lit_drive_clipped: bool
    displayed_drive_clipped: np.ndarray  # (n,) bool: any channel of that patch clipped
    black_level: np.ndarray | None


def predict_stage(
    stage: SpectralStage,
    environment: EnvironmentLight,
    *,
    M: ArrayLike,
    Q: ArrayLike | None = None,
    N: ArrayLike | None = None,
    offset: ArrayLike | None = None,
    content: ArrayLike | None = None,
) -> StagePrediction:
    """Predict the lit and the displayed chart for a solve, from the spectra (paper's theory).

    Lit chart: ``sum S R_j (L clip(M w_avg, 0))`` (eq. 3 with the LED drive the wall can
    emit), then ``Q``. Displayed chart: ``[SL] clip(N c + offset, 0) + b_camera`` (N = M when
    not given), then ``Q``; ``content`` c defaults to the true target chart (the background
    shows the scene as it was photographed). The true black level comes from the panel albedo
    under the emitted lighting.
    """
    M = np.asarray(M, dtype=np.float64)
    Q = np.eye(3) if Q is None else np.asarray(Q, dtype=np.float64)
    spectrum = environment_spectrum(stage, environment)
    target = camera_rgb(stage, stage.reflectances * spectrum)
    w_avg = camera_rgb(stage, spectrum)
    drive = M @ w_avg
    emitted = np.clip(drive, 0.0, None)
    lit = camera_rgb(stage, stage.reflectances * (stage.leds @ emitted))
    black = black_level_reading(stage, M, w_avg)
    c = target if content is None else np.asarray(content, dtype=np.float64)
    in_frustum = M if N is None else np.asarray(N, dtype=np.float64)
    in_drive = in_frustum_drive(c, matrix=in_frustum, offset=offset)
    displayed = predict_displayed_chart(
        c, SL=stage.SL, matrix=in_frustum, offset=offset, black_level=black
    )
    return StagePrediction(
        target=target,
        lit=lit,
        lit_corrected=lit @ Q.T,
        displayed=displayed,
        displayed_corrected=displayed @ Q.T,
        drive=drive,
        drive_emitted=emitted,
        lit_drive_clipped=bool(np.any(drive < 0)),
        displayed_drive_clipped=np.any(in_drive < 0, axis=-1),
        black_level=black,
    )


def predict_solution(
    stage: SpectralStage, environment: EnvironmentLight, solution: Solution
) -> StagePrediction:
    """:func:`predict_stage` for a solved :class:`~ocio_vp.formats.solution.Solution`.

    Uses its M (lighting), post-correction, in-frustum matrix (N, or M where N was not solved,
    in which case Q is *not* applied to the displayed chart: the wall stays as M shows it) and
    offset. A non-linear post-correction (``solution.correction``) is applied as the model
    itself, and in-frustum content goes through ``N(c) = M Q^-1(c)`` exactly, as the config's
    LUTs carry them (``solution.Q`` and ``solution.N`` are only their 3x3s).
    """
    args = {"M": solution.M, "Q": solution.Q, "offset": solution.in_frustum_offset}
    prediction = predict_stage(stage, environment, N=solution.in_frustum_matrix, **args)
    correction = solution.correction
    if not correction.linear:
        if solution.N is not None:
            content = correction.inverse(prediction.target)
            prediction = predict_stage(
                stage, environment, N=solve_M(solution.SL), content=content, **args
            )
        prediction = replace(
            prediction,
            lit_corrected=correction.apply(prediction.lit),
            displayed_corrected=correction.apply(prediction.displayed),
        )
    if solution.N is None:
        prediction = replace(prediction, displayed_corrected=prediction.displayed)
    return prediction
