"""Non-linear Q: writing its OCIO LUT chains (time, agreement, LUT size) and applying it.

- Baking: ``ocio_vp.ocio.bake.model_outputs`` per environment, root-polynomial and
  emitter-protected (the Q and Q^-1 chains, their check and their CLF text: everything a
  non-linear config adds), with the agreement it records (ΔE2000 against the exact model over
  the camera range built from the calibration).
- LUT size vs agreement: the same chains at 17..65 points per axis (one environment), on the
  simulator's camera range.
- The in-frustum round trip through the written config: content c -> the config's in-frustum
  drive (OCIO) -> the wall [SL] -> the exact model Q, against c.
- Apply, in memory on one 4096x2160 float32 frame: the 3x3 OCIO path, the exact model
  (``ocio-vp apply`` on a root-polynomial solution) and the config's baked LUT, at 1 and 2
  threads, each with its error against the float64 model.
- Apply, file to file: the same 4K half-float zip EXR frames through ``apply_file`` with a
  least-squares solution (OCIO) and a root-polynomial one (exact model), interleaved.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time

ENVIRONMENTS = (
    "warm_white_led",
    "incandescent",
    "indoor_daylight",
    "rgb_led_white",
    "outdoor_shade",
    "direct_sun",
)


def _solutions(names, protect: bool = False):
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(names)
    method = "auto" if protect else "root-polynomial"
    return [
        solve_environment(m, env, method=method, protect_emitters=protect) for env in m.environments
    ]


def _bakes(solution, size: int = 65):
    """(correction, target chart, Q chain, Q^-1 chain) baked at ``size`` as the writer does."""
    from ocio_vp.ocio import bake

    correction = solution.correction
    lit = np.asarray(solution.diagnostics.charts.lit_baseline, dtype=np.float64)
    chart = np.asarray(solution.diagnostics.charts.target, dtype=np.float64)
    forward = bake.forward_chain(correction, lit[18], np.vstack([lit, chart]), size)
    q = bake.chain_transform(forward, bake.bake(correction.apply, forward))
    backward = bake.inverse_chain(correction, bake.chart_content(chart), size)
    q_inverse = bake.chain_transform(backward, bake.bake_inverse(correction, backward))
    return correction, chart, q, q_inverse


def _agreement(block: dict) -> str:
    return f"{block['p99']['all']:.2g} / {block['worst']['all']:.2g}"


def baking(quick: bool) -> str:
    from ocio_vp.ocio.bake import model_outputs

    names = ENVIRONMENTS[:3] if quick else ENVIRONMENTS
    rows = []
    for protect in (False, True):
        for solution in _solutions(names[:3] if protect else names, protect):
            start = time.perf_counter()
            outputs = model_outputs(solution)
            total = time.perf_counter() - start
            block = outputs.block
            rows.append(
                (
                    solution.environment,
                    solution.correction.kind,
                    fmt_ms(total),
                    _agreement(block["agreement"]),
                    _agreement(block["inverse_agreement"]),
                    f"{sum(len(t) for t in outputs.files.values()) / 1e6:.1f} MB",
                )
            )
    table = markdown_table(
        [
            "environment",
            "model",
            "write Q + Q^-1 chains (design, bake, check, CLF text)",
            "Q vs model, p99 / worst ΔE2000",
            "Q(Q^-1 chain) vs content, p99 / worst",
            "CLF size",
        ],
        rows,
    )
    return "\n".join(
        [
            "### Baking a non-linear Q into the config (LUT chains, 65^3)",
            "",
            table,
            "",
            "ΔE2000 over the camera range built from the calibration alone "
            "(`ocio_vp.model.footage_range.calibration_footage_range`: the lit chart at 1/16-4x "
            "with noise, near black, highlights to 16x, the wall's primaries), as "
            "`solution.json` records it (`diagnostics.post_correction_ocio`). The same run's "
            "agreement over the simulator's full camera range is in docs/hosts.md.",
        ]
    )


def sizes(quick: bool) -> str:
    from benchmarks.bench_hosts import ocio_function
    from ocio_vp.model.footage_range import agreement
    from ocio_vp.simulator.stage import paper_stage
    from ocio_vp.simulator.truth import stage_footage_range

    (solution,) = _solutions(("incandescent",))
    footage = stage_footage_range(paper_stage(), "incandescent", solution)
    rows = []
    for size in (33, 49, 65) if quick else (17, 33, 49, 65):
        start = time.perf_counter()
        correction, _, q, q_inverse = _bakes(solution, size)
        bake = time.perf_counter() - start
        measured = agreement(footage, correction.apply, ocio_function(q))
        inverse = ocio_function(q_inverse)
        content = np.vstack([v for k, v in footage.sets.items() if k != "near_black"])
        content = correction.apply(content)
        content = content[np.all(content > 0, axis=1)]
        back = correction.apply(inverse(content))
        error = np.abs(back - content).max(axis=1) / np.abs(content).max(axis=1)
        rows.append(
            (
                f"{size}^3",
                fmt_ms(bake),
                f"{measured.p99['all']:.2g} / {measured.worst['all']:.2g}",
                f"{100 * np.percentile(error, 99):.2g} % / {100 * error.max():.2g} %",
            )
        )
    table = markdown_table(
        ["grid", "design and bake Q + Q^-1", "Q vs model p99 / worst ΔE2000",
         "Q(Q^-1 chain(c)) vs c, p99 / worst (% of largest channel)"],
        rows,
    )  # fmt: skip
    return "\n".join(
        [
            "### LUT size vs agreement (incandescent, the simulator's camera range)",
            "",
            table,
        ]
    )


def round_trip(quick: bool) -> str:
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio import IN_FRUSTUM, REFERENCE
    from ocio_vp.ocio.writer import write_solutions

    names = ENVIRONMENTS[:3] if quick else ENVIRONMENTS
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for solution in write_solutions(_solutions(names), Path(tmp)):
            config = OCIO.Config.CreateFromFile(
                str(Path(tmp) / solution.environment / "config.ocio")
            )
            cpu = config.getProcessor(REFERENCE, IN_FRUSTUM).getDefaultCPUProcessor()
            chart = np.asarray(solution.diagnostics.charts.target, dtype=np.float64)
            rng = np.random.default_rng(7)
            mix = rng.dirichlet(np.full(len(chart), 0.3), 5000) @ chart
            c = mix / mix.max(axis=1, keepdims=True) * np.exp2(rng.uniform(-13, 2, (5000, 1)))
            drive = np.ascontiguousarray(c, dtype=np.float32)
            cpu.applyRGB(drive)
            wall = (drive - solution.in_frustum_offset) @ np.asarray(solution.SL).T
            error = np.abs(solution.correction.apply(wall) - c).max(axis=1)
            error /= c.max(axis=1)
            rows.append(
                (solution.environment, f"{100 * error.mean():.3f} %", f"{100 * error.max():.3f} %")
            )
    table = markdown_table(["environment", "mean", "max"], rows)
    return "\n".join(
        [
            "### In-frustum round trip through the written config",
            "",
            "Q([SL] (drive - offset)) against c, in % of each colour's largest channel, for "
            "5000 colours inside the target chart's gamut at exposures 2^-13..4 (the drive from "
            "OCIO's processor on the written config.ocio and its luts/).",
            "",
            table,
        ]
    )


def _ocio_cpu(transform):
    import PyOpenColorIO as OCIO

    return (
        OCIO.Config.CreateRaw()
        .getProcessor(transform)
        .getOptimizedCPUProcessor(OCIO.BIT_DEPTH_F32, OCIO.BIT_DEPTH_F32, OCIO.OPTIMIZATION_DEFAULT)
    )


def apply_speed(quick: bool) -> str:
    from ocio_vp.footage.apply import ModelTransform, apply_in_place
    from ocio_vp.ocio.config import matrix_transform

    (solution,) = _solutions(("incandescent",))
    correction, chart, q_lut, _ = _bakes(solution, 65)
    height, width = (1080, 2048) if quick else (2160, 4096)
    repeats = 3 if quick else 5
    # Footage whose corrected colours are inside the chart's gamut (exact preimages of random
    # mixtures at exposures 1/64..4), tiled over the frame.
    rng = np.random.default_rng(0)
    content = rng.dirichlet(np.full(len(chart), 0.3), 1 << 16) @ chart
    content *= np.exp2(rng.uniform(-6, 2, (len(content), 1))) / content.max()
    tile = correction.inverse(content).astype(np.float32)
    src = np.resize(tile, (height, width, 3))
    reference = correction.apply(src.reshape(-1, 3)).reshape(src.shape)
    candidates = {
        "3x3 Q (OCIO CPU processor)": _ocio_cpu(matrix_transform(solution.Q, np.zeros(3))),
        "root-polynomial, exact (float64 in 16K-pixel bands)": ModelTransform(correction),
        "root-polynomial, the config's LUT chain (OCIO)": _ocio_cpu(q_lut),
    }
    rows, times = [], {}
    for name, transform in candidates.items():
        for threads in (1, 2):
            work = src.copy()
            times[name, threads] = median_time(
                lambda w=work, t=transform, n=threads: apply_in_place(t, w, threads=n),
                repeats=repeats,
            )
            np.copyto(work, src)
            apply_in_place(transform, work, threads=threads)
            scale = np.abs(reference).max(axis=-1)
            error = float((np.abs(work - reference).max(axis=-1) / scale).max())
            rows.append((name, threads, fmt_ms(times[name, threads]), f"{100 * error:.2g} %"))
    names = list(candidates)
    best = {n: min(times[n, 1], times[n, 2]) for n in names}
    table = markdown_table(
        [f"post-correction ({width}x{height} float32 RGB, in-gamut footage)", "threads",
         "median time",
         "max error vs float64 model (% of pixel max)"],
        rows,
    )  # fmt: skip
    return "\n".join(
        [
            "### Applying a root-polynomial Q to a frame (in memory)",
            "",
            table,
            "",
            f"- exact root-polynomial / 3x3 (best of 1-2 threads, same run): "
            f"**{best[names[1]] / best[names[0]]:.1f}x**; the config's LUT / 3x3: "
            f"{best[names[2]] / best[names[0]]:.1f}x.",
            "- The 3x3 row's error is the 3x3 approximation's, not a rounding error: it is what "
            "a matrix-only path would give for this model.",
        ]
    )


def file_to_file(quick: bool) -> str:
    from benchmarks.bench_apply import make_solution, write_frames
    from ocio_vp.footage.apply import apply_file, load_post_correction
    from ocio_vp.ocio.writer import write_solutions

    count, rounds, (height, width) = (2, 2, (1080, 2048)) if quick else (4, 3, (2160, 4096))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        frames = write_frames(root / "plates", count, height, width)
        (solution,) = _solutions(("incandescent",))
        write_solutions([solution], root / "rp")
        posts = {
            "3x3 Q (least-squares, OCIO)": load_post_correction(make_solution(root / "ls")),
            "root-polynomial (exact model)": load_post_correction(root / "rp" / "incandescent"),
        }
        times: dict[tuple[str, int], list[float]] = {}
        for _ in range(rounds):  # interleaved: drifting load hits both alike
            for name, post in posts.items():
                for threads in (1, 2):
                    for frame in frames:
                        start = time.perf_counter()
                        apply_file(frame, root / "out" / frame.name, post, threads=threads)
                        times.setdefault((name, threads), []).append(time.perf_counter() - start)
    median = {key: statistics.median(v) for key, v in times.items()}
    rows = [(name, threads, fmt_ms(t)) for (name, threads), t in median.items()]
    names = list(posts)
    best = {n: min(median[n, 1], median[n, 2]) for n in names}
    table = markdown_table(
        [f"solution ({width}x{height} half zip EXR)", "threads", "per frame"], rows
    )
    return "\n".join(
        [
            "### Applying a root-polynomial Q, file to file",
            "",
            table,
            "",
            f"- root-polynomial / 3x3 per frame (best of 1-2 threads, same run): "
            f"**{best[names[1]] / best[names[0]]:.2f}x** (read, transform, write).",
        ]
    )


def run(quick: bool = False) -> str:
    return "\n\n".join(
        [
            "## Root-polynomial Q: bake and apply",
            baking(quick),
            sizes(quick),
            round_trip(quick),
            apply_speed(quick),
            file_to_file(quick),
        ]
    )


if __name__ == "__main__":
    import sys

    print(run(quick="--quick" in sys.argv))
