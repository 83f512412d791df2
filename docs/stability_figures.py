"""Regenerate the measured tables of docs/stability.md: ``python docs/stability_figures.py``.

Every number comes from ocio_vp itself on the spectral simulator (ocio_vp.simulator.stage) or on random
matrices; seeds are fixed so a re-run prints the same tables.
"""

from __future__ import annotations

import dataclasses
import time
from collections import Counter

import numpy as np

from ocio_vp.calibration.equations import condition_number, predict_lit_chart, solve_M, solve_N
from ocio_vp.metrics import error_relative_to_white
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.data import ENVIRONMENTS
from ocio_vp.simulator.stage import simulate_measurements

NOISE = 0.005
TRIALS = 40


def model_table(m) -> str:
    rows = [
        "| environment | auto picks | N | identity | diagonal | regularised | least-squares "
        "| root-polynomial |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for env in m.environments:
        t0 = time.perf_counter()
        s = solve_environment(m, env, method="auto")
        ms = 1000 * (time.perf_counter() - t0)
        cv = s.diagnostics.method_notes["cv_delta_e"]
        cells = [f"{cv[k]:.2f}" if k in cv else "-" for k in (
            "identity", "diagonal", "regularised", "least-squares", "root-polynomial")]  # fmt: skip
        n = "= M" if s.diagnostics.N_equals_M else ("solved" if s.N is not None else "no")
        rows.append(f"| {env.name} | {s.diagnostics.model} | {n} | " + " | ".join(cells) + " |")
    rows.append(f"\nOne `solve_environment(method='auto')` with its diagnostics: ~{ms:.0f} ms.")
    return "\n".join(rows)


def noise_table(m) -> str:
    rows = [
        "| environment | method | models chosen | N spread | lit error on the true stage |",
        "|---|---|---|---|---|",
    ]
    for name in ("high_pressure_sodium", "incandescent", "d65", "rgb_led_white"):
        env = m.environment(name)
        for method in ("least-squares", "auto"):
            rng = np.random.default_rng(11)
            Ns, models, errors = [], Counter(), []
            for _ in range(TRIALS):
                noisy = dataclasses.replace(
                    m,
                    SL=m.SL * (1 + NOISE * rng.standard_normal((3, 3))),
                    SRL=m.SRL * (1 + NOISE * rng.standard_normal(m.SRL.shape)),
                )
                s = solve_environment(noisy, env, method=method)
                Ns.append(s.in_frustum_matrix)
                models[s.diagnostics.model] += 1
                # The solve from noisy plates, played on the true stage (eq. 3 with true [SRL]).
                correct = s.correction.apply
                lit = correct(predict_lit_chart(m.SRL, s.beta, s.M, s.w_avg))
                errors.append(np.mean(error_relative_to_white(lit, env.target_chart)))
            Ns = np.array(Ns)
            spread = np.sqrt(np.mean(np.sum((Ns - Ns.mean(0)) ** 2, axis=(1, 2))))
            spread /= np.linalg.norm(Ns.mean(0))
            chosen = ", ".join(f"{k} x{v}" for k, v in models.most_common())
            rows.append(
                f"| {name} | {method} | {chosen} | {100 * spread:.2f}% | "
                f"{100 * np.mean(errors):.2f}% |"
            )
    return "\n".join(rows)


def identity_bound() -> str:
    rng = np.random.default_rng(1)
    eps = np.finfo(float).eps
    worst = {"via M then N Q = M": 0.0, "(Q [SL]) N = I": 0.0}

    def random_matrix(cond: float) -> np.ndarray:
        U, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        V, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        s = np.array([1.0, cond ** rng.uniform(0, 1), cond])
        return U @ np.diag(1 / s) @ V.T * 10 ** rng.uniform(-6, 4)

    for _ in range(20000):
        SL = random_matrix(10 ** rng.uniform(0, 8))
        Q = random_matrix(10 ** rng.uniform(0, 3))
        M = solve_M(SL)
        scale = eps * condition_number(Q) * condition_number(SL)
        for key, N in (
            ("via M then N Q = M", solve_N(M, Q)[0]),
            ("(Q [SL]) N = I", solve_N(M, Q, SL=SL)[0]),
        ):
            error = np.max(np.abs(Q @ SL @ N - np.eye(3)))
            worst[key] = max(worst[key], error / scale)
    return "\n".join(
        ["| N computed | max ‖Q[SL]N − I‖max / (eps cond(Q) cond([SL])) |", "|---|---|"]
        + [f"| {k} | {v:.2f} |" for k, v in worst.items()]
    )


if __name__ == "__main__":
    measurements = simulate_measurements(list(ENVIRONMENTS))
    print(model_table(measurements), end="\n\n")
    print(noise_table(measurements), end="\n\n")
    print(identity_bound())
