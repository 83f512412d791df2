"""Judge solves against the simulated stage's spectral truth, and how noise moves them.

:func:`evaluate_solution` judges a solve on the spectra (the paper's "theory" column, from
:func:`ocio_vp.simulator.predict.predict_solution`); :func:`agreement_with_spectra` checks the
figures ``solve``/``demo`` print against it; :func:`noise_study` re-solves an
environment from measurements with multiplicative noise and reports how much N moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocio_vp.metrics import error_relative_to_white
from ocio_vp.simulator.data import ENVIRONMENTS
from ocio_vp.simulator.predict import predict_solution, predict_stage
from ocio_vp.simulator.stage import SpectralStage

__all__ = [
    "Evaluation",
    "NoiseStudy",
    "agreement_with_spectra",
    "evaluate_solution",
    "noise_study",
]


@dataclass(frozen=True)
class Evaluation:
    """One environment's solve judged on the spectral stage (errors relative to white, (3,)).

    ``lit_baseline``: chart lit through M alone; ``lit``: after Q (both with the LED drive the
    wall can emit). ``displayed_baseline``: the background through M with the panel bounce;
    ``displayed``: through N + offset, then Q (through M without Q where N was not solved).
    """

    environment: str
    broadband: bool | None
    method: str
    cond_Q: float
    N_solved: bool
    N_reason: str | None
    lit_baseline: np.ndarray
    lit: np.ndarray
    displayed_baseline: np.ndarray
    displayed: np.ndarray


def evaluate_solution(stage: SpectralStage, solution, environment=None) -> Evaluation:
    """Evaluate a :class:`~ocio_vp.formats.solution.Solution` on the stage it was simulated from.

    ``environment`` (name or spectrum) defaults to ``solution.environment`` as a known name.
    """
    env = solution.environment if environment is None else environment
    ours = predict_solution(stage, env, solution)
    baseline = predict_stage(stage, env, M=solution.M)
    white = stage.white_patch
    spec = ENVIRONMENTS.get(solution.environment) if isinstance(env, str) else None
    model = solution.model
    method = solution.method if model == solution.method else f"{solution.method}: {model}"
    return Evaluation(
        environment=solution.environment,
        broadband=None if spec is None else spec.broadband,
        method=method,
        cond_Q=np.nan if solution.diagnostics.cond_Q is None else solution.diagnostics.cond_Q,
        N_solved=solution.N is not None,
        N_reason=solution.diagnostics.N_reason,
        lit_baseline=error_relative_to_white(baseline.lit, ours.target, white),
        lit=error_relative_to_white(ours.lit_corrected, ours.target, white),
        displayed_baseline=error_relative_to_white(baseline.displayed, ours.target, white),
        displayed=error_relative_to_white(ours.displayed_corrected, ours.target, white),
    )


@dataclass(frozen=True)
class NoiseStudy:
    """How far N moves under noise: relative Frobenius change ``||N' - N|| / ||N||``."""

    environment: str
    noise: float
    trials: int
    cond_Q: float
    median: float
    p95: float
    maximum: float


def noise_study(
    measurements,
    environment: str,
    *,
    noise: float = 0.005,
    trials: int = 200,
    seed: int = 0,
    method: str = "least-squares",
) -> NoiseStudy:
    """Re-solve N with every measured sample multiplied by ``1 + noise * gauss`` (independent).

    All of [SL], [SRL]_j, the target chart and w_avg are perturbed, then M, Q (``method``) and
    ``N = M Q^-1`` (paper eqs. 2, 5, 8) are solved again with no conditioning limit, and
    compared with the noise-free N.
    """
    from ocio_vp.calibration.equations import condition_number, solve_M, solve_N
    from ocio_vp.calibration.geometry import environment_w_avg, stage_beta
    from ocio_vp.correction.registry import QProblem, solve_post_correction

    env = measurements.environment(environment)
    beta = stage_beta(measurements)
    white = measurements.stage.white_patch

    def solve(SL, SRL, target, w_avg):
        M = solve_M(SL)
        problem = QProblem(
            SL=SL, SRL=SRL, beta=beta, M=M, w_avg=w_avg, target=target, white_patch=white
        )
        Q = solve_post_correction(problem, method=method).Q
        N, _ = solve_N(M, Q, max_condition=np.inf)
        return Q, N

    clean = (
        measurements.SL,
        measurements.SRL,
        env.target_chart,
        environment_w_avg(measurements, env),
    )
    Q, N = solve(*clean)
    if N is None:
        raise ValueError(f"Q is singular for {environment!r}: N cannot be solved at all")
    rng = np.random.default_rng(seed)
    changes = []
    for _ in range(trials):
        noisy = [a * (1.0 + noise * rng.standard_normal(np.shape(a))) for a in clean]
        _, N_noisy = solve(*noisy)
        if N_noisy is None:
            changes.append(np.inf)
            continue
        changes.append(float(np.linalg.norm(N_noisy - N) / np.linalg.norm(N)))
    relative = np.array(changes)
    return NoiseStudy(
        environment=environment,
        noise=noise,
        trials=trials,
        cond_Q=condition_number(Q),
        median=float(np.median(relative)),
        p95=float(np.percentile(relative, 95)),
        maximum=float(np.max(relative)),
    )


def agreement_with_spectra(stage: SpectralStage, solutions) -> tuple[float, str]:
    """Largest |spectral truth - reported figure| (fraction of white, mean over R, G, B).

    The figures ``solve``, ``demo`` and the report print come from the measurements
    (:func:`~ocio_vp.calibration.diagnostics.summary_errors`); on a noise-free simulated stage
    they must match what the spectra predict. Returns the largest gap and where it is.
    """
    from ocio_vp.calibration.diagnostics import summary_errors

    worst, where = 0.0, "-"
    for solution in solutions:
        truth = evaluate_solution(stage, solution)
        figures = summary_errors(solution.diagnostics)
        # each spectral truth and the reported figure that estimates it from the measurements
        pairs = {
            "lit_baseline": (truth.lit_baseline, figures.lit_baseline),
            "lit": (truth.lit, figures.lit),
            "shown_baseline": (truth.displayed_baseline, figures.shown_baseline),
            "shown": (truth.displayed, figures.shown),
        }
        for key, (spectral, reported) in pairs.items():
            gap = abs(float(np.mean(spectral)) - float(np.mean(np.asarray(reported))))
            if gap >= worst:
                worst, where = gap, f"{solution.environment} {key}"
    return worst, where
