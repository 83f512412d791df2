"""How good a synthesized target is, measured on the spectral simulator.

For one environment spectrum E, Q is solved (paper eq. 5) from the *real* target (the chart
photographed under E) and from the *synthesized* one (``synthesize(w_avg)``), each against the
same noisy stage measurements (:func:`~ocio_vp.simulator.truth.noisy_measurements`, several
seeds), and judged on held-out reflectances by :func:`~ocio_vp.simulator.truth.held_out_errors`
(mean ΔE2000), M alone (Q = I) the baseline.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.correction.registry import QProblem, solve_post_correction
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.simulator.stage import SpectralStage, environment_spectrum, simulate_measurements
from ocio_vp.simulator.truth import held_out_errors, held_out_reflectances, noisy_measurements

__all__ = ["HeldOutStudy", "study_environment"]


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


def _one_seed(stage, clean, spectrum, synthesize, rng, noise, method, held_out):
    noisy = noisy_measurements(clean, noise[0], rng)
    env = noisy.environments[0]
    if noise[1] is not None:  # w_avg with its own noise level (0: a rendered HDRI)
        true = clean.environments[0].w_avg
        env = dataclasses.replace(env, w_avg=true * (1.0 + noise[1] * rng.standard_normal(3)))
    M = np.linalg.inv(noisy.SL)

    def mean_delta_E(Q):
        errors = held_out_errors(stage, spectrum, M=M, w_avg=env.w_avg, Q=Q, reflectances=held_out)
        return float(np.mean(errors.delta_E_2000))

    row = [mean_delta_E(np.eye(3))]
    for target in (env.target_chart, synthesize(env.w_avg)):
        problem = QProblem(
            SL=noisy.SL,
            SRL=noisy.SRL,
            beta=stage.beta,
            M=M,
            w_avg=env.w_avg,
            target=target,
            white_patch=stage.white_patch,
        )
        row.append(mean_delta_E(solve_post_correction(problem, method=method).Q))
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
    whose w_avg has no measurement error. ``held_out`` (k, W) defaults to the RAW to ACES
    training reflectances that are not on the chart
    (:func:`ocio_vp.simulator.truth.held_out_reflectances`).
    """
    spectrum = environment_spectrum(stage, environment)
    clean = simulate_measurements({"env": spectrum}, stage=stage)
    env = clean.environments[0]
    if held_out is None:
        held_out = held_out_reflectances(stage.chart_name)["rawtoaces"]
    to_xyz = camera_to_xyz_matrix(stage.camera)
    assert env.w_avg is not None  # the simulator measures it
    chart = chart_errors(synthesize(env.w_avg), env.target_chart, camera_to_xyz=to_xyz)
    rows = np.array(
        [
            _one_seed(
                stage,
                clean,
                spectrum,
                synthesize,
                np.random.default_rng(seed),
                (noise, w_avg_noise),
                method,
                held_out,
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
