"""Q-solve methods: solve time vs the lit chart's colour error on the simulator's environments.

For every method of ``Q_SOLVE_METHODS`` (plus the perceptual solve on ΔE ITP) and every sample
environment of :func:`ocio_vp.simulator.stage.paper_stage_measurements` (spectral ground truth), the
corrected lit chart ``Q x_j`` (eq. 3 and 5 of the paper, through the method's own M when it
returns one) is compared with the target chart: mean ΔE2000 and ΔE ITP through
:func:`ocio_vp.metrics.chart_errors` with the simulated camera's XYZ matrix, and the paper's
error relative to white (Fig. 11).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time


def run(quick: bool = False) -> str:
    from ocio_vp.correction.perceptual import make_q_perceptual
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
    from ocio_vp.pipeline import post_correction_problem
    from ocio_vp.simulator.stage import paper_stage, paper_stage_measurements

    stage = paper_stage()
    measurements = paper_stage_measurements()
    matrix = camera_to_xyz_matrix(stage.camera)
    # The problem as the solve poses it (M = [SL]^-1, beta, w_avg, the target; no clipping).
    problems = {
        env.name: post_correction_problem(measurements, env) for env in measurements.environments
    }
    methods = dict(Q_SOLVE_METHODS)
    methods["perceptual (ΔE ITP)"] = make_q_perceptual(metric="ITP")
    repeats = 1 if quick else 3
    broadband = [n for n in problems if n != "sodium_vapour"]
    rows, per_env = [], {}
    for name, solver in methods.items():
        times, de2000, itp, rel = [], {}, {}, {}
        for env, problem in problems.items():
            times.append(median_time(lambda s=solver, p=problem: s(p), repeats=repeats, warmup=0))
            fit = solver(problem)
            lit = problem if fit.M is None else dataclasses.replace(problem, M=fit.M)
            corrected = lit.predicted @ np.asarray(fit.Q).T
            errors = chart_errors(corrected, problem.target, camera_to_xyz=matrix)
            de2000[env] = float(errors.delta_E_2000.mean())
            itp[env] = float(errors.delta_E_ITP.mean())
            rel[env] = float(errors.relative_to_white.mean())
        per_env[name] = de2000
        rows.append(
            (
                f"`{name}`",
                fmt_ms(float(np.median(times))),
                fmt_ms(float(np.max(times))),
                f"{np.mean([de2000[e] for e in broadband]):.2f}",
                f"{np.mean([itp[e] for e in broadband]):.2f}",
                f"{100 * np.mean([rel[e] for e in broadband]):.2f}%",
            )
        )
    baseline_rows = []
    for problem in problems.values():
        errors = chart_errors(problem.predicted, problem.target, camera_to_xyz=matrix)
        baseline_rows.append(float(errors.delta_E_2000.mean()))
    env_table = markdown_table(
        ["method", *problems],
        [("M only (no Q)", *[f"{v:.2f}" for v in baseline_rows])]
        + [(f"`{m}`", *[f"{per_env[m][e]:.2f}" for e in problems]) for m in methods],
    )
    return "\n".join(
        [
            "## Q-solve methods: time vs lit-chart colour error",
            "",
            f"{len(problems)} simulated environments of the paper stage (Nikon 5100 (NPL) "
            "sensitivities, 630/525/460 nm LEDs, ColorChecker N Ohta). Time: one Q solve "
            f"(median of {repeats} per environment, then median / max over environments); "
            "`auto` and `regularised` include their cross-validation. Errors: mean over the "
            f"{len(broadband)} broadband environments (low-pressure sodium is rank 1 and listed "
            "only per environment below).",
            "",
            markdown_table(
                [
                    "method",
                    "median time",
                    "max time",
                    "mean ΔE2000",
                    "mean ΔE ITP",
                    "error rel. to white (Fig. 11)",
                ],
                rows,
            ),
            "",
            "Mean ΔE2000 of the corrected lit chart per environment:",
            "",
            env_table,
        ]
    )
