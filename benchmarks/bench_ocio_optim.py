"""OCIO optimisation levels (lossless / default / good / draft): error vs throughput.

Measured on the full wall chain of a realistic config: content (camera native linear) ->
``LED Wall - Inner Frustum`` = N + black-level offset -> panel-linearity shaper + 1D LUT
(a simulated panel whose red and green are not linear) -> SMPTE ST 2084 (PQ, 1000 nits) or
gamma 2.4 (an ExponentTransform, where OCIO's fast pow approximation applies); and on
the post-correction Q (a single matrix, which every level keeps exact). Error: max absolute
difference from the ``lossless`` processor (in output units: PQ signal for the wall, linear
camera RGB for Q), on the same 4096x2160 frame that is timed.
"""

from __future__ import annotations

import dataclasses
import tempfile
from pathlib import Path

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time

#: Simulated panel responses r(d) per channel: red and green bend, blue is linear.
PANEL_GAMMA = {"red": 1.25, "green": 0.9, "blue": 1.0}


def wall_config(folder: Path, *, encoding: str = "pq"):
    """Solve a sample environment with a non-linear panel; returns (config path, solution)."""
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage_measurements
    from ocio_vp.wall.encoding import with_wall_encoding
    from ocio_vp.wall.linearity import fit_linearity, parse_ramps

    m = paper_stage_measurements(("incandescent",))
    drive = np.linspace(0.0, 1.0, 17)
    ramps = parse_ramps(
        {
            name: {
                "drive": drive.tolist(),
                "camera": [(m.SL[:, k] * d**gamma).tolist() for d in drive],
            }
            for k, (name, gamma) in enumerate(PANEL_GAMMA.items())
        }
    )
    solution = solve_environment(m, m.environments[0], method="least-squares")
    solution = dataclasses.replace(solution, linearity=fit_linearity(ramps, m.SL))
    solution = with_wall_encoding(solution, encoding)
    written = write_solutions([solution], folder)
    return folder / solution.environment / "config.ocio", written[0]


def frame(height: int = 2160, width: int = 4096) -> np.ndarray:
    rng = np.random.default_rng(7)
    return rng.uniform(0.0, 1.5, size=(height, width, 3)).astype(np.float32)


def run(quick: bool = False) -> str:
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio.config import IN_FRUSTUM, POST_CORRECTION_COLORSPACE, REFERENCE

    levels = {
        "lossless": OCIO.OPTIMIZATION_LOSSLESS,
        "default": OCIO.OPTIMIZATION_DEFAULT,
        "good": OCIO.OPTIMIZATION_GOOD,
        "draft": OCIO.OPTIMIZATION_DRAFT,
    }
    repeats = 3 if quick else 7
    src = frame()
    sections = []
    with tempfile.TemporaryDirectory() as tmp:
        pq = OCIO.Config.CreateFromFile(str(wall_config(Path(tmp) / "pq")[0]))
        gamma = OCIO.Config.CreateFromFile(
            str(wall_config(Path(tmp) / "gamma", encoding="gamma2.4")[0])
        )
        chains = (
            ("wall chain, PQ: content -> Inner Frustum", pq, REFERENCE, IN_FRUSTUM),
            ("wall chain, gamma 2.4: content -> Inner Frustum", gamma, REFERENCE, IN_FRUSTUM),
            ("post-correction Q (one matrix)", pq, POST_CORRECTION_COLORSPACE, REFERENCE),
        )
        for label, config, a, b in chains:
            processor = config.getProcessor(a, b)
            outputs, rows = {}, []
            for name, level in levels.items():
                cpu = processor.getOptimizedCPUProcessor(
                    OCIO.BIT_DEPTH_F32, OCIO.BIT_DEPTH_F32, level
                )
                work = src.copy()

                def apply(cpu=cpu, work=work):
                    np.copyto(work, src)
                    cpu.apply(OCIO.PackedImageDesc(work, work.shape[1], work.shape[0], 3))

                seconds = median_time(apply, repeats=repeats)
                apply()
                outputs[name] = work.astype(np.float64)
                group = processor.getOptimizedProcessor(level).createGroupTransform()
                ops = ", ".join(type(t).__name__.removesuffix("Transform") for t in group)
                rows.append([name, ops, fmt_ms(seconds), f"{src.size / 3 / seconds / 1e6:.0f}"])
            for row in rows:
                err = np.abs(outputs[row[0]] - outputs["lossless"]).max()
                row.append(f"{err:.2e}")
            sections += [
                f"### {label}",
                "",
                markdown_table(
                    [
                        "level",
                        "ops after optimisation",
                        "time / 4K frame (incl. a copy)",
                        "Mpixel/s",
                        "max abs error vs lossless",
                    ],
                    rows,
                ),
                "",
            ]
    return "\n".join(
        [
            "## OCIO optimisation levels: error vs throughput",
            "",
            f"CPU processor, float32 RGB in place (`apply(PackedImageDesc)`), one thread, median "
            f"of {repeats}; input uniform in [0, 1.5] (HDR content above 1.0 included).",
            "",
            *sections,
        ]
    )
