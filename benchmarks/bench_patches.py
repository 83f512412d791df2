"""Solve time against the number of chart patches, for every Q method of the registry.

Charts of 24 (ColorChecker), 140 (ColorChecker SG), 288 (IT8-like) and 1000 patches are made
from the simulator's direct-sun chart: each patch a copy of one of the 24 with its own 0.5 %
noise on every value. Each method is solved through ``ocio_vp.pipeline.solve_environment`` (with
patch screening and the closed-form leave-one-out diagnostics), timed with the median of a few
runs. Accuracy column: the solve's own leave-one-out error (% of white), so a fast wrong solve
would show. Iterative methods (perceptual, joint) are timed up to 288 patches in ``--quick``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time

SIZES = (24, 140, 288, 1000)
ITERATIVE = ("perceptual", "joint")


def _chart(n: int):
    from ocio_vp.simulator.stage import simulate_measurements

    m = simulate_measurements(["direct_sun"])
    rng = np.random.default_rng(n)
    index = np.arange(n) % 24
    SRL = m.SRL[index] * (1 + 0.005 * rng.standard_normal((n, 3, 3)))
    env = m.environments[0]
    target = env.target_chart[index] * (1 + 0.005 * rng.standard_normal((n, 3)))
    env = dataclasses.replace(env, target_chart=target)
    return dataclasses.replace(m, SRL=SRL, environments=(env,)), env


def run(quick: bool = False) -> str:
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.pipeline import solve_environment

    rows = []
    for method in Q_SOLVE_METHODS:
        cells = []
        for n in SIZES:
            if method in ITERATIVE and quick and n > 288:
                cells.append("-")
                continue
            m, env = _chart(n)
            seconds = median_time(
                lambda m=m, env=env, method=method: solve_environment(m, env, method=method),
                repeats=1 if method in ITERATIVE else 3,
                warmup=0 if method in ITERATIVE else 1,
            )
            s = solve_environment(m, env, method=method)
            cv = s.diagnostics.cross_validated_error
            accuracy = "" if cv is None else f" ({100 * float(np.mean(cv)):.2f}%)"
            cells.append(fmt_ms(seconds) + accuracy)
        rows.append((f"`{method}`", *cells))
    return "\n".join(
        [
            "## Solve time against the number of chart patches",
            "",
            __doc__.split("\n\n", 1)[1].strip(),
            "",
            markdown_table(["method", *[f"{n} patches" for n in SIZES]], rows),
        ]
    )
