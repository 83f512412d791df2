"""The tables of docs/stability.md, "Measured on the simulator": ``python -m benchmarks.stability_tables``.

1. On the noise-free paper stage, every environment of the simulator: the leave-one-patch-out
   mean ΔE2000 of each candidate `auto` weighs (from ``solution.json``'s method notes), what
   it picks and whether N is solved.
2. 0.5 % multiplicative Gaussian noise on every calibration sample ([SL] and every [SRL]_j),
   :data:`DRAWS` draws, the same draws for least squares and `auto`: the models chosen, the
   spread of N (RMS ``||N_i - mean N||_F / ||mean N||_F``) and the lit chart's error when each
   noisy solve (its M and its post-correction, the model itself) plays on the noise-free stage
   (mean absolute error relative to the target white, %, :func:`error_relative_to_white`).

Prints Markdown; about a minute on 2 cores.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from ocio_vp.calibration.equations import predict_lit_chart  # noqa: E402
from ocio_vp.calibration.geometry import stage_beta  # noqa: E402
from ocio_vp.metrics import error_relative_to_white  # noqa: E402
from ocio_vp.pipeline import solve_environment  # noqa: E402
from ocio_vp.simulator.data import ENVIRONMENTS  # noqa: E402
from ocio_vp.simulator.stage import paper_stage, simulate_measurements  # noqa: E402

CANDIDATES = ("identity", "diagonal", "regularised", "least-squares", "root-polynomial")
NOISY = ("high_pressure_sodium", "incandescent", "d65", "rgb_led_white")
DRAWS = 40
NOISE = 0.005


def _n_status(solution) -> str:
    if solution.N is None:
        return "no"
    return "= M" if np.allclose(solution.N, solution.M, rtol=1e-12, atol=0) else "solved"


def candidates_table(measurements) -> list[str]:
    rows = [
        "| environment | auto picks | N | " + " | ".join(CANDIDATES) + " |",
        "|---|---|---|" + "---|" * len(CANDIDATES),
    ]
    for environment in measurements.environments:
        solution = solve_environment(measurements, environment, method="auto")
        notes = solution.diagnostics.method_notes or {}
        cv = notes.get("cv_delta_e") or {}
        cells = [f"{cv[c]:.2f}" if c in cv else "-" for c in CANDIDATES]
        picks = solution.diagnostics.model
        if solution.correction.kind == "rank-deficient":
            picks = f"{picks} (no inverse)"
        rows.append(
            f"| {environment.name} | {picks} | {_n_status(solution)} | {' | '.join(cells)} |"
        )
    return rows


def _noisy(measurements, rng: np.random.Generator):
    SL = measurements.SL * (1.0 + NOISE * rng.standard_normal(measurements.SL.shape))
    SRL = measurements.SRL * (1.0 + NOISE * rng.standard_normal(measurements.SRL.shape))
    return dataclasses.replace(measurements, SL=SL, SRL=SRL)


def _lit_error(truth, environment, solution) -> float:
    """The noisy solve's M and post-correction played on the noise-free stage, in %."""
    lit = predict_lit_chart(truth.SRL, stage_beta(truth), solution.M, environment.w_avg)
    corrected = solution.correction.apply(lit)
    white = solution.diagnostics.white_patch
    return 100.0 * float(
        np.mean(error_relative_to_white(corrected, environment.target_chart, white))
    )


def noise_table(truth) -> list[str]:
    rows = [
        "| environment | method | models chosen | N spread | lit error on the true stage |",
        "|---|---|---|---|---|",
    ]
    for name in NOISY:
        environment = truth.environment(name)
        for method in ("least-squares", "auto"):
            rng = np.random.default_rng(0)  # the same draws for both methods
            models, Ns, errors = Counter(), [], []
            for _ in range(DRAWS):
                noisy = _noisy(truth, rng)
                solution = solve_environment(noisy, noisy.environment(name), method=method)
                models[solution.diagnostics.model] += 1
                if solution.N is not None:
                    Ns.append(np.asarray(solution.N))
                errors.append(_lit_error(truth, environment, solution))
            chosen = ", ".join(f"{m} x{k}" for m, k in models.most_common())
            spread = "-"
            if len(Ns) > 1:
                mean = np.mean(Ns, axis=0)
                rms = np.sqrt(np.mean([np.linalg.norm(N - mean) ** 2 for N in Ns]))
                spread = f"{100 * rms / np.linalg.norm(mean):.2f}%"
            rows.append(f"| {name} | {method} | {chosen} | {spread} | {np.mean(errors):.2f}% |")
    return rows


def main() -> int:
    start = time.perf_counter()
    truth = simulate_measurements(tuple(ENVIRONMENTS), stage=paper_stage())
    print("\n".join(candidates_table(truth)))
    print()
    print("\n".join(noise_table(truth)))
    print(f"\n_({time.perf_counter() - start:.0f} s)_")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
