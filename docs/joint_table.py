"""The tables of docs/joint.md: ``joint`` against ``least-squares`` on the simulator.

Regenerate with ``python docs/joint_table.py`` (tests/test_correction_joint.py checks the
docs still match).
"""

from __future__ import annotations

import numpy as np

from ocio_vp.calibration.geometry import stage_beta
from ocio_vp.correction.joint import make_q_joint
from ocio_vp.correction.linear import fit_least_squares
from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.simulator.data import ENVIRONMENTS, PAPER_ENVIRONMENTS
from ocio_vp.simulator.predict import predict_stage
from ocio_vp.simulator.stage import paper_stage, simulate_measurements


def _change(before: float, after: float) -> str:
    return "n/a (both ~0)" if before < 1e-6 else f"{100 * (after / before - 1):+.2f}%"


def comparison_table(
    environments: tuple[str, ...] | None = None,
    *,
    settings: tuple[tuple[float, float], ...] = ((1.0, 1.0), (2.0, 1.0), (4.0, 1.2)),
) -> str:
    """Markdown tables for docs/joint.md: ``joint`` against ``least-squares`` on the simulator.

    Errors are of the chart the simulated stage *really* lights (:func:`ocio_vp.simulator.stage.
    predict_stage`, spectra of :func:`ocio_vp.simulator.stage.paper_stage`), as mean CIEDE2000
    (:func:`ocio_vp.metrics.chart_errors` with the stage camera's own XYZ matrix). The first
    table uses the defaults; the second sweeps ``(max_delta_e, max_drive / baseline)`` over the
    broadband environments.
    """
    stage = paper_stage()
    names = tuple(environments or PAPER_ENVIRONMENTS)
    m = simulate_measurements(names, stage=stage)
    xyz = camera_to_xyz_matrix(stage.camera)
    M = np.linalg.inv(m.SL)

    def mean_de(name: str, M_: np.ndarray, Q: np.ndarray) -> float:
        truth = predict_stage(stage, name, M=M_, Q=Q)
        return float(
            chart_errors(truth.lit_corrected, truth.target, camera_to_xyz=xyz).delta_E_2000.mean()
        )

    def solve(env, method) -> tuple[QFit, float, float]:
        problem = QProblem(m.SL, m.SRL, stage_beta(m), M, env.w_avg, env.target_chart)
        fit = method(problem)
        seq = fit_least_squares(problem.predicted, problem.target, problem.fit_weights)
        joint_M = M if fit.M is None else fit.M
        return fit, mean_de(env.name, M, seq), mean_de(env.name, joint_M, fit.Q)

    head = "| environment | broadband | ΔE2000 least-squares | ΔE2000 joint | change | eq. 5 error change | white point ΔE2000 | drive (limit) | cond(Q) | active limits |"
    lines = [head, "|" + "---|" * 10]
    for env in m.environments:
        fit, de_seq, de_joint = solve(env, make_q_joint(camera_to_xyz=xyz))
        n = fit.notes
        applied = n["joint_applied"]
        d = np.asarray(n["drive"]) if applied else M @ env.w_avg
        top = n["limits"]["drive_range"][1]
        lines.append(
            f"| {env.name} | {'yes' if ENVIRONMENTS[env.name].broadband else 'no'} "
            f"| {de_seq:.3f} | {de_joint:.3f} | {_change(de_seq, de_joint)} "
            f"| {-100 * n['lit_chart_error_reduction']:+.2f}% "
            f"| {n.get('white_point_delta_e', 0.0):.2f} "
            f"| {d.min():.3f}..{d.max():.3f} ({top:.3f}) | {n.get('cond_Q', n['sequential']['cond_Q']):.3g} "
            f"| {', '.join(n['active_limits']) if applied else 'not applied: ' + n['reason']} |"
        )
    broadband = [e for e in m.environments if ENVIRONMENTS[e.name].broadband]
    sweep = [
        "| max white-point ΔE2000 | max drive / baseline | mean ΔE2000 least-squares | mean ΔE2000 joint | change |",
        "|---|---|---|---|---|",
    ]
    for max_de, drive_factor in settings:
        seq_all, joint_all = [], []
        for env in broadband:
            top = drive_factor * float(np.max(M @ env.w_avg))
            method = make_q_joint(camera_to_xyz=xyz, max_delta_e=max_de, max_drive=top)
            _, de_seq, de_joint = solve(env, method)
            seq_all.append(de_seq)
            joint_all.append(de_joint)
        a, b = float(np.mean(seq_all)), float(np.mean(joint_all))
        sweep.append(
            f"| {max_de:g} | {drive_factor:g} | {a:.3f} | {b:.3f} | {100 * (b / a - 1):+.2f}% |"
        )
    return "\n".join(lines) + "\n\n" + "\n".join(sweep) + "\n"


if __name__ == "__main__":
    print(comparison_table(), end="")
