"""How long ``ocio-vp demo`` takes: the whole command, and step by step.

Target: the whole command, HTML report included, under about 3 s on 2 cores. The whole command
is timed as a user runs it (a fresh interpreter, imports included, Python's bytecode cache filled
as after the first run), with and without the report, interleaved; the steps are timed in this
process after the imports.

About half of those 3 s is starting Python and importing colour-science, numpy and OpenColorIO
(the *floor*: 1.45-1.6 s on a quiet 2-core machine here), and that half moves with the machine's
load: the same code measured 3.01 s and 3.20 s in two runs an hour apart, the floor 1.57 s and
1.83 s. So the target is judged, like every other one in docs/performance.md, side by side in
one run: each round times the demo and the floor, and the demo's own work (its time minus the
floor's, per round; median over rounds) must stay within 3 s - OWN_FLOOR. The absolute median
is printed next to it.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks import cached_bytecode, markdown_table


def _timed(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, float]:
    """Wall and CPU seconds of ``cmd`` (a fresh interpreter, run to completion) in ``env``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def _command(out: Path, report: bool, *extra: str, env=None) -> tuple[float, float]:
    """Wall and CPU seconds of ``python -m ocio_vp demo`` into a fresh ``out``."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-m", "ocio_vp", "demo", "--out", str(out), *extra]
    return _timed(cmd + ([] if report else ["--no-report"]), env)


#: The import floor of a quiet 2-core machine here (seconds): the target's 3 s less this is
#: the demo's own budget.
OWN_FLOOR = 1.5
#: What any run of the demo pays before its own work: colour-science 0.4.7 imports
#: matplotlib.pyplot and scipy from its ``__init__``; the simulator needs colour-science's data.
FLOOR = [sys.executable, "-c", "import colour, numpy, PyOpenColorIO"]


def whole_command(quick: bool) -> str:
    """Interleaved runs of the demo with and without its report, and of its import floor."""
    rounds = 1 if quick else 5
    runs: dict[bool | str | None, list[tuple[float, float]]] = {
        True: [], False: [], "least-squares": [], "no-cache": [], None: []
    }  # fmt: skip
    no_cache = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    with tempfile.TemporaryDirectory() as tmp, cached_bytecode() as env:
        _command(Path(tmp) / "warm", True, env=env)  # fills the bytecode cache
        _timed(FLOOR, env)
        load = os.getloadavg()[0]
        for _ in range(rounds):
            # The paper's 3x3 everywhere: what the default's root-polynomial LUT bakes cost.
            runs["least-squares"].append(
                _command(Path(tmp) / "ls", True, "--method", "least-squares", env=env)
            )
            for report in (True, False):
                runs[report].append(_command(Path(tmp) / "demo", report, env=env))
            runs["no-cache"].append(_command(Path(tmp) / "cold", True, env=no_cache))
            runs[None].append(_timed(FLOOR, env))
        load = (load + os.getloadavg()[0]) / 2
        # Accuracy of what the run produced: the paper's Fig. 11 lit-chart error (mean over
        # channels, relative to the target white), corrected, over the broadband environments.
        errors = {}
        for solution in sorted(Path(tmp, "demo").glob("*/solution.json")):
            diagnostics = json.loads(solution.read_text())["diagnostics"]
            errors[solution.parent.name] = 100 * statistics.fmean(diagnostics["lit_chart_error"])
    rows = []
    for report, label in (
        (True, "`ocio-vp demo` (with the HTML report)"),
        (False, "`ocio-vp demo --no-report`"),
        ("least-squares", "`ocio-vp demo --method least-squares` (the paper's 3x3, no LUT bakes)"),
        ("no-cache", "`ocio-vp demo`, Python caching no bytecode (`PYTHONDONTWRITEBYTECODE=1`)"),
        (None, "`python -c 'import colour, numpy, PyOpenColorIO'` (the floor: imports only)"),
    ):
        wall = statistics.median(w for w, _ in runs[report])
        cpu = statistics.median(c for _, c in runs[report])
        rows.append((label, f"{wall:.2f} s", f"{cpu:.2f} s"))
    total = statistics.median(w for w, _ in runs[True])
    floor = statistics.median(w for w, _ in runs[None])
    paper = statistics.median(w for w, _ in runs["least-squares"])
    cold = statistics.median(w for w, _ in runs["no-cache"])
    # Paired: each round's demo against the floor timed in the same round.
    pairs = list(zip(runs[True], runs[None], strict=True))
    own = statistics.median(demo - base for (demo, _), (base, _) in pairs)
    ratio = statistics.median(demo / base for (demo, _), (base, _) in pairs)
    verdict = "met" if own <= 3.0 - OWN_FLOOR else "**not met**"
    broadband = [v for k, v in errors.items() if k != "sodium_vapour"]
    return "\n".join(
        [
            markdown_table(
                ["command (fresh interpreter)", f"wall (median of {rounds})", "CPU"], rows
            ),
            "",
            f"- Whole demo with its report: **{total:.2f} s**. Of that, **{floor:.2f} s** "
            f"({100 * floor / total:.0f}%) is starting Python and importing colour-science, "
            f"numpy and OpenColorIO, which the demo cannot avoid (colour-science's own import "
            f"loads matplotlib and scipy); load average (1 min) during these runs {load:.1f} on "
            f"{os.cpu_count()} cores.",
            f"- Target about 3 s on 2 cores, judged side by side as every target here: the "
            f"demo's own work, report included (its time minus the floor's in the same round, "
            f"median over rounds), **{own:.2f} s** against 3 s less the {OWN_FLOOR:.1f} s floor "
            f"of a quiet machine: {verdict}; demo / floor {ratio:.2f}x in the same rounds. "
            f"Accuracy of the result: mean corrected lit-chart error "
            f"{statistics.fmean(broadband):.2f}% of white over the 6 broadband environments "
            f"(Fig. 11 metric, from the solution.json files the runs wrote; in-sample: the "
            f"chart Q was fitted on, so a check that the run worked, not an accuracy claim: "
            f"held-out colours are in docs/accuracy.md).",
            f"- With the paper's least squares everywhere the whole demo takes **{paper:.2f} s**: "
            f"the default's root-polynomial environments (each bakes Q and Q^-1 as 65^3 LUTs "
            f"into its config, checks them, and writes them as CLF text) cost the other "
            f"{total - paper:.2f} s, for a lower held-out ΔE2000 "
            f"(auto against least squares in docs/accuracy.md).",
            f"- Every command runs with Python's bytecode cache filled, as any run after the "
            f"first (the cache kept in a temporary folder). Where `PYTHONDONTWRITEBYTECODE=1` "
            f"is set, as on some CI machines, every run recompiles ocio_vp's modules: "
            f"{cold:.2f} s ({cold - total:+.2f} s).",
        ]
    )


def run(quick: bool = False) -> str:
    """Time the demo's steps in this process; returns a markdown section."""
    from ocio_vp.ocio.writer import writer_pool

    # As the demo does: the writing helper starts first and imports while colour-science does.
    with writer_pool() as pool:
        import colour  # noqa: F401  (imported before the steps are timed: "after imports")

        # In the demo the helper is ready by the time colour-science is imported (~1.5 s);
        # here colour-science may already be loaded, so wait for the helper's own imports.
        pool.submit(exec, "import ocio_vp.ocio.writer").result()
        rows, alone = _steps(pool)
    total = sum(seconds for _, seconds in rows)
    lines = [
        "## ocio-vp demo",
        "",
        whole_command(quick),
        "",
        "Steps of `ocio-vp demo` in one process (after imports), measured in this run. The "
        "demo writes the environments two at a time: a helper process bakes some "
        f"root-polynomial LUTs while the command bakes the others; writing them all in this "
        f"process alone takes {alone:.2f} s.",
        "",
        "| step | seconds | share |",
        "|---|---|---|",
    ]
    lines += [
        f"| {name} | {seconds:.2f} | {100 * seconds / total:.0f}% |" for name, seconds in rows
    ]
    lines.append(f"| **total** | **{total:.2f}** | 100% |")
    return "\n".join(lines) + "\n"


def _steps(pool) -> tuple[list[tuple[str, float]], float]:
    """(step, seconds) of the demo with the writing helper ``pool``, and the write step's
    seconds without it (the same solutions into another folder)."""
    from ocio_vp.metrics import camera_to_xyz_matrix
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.report.build import build_report
    from ocio_vp.simulator.evaluate import evaluate_solution
    from ocio_vp.simulator.samples import simulate_and_solve
    from ocio_vp.simulator.stage import paper_stage

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "demo_out"
        start = time.perf_counter()
        stage = paper_stage()
        t_stage = time.perf_counter()
        _, solutions = simulate_and_solve(Path(tmp) / "paper_stage.yaml", stage=stage)
        t_solve = time.perf_counter()
        written = write_solutions(solutions, out, pool=pool)
        t_write = time.perf_counter()
        for s in written:
            evaluate_solution(stage, s)
        t_eval = time.perf_counter()
        # The report, quick or not: its 16 SVG figures take a fraction of a second.
        camera_to_xyz = camera_to_xyz_matrix(stage.camera)
        t_report = time.perf_counter()
        build_report(
            [out / s.environment for s in written], out / "report", camera_to_xyz=camera_to_xyz
        )
        t_end = time.perf_counter()
        write_solutions(solutions, Path(tmp) / "alone")
        alone = time.perf_counter() - t_end
    rows = [
        ("build the spectral stage", t_stage - start),
        ("simulate, save, load, solve 7 environments", t_solve - t_stage),
        ("write 7 configs + solution.json (staged; with the helper)", t_write - t_solve),
        ("spectral evaluation (table)", t_eval - t_write),
        ("camera-to-XYZ matrix for the report", t_report - t_eval),
        ("HTML report (build_report: data, 16 SVG figures, page)", t_end - t_report),
    ]
    return rows, alone


if __name__ == "__main__":
    print(run())
