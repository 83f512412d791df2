"""``ocio-vp demo [--out DIR]``: the whole method on the built-in simulated stage.

Simulates the paper-like stage (Nikon 5100, 630/525/460 nm LEDs, ColorChecker, 1 m panel at
1 m, 4% panel albedo) under the paper's seven environments, solves them, writes
``DIR/<environment>/config.ocio`` + ``solution.json`` and ``DIR/paper_stage.yaml`` (the
measurements), and prints how well each environment is reproduced, judged on the spectra.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ocio_vp.commands.common import add_method_argument, progress
from ocio_vp.commands.solve import print_content_scale
from ocio_vp.commands.summary import print_summary
from ocio_vp.errors import InputError

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="simulate a stage under the paper's seven environments, solve, write configs",
        description="Run the whole method on the built-in simulated stage (no stage needed): "
        "writes DIR/<environment>/config.ocio and solution.json for the paper's seven "
        "environments and prints the errors the stage would really show.",
    )
    parser.add_argument("--out", default="demo_out", help="output folder")
    add_method_argument(parser)
    parser.add_argument("--no-report", action="store_true", help="skip the HTML report (faster)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import math
    import time

    from ocio_vp.ocio.writer import writer_pool
    from ocio_vp.simulator.data import PAPER_ENVIRONMENTS
    from ocio_vp.simulator.samples import SAMPLE_NAME
    from ocio_vp.staging import check_file_replaceable, check_replaceable

    start = time.perf_counter()
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError("exists and is not a folder", source=out, key="--out")
    # Every destination is checked before anything is written: all or nothing.
    for name in (*PAPER_ENVIRONMENTS, *(() if args.no_report else ("report",))):
        check_replaceable(out / name)
    check_file_replaceable(out / f"{SAMPLE_NAME}.yaml")
    # The writing helper starts first, so that its imports overlap loading and solving.
    with writer_pool(args.method) as pool:
        stage, written = _simulate_and_write(out, args.method, pool)
    print(
        f"simulated stage: {stage.camera_name}, {stage.led_description}, {stage.chart_name}, "
        f"beta {stage.beta:.5f}, panel albedo {stage.panel_albedo}; the camera exposed so the "
        f"wall's full white is {stage.wall_gain:g}x the location's white (content white "
        f"{math.log2(stage.wall_gain):.3g} stops below the wall's peak, as a stage engineer sets "
        "it up)"
    )
    print_summary(written)
    print(spectral_check(stage, written))
    print_content_scale(written)
    if not args.no_report:
        from ocio_vp.metrics import camera_to_xyz_matrix
        from ocio_vp.report.build import build_report

        # The simulated camera is known: its own camera-to-XYZ drives the report's colours and ΔE.
        with progress(total=len(written), desc="report", unit="environment") as bar:
            report = build_report(
                [out / s.environment for s in written],
                out / "report",
                camera_to_xyz=camera_to_xyz_matrix(stage.camera),
                on_step=lambda: bar.update(1),
            )
        print(f"report: {report.index} (open it in a browser)")
    print(
        f"wrote {len(written)} environments and {SAMPLE_NAME}.yaml to {out} "
        f"in {time.perf_counter() - start:.1f} s"
    )
    return 0


def _simulate_and_write(out, method: str, pool) -> tuple:
    """The paper-like stage, its seven environments solved and written to ``out``."""
    import tempfile

    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.simulator.samples import SAMPLE_NAME, simulate_and_solve
    from ocio_vp.simulator.stage import paper_stage
    from ocio_vp.staging import write_output_file

    stage = paper_stage()
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / f"{SAMPLE_NAME}.yaml"
        _, solutions = simulate_and_solve(scratch, method=method, stage=stage)
        try:
            written = write_solutions(solutions, out, pool=pool)
            write_output_file(out / scratch.name, scratch.read_bytes())
        except OSError as error:
            raise InputError(f"cannot write: {error.strerror}", source=out, key="--out") from None
    return stage, written


def spectral_check(stage, solutions) -> str:
    """How far the table's figures (from the measurements) are from the simulator's spectra."""
    from ocio_vp.simulator.evaluate import agreement_with_spectra

    worst, where = agreement_with_spectra(stage, solutions)
    # Below 1e-9 the gap is rounding (its digits differ between machines): printed as a bound.
    gap = f"{100 * worst:.2g}" if worst >= 1e-11 else "1e-9"
    return (
        f"checked on the simulated spectra: the table's figures agree within {gap} "
        f"percentage points (largest: {where})"
    )
