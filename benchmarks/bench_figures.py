"""One way to draw figures: the report's SVG writer against matplotlib, side by side.

    python -m benchmarks.bench_figures --out docs/report.md

The demo's seven environments are solved once; then, in each round and in turn, the report's
16 figures (two Fig. 11 error-bar charts, and per environment the comparison charts, the
per-patch ΔE and, where measured, the panel linearity) are drawn by

- ``svg writer``: :mod:`ocio_vp.report.plots` (what ``ocio-vp report`` uses);
- ``matplotlib Agg``: :mod:`benchmarks.report_matplotlib` (the same figures as ocio_vp drew
  them with matplotlib before the SVG writer), PNG files;
- ``matplotlib SVG``: the same, through matplotlib's SVG backend.

Then the take's contact sheet (``ocio-vp measure``, ``ocio-vp validate``) of a simulated take
(the default calibration sequence filmed at 25 fps, 96x54 pixels: the sheet's cost is its
frames, not their size), drawn in turn by :mod:`ocio_vp.plates.contact_sheet` (SVG writer)
and :mod:`benchmarks.contact_sheet_matplotlib` (matplotlib Agg, as before).

Each row gives the median over the rounds and its ratio to the SVG writer's time in the same
rounds. Everything is drawn once before timing (matplotlib's import and first layout are a
separate row, measured in a fresh interpreter).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: ``benchmarks.run`` puts this section into docs/<SECTION_OF>.
SECTION_OF = "report.md"
HEADING = "## Figures: the SVG writer against matplotlib"

_IMPORT = (
    "import time; t = time.perf_counter(); "
    "from matplotlib.figure import Figure; from matplotlib.backends.backend_agg import "
    "FigureCanvasAgg; print(time.perf_counter() - t)"
)


def _solutions(folder: Path) -> Path:
    import contextlib
    import io

    from ocio_vp.cli import main

    out = folder / "demo"
    with contextlib.redirect_stdout(io.StringIO()):  # the demo's table: not this benchmark's
        code = main(["demo", "--out", str(out), "--no-report"])
    if code != 0:
        raise RuntimeError("ocio-vp demo failed")
    return out


def _draw(module, environments, curves, folder: Path, ext: str) -> int:
    count = 0
    for kind in ("lit", "displayed"):
        module.plot_error_bars(environments, kind, folder / f"error_{kind}.{ext}")
        count += 1
    for data in environments:
        module.plot_comparison_charts(data, folder / f"{data.key}-charts.{ext}")
        module.plot_delta_e(data, folder / f"{data.key}-delta_e.{ext}")
        count += 2
        if curves[data.key]:
            module.plot_linearity(curves[data.key], folder / f"{data.key}-linearity.{ext}")
            count += 1
    return count


def _take(folder: Path):
    """A simulated take of the default calibration sequence, measured."""
    import numpy as np

    from ocio_vp.patterns.design import PatternOptions, calibration_sequence
    from ocio_vp.patterns.frames import write_sequence_folder
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.plates.take import TakeRef, measure_take
    from ocio_vp.simulator.take import TakeOptions, write_take

    SL = np.array([[0.5, 0.08, 0.01], [0.2, 0.6, 0.08], [0.02, 0.1, 0.55]])
    sequence = write_sequence_folder(calibration_sequence(PatternOptions()), folder / "patterns")
    options = TakeOptions(fps=25.0, preroll=1.0, noise=0.01, size=(96, 54), seed=11)
    name = write_take(load_sequence(sequence), SL, folder / "take", options)
    return measure_take(TakeRef(frames=folder / "take" / name, sequence=sequence))


def measure_sheets(rounds: int) -> dict[str, list[float]]:
    from benchmarks import contact_sheet_matplotlib
    from ocio_vp.plates import contact_sheet

    ways = {
        "svg writer": (contact_sheet.write_contact_sheet, "svg"),
        "matplotlib Agg": (contact_sheet_matplotlib.write_contact_sheet, "png"),
    }
    times: dict[str, list[float]] = {name: [] for name in ways}
    with tempfile.TemporaryDirectory(prefix="ocio-vp-bench-sheet-") as tmp:
        reading = _take(Path(tmp))
        times["frames"] = [float(len(reading.numbers))]
        for write, ext in ways.values():
            write(reading, Path(tmp) / f"warm.{ext}")
        for _ in range(rounds):
            for name, (write, ext) in ways.items():
                start = time.perf_counter()
                write(reading, Path(tmp) / f"take.{ext}")
                times[name].append(time.perf_counter() - start)
    return times


def measure(rounds: int) -> dict[str, list[float]]:
    from benchmarks import report_matplotlib
    from ocio_vp.report import plots
    from ocio_vp.report.build import linearity_curves
    from ocio_vp.report.data import environment_data

    ways = {
        "svg writer": (plots, "svg"),
        "matplotlib Agg": (report_matplotlib, "png"),
        "matplotlib SVG": (report_matplotlib, "svg"),
    }
    times: dict[str, list[float]] = {name: [] for name in ways}
    with tempfile.TemporaryDirectory(prefix="ocio-vp-bench-figures-") as tmp:
        root = Path(tmp)
        environments = environment_data([_solutions(root)])
        curves = {d.key: linearity_curves(d.solution.linearity) for d in environments}
        for name, (module, ext) in ways.items():  # warm-up: imports, fonts, first layouts
            (root / name).mkdir()
            times.setdefault("figures", []).append(
                _draw(module, environments, curves, root / name, ext)
            )
        for _ in range(rounds):
            for name, (module, ext) in ways.items():
                start = time.perf_counter()
                _draw(module, environments, curves, root / name, ext)
                times[name].append(time.perf_counter() - start)
    imports = [
        float(subprocess.run([sys.executable, "-c", _IMPORT], capture_output=True, text=True,
                             check=True).stdout)
        for _ in range(rounds)
    ]  # fmt: skip
    times["matplotlib import"] = imports
    return times


def _row(name: str, times: dict[str, list[float]]) -> str:
    ratio = statistics.median(t / s for t, s in zip(times[name], times["svg writer"], strict=True))
    return f"| {name} | {statistics.median(times[name]):.2f} | {ratio:.0f}x |"


def report(times: dict[str, list[float]], sheets: dict[str, list[float]], rounds: int) -> str:
    import os

    lines = [
        HEADING,
        "",
        "Generated by `python -m benchmarks.bench_figures --out docs/report.md` (also by "
        "`python -m benchmarks.run`); method in the module docstring. "
        f"{times['figures'][0]} figures, the demo's 7 environments; median of {rounds} rounds, "
        "side by side; load average (1 min) at the end "
        f"{os.getloadavg()[0]:.1f}.",
        "",
        "| drawn with | the report's figures (s) | x the SVG writer's time |",
        "|---|---:|---:|",
    ]
    lines += [_row(name, times) for name in ("svg writer", "matplotlib SVG", "matplotlib Agg")]
    lines += [
        f"| (matplotlib's import, once per process) | "
        f"{statistics.median(times['matplotlib import']):.2f} | |",
        "",
        f"The take's contact sheet ({sheets['frames'][0]:.0f} camera frames, three strips):",
        "",
        "| drawn with | one contact sheet (s) | x the SVG writer's time |",
        "|---|---:|---:|",
        *(_row(name, sheets) for name in ("svg writer", "matplotlib Agg")),
        "",
    ]
    return "\n".join(lines)


def run(quick: bool = False) -> str:
    rounds = 2 if quick else 5
    return report(measure(rounds), measure_sheets(rounds), rounds)


def main(argv: list[str] | None = None) -> int:
    from benchmarks import write_section

    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_figures", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="two rounds instead of five")
    parser.add_argument("--out", help="replace this section of that document (default: print)")
    args = parser.parse_args(argv)
    text = run(quick=args.quick)
    write_section(text, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
