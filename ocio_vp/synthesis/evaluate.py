"""How good a synthesized target is, measured on the spectral simulator.

For one environment spectrum E on a :class:`~ocio_vp.simulator.stage.SpectralStage`:

- the *real* target is the chart photographed under E (``sum S R_j E``); the *synthesized* one
  is whatever ``synthesize(w_avg)`` returns from the environment's w_avg alone;
- with measurement noise (every measured value times ``1 + noise N(0, 1)``, independently, for
  [SL], [SRL]_j, the photographed chart and w_avg; several seeds), Q is solved (paper eq. 5) from
  each target against the same noisy stage measurements;
- each Q is judged on colours *not on the chart*: colour-science's 190 RAW to ACES training
  reflectances, lit by the wall as it really emits (``L clip(M w_avg, 0)``), post-corrected by
  Q and compared with the same reflectances under E (mean CIE ΔE2000 through the camera's
  fitted XYZ matrix, white = a perfect diffuser under E). M alone (Q = I) is the baseline.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.correction.registry import QProblem, solve_post_correction
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.simulator.stage import (
    SpectralStage,
    camera_rgb,
    environment_spectrum,
    simulate_measurements,
)
from ocio_vp.spectra import spectral_shape

__all__ = ["HeldOutStudy", "held_out_reflectances", "study_environment"]


def held_out_reflectances() -> np.ndarray:
    """(190, W) colour-science's RAW to ACES v1 training reflectances on the project's grid."""
    import colour

    data = colour.characterisation.read_training_data_rawtoaces_v1().copy().align(spectral_shape())
    return np.asarray(data.values, dtype=np.float64).T


@dataclass(frozen=True)
class HeldOutStudy:
    """Mean held-out ΔE2000 (over reflectances, then seeds) of M alone and of both Qs.

    ``chart_delta_E``: mean ΔE2000 of the noise-free synthesized chart against the real one.
    ``per_seed``: (seeds, 3) columns M only, Q real, Q synthesized.
    """

    environment: str
    chart_delta_E: float
    m_only: float
    q_real: float
    q_synthesized: float
    per_seed: np.ndarray
    noise: float

    @property
    def ratio(self) -> float:
        """Q from the synthesized chart over Q from the real chart (held-out mean ΔE2000)."""
        return self.q_synthesized / self.q_real


def _held_out_delta_E(stage, spectrum, drive, Q, reflectances, to_xyz) -> float:
    white = camera_rgb(stage, spectrum)
    target = np.vstack([camera_rgb(stage, reflectances * spectrum), white])
    lit = camera_rgb(stage, reflectances * (stage.leds @ np.clip(drive, 0.0, None)))
    predicted = np.vstack([lit @ np.asarray(Q).T, white])
    errors = chart_errors(predicted, target, camera_to_xyz=to_xyz, white_patch=-1)
    return float(np.mean(errors.delta_E_2000[:-1]))


def _one_seed(stage, truth, spectrum, synthesize, rng, noise, method, held_out, to_xyz):
    noises = (noise[0], noise[0], noise[0], noise[1])
    SL, SRL, real, w_avg = (
        a * (1.0 + n * rng.standard_normal(np.shape(a))) for a, n in zip(truth, noises, strict=True)
    )
    M = np.linalg.inv(SL)
    beta = stage.beta
    row = [_held_out_delta_E(stage, spectrum, M @ w_avg, np.eye(3), held_out, to_xyz)]
    for target in (real, synthesize(w_avg)):
        problem = QProblem(
            SL=SL,
            SRL=SRL,
            beta=beta,
            M=M,
            w_avg=w_avg,
            target=target,
            white_patch=stage.white_patch,
        )
        Q = solve_post_correction(problem, method=method).Q
        row.append(_held_out_delta_E(stage, spectrum, M @ w_avg, Q, held_out, to_xyz))
    return row


def study_environment(
    stage: SpectralStage,
    environment,
    synthesize: Callable[[np.ndarray], np.ndarray],
    *,
    name: str | None = None,
    noise: float = 0.005,
    w_avg_noise: float | None = None,
    seeds: int = 5,
    method: str = "least-squares",
    held_out: np.ndarray | None = None,
) -> HeldOutStudy:
    """Compare Q from the synthesized target with Q from the real chart (module docstring).

    ``environment`` is a simulator environment name, a colour ``SpectralDistribution`` or a
    (W,) spectrum; ``synthesize(w_avg) -> (n, 3)`` makes the target from camera-RGB w_avg.
    ``w_avg_noise`` (default ``noise``) is the noise on w_avg alone: 0 models a rendered HDRI,
    whose w_avg has no measurement error.
    """
    spectrum = environment_spectrum(stage, environment)
    measured = simulate_measurements({"env": spectrum}, stage=stage)
    env = measured.environments[0]
    truth = (measured.SL, measured.SRL, env.target_chart, env.w_avg)
    held_out = held_out_reflectances() if held_out is None else held_out
    to_xyz = camera_to_xyz_matrix(stage.camera)
    chart = chart_errors(synthesize(env.w_avg), env.target_chart, camera_to_xyz=to_xyz)
    rows = np.array(
        [
            _one_seed(
                stage,
                truth,
                spectrum,
                synthesize,
                np.random.default_rng(seed),
                (noise, noise if w_avg_noise is None else w_avg_noise),
                method,
                held_out,
                to_xyz,
            )
            for seed in range(seeds)
        ]
    )
    m_only, q_real, q_synth = rows.mean(axis=0)
    label = name if name is not None else (environment if isinstance(environment, str) else "?")
    return HeldOutStudy(
        environment=label,
        chart_delta_E=float(np.mean(chart.delta_E_2000)),
        m_only=float(m_only),
        q_real=float(q_real),
        q_synthesized=float(q_synth),
        per_seed=rows,
        noise=noise,
    )
