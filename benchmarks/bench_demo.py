"""How long ``ocio-vp demo`` takes, step by step (target: under 30 s on 2 cores)."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path


def run(quick: bool = False) -> str:
    """Time the demo's steps in this process; returns a markdown section."""
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.simulator.evaluate import evaluate_solution
    from ocio_vp.simulator.samples import simulate_and_solve
    from ocio_vp.simulator.stage import paper_stage

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "demo_out"
        start = time.perf_counter()
        stage = paper_stage()
        t_stage = time.perf_counter()
        _, solutions = simulate_and_solve(Path(tmp) / "paper_stage.yaml", stage=stage)
        t_solve = time.perf_counter()
        written = write_solutions(solutions, out)
        t_write = time.perf_counter()
        for s in written:
            evaluate_solution(stage, s)
        t_eval = time.perf_counter()
        rows += [
            ("build the spectral stage", t_stage - start),
            ("simulate, save, load, solve 7 environments", t_solve - t_stage),
            ("write 7 configs + solution.json (staged)", t_write - t_solve),
            ("spectral evaluation (table)", t_eval - t_write),
        ]
        if not quick:
            from ocio_vp.metrics import camera_to_xyz_matrix
            from ocio_vp.report.build import build_report

            build_report(
                [out / s.environment for s in written],
                out / "report",
                camera_to_xyz=camera_to_xyz_matrix(stage.camera),
            )
            rows.append(("HTML report", time.perf_counter() - t_eval))
    total = sum(seconds for _, seconds in rows)
    lines = [
        "## ocio-vp demo",
        "",
        "Steps of `ocio-vp demo` in one process (after imports), measured in this run. "
        "Target: the whole command under 30 s on 2 cores.",
        "",
        "| step | seconds | share |",
        "|---|---|---|",
    ]
    lines += [
        f"| {name} | {seconds:.2f} | {100 * seconds / total:.0f}% |" for name, seconds in rows
    ]
    lines.append(f"| **total** | **{total:.2f}** | 100% |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(run())
