"""``ocio-vp apply``: in memory, file to file against the I/O limit, Dask workers, peak memory.

Targets, each checked as a ratio measured in the same run (methods interleaved, so drifting load
from other processes hits all of them alike):
- in memory, Q + offset on a 4096x2160 float RGB frame: <= 2x a plain memory copy and >= 2x
  faster than a numpy matmul;
- file to file on 4K half-float zip EXR, 6 and 48 frames: ``ocio-vp apply`` at >= 0.9x the speed
  of the I/O limit, a plain OpenImageIO read + write of the same frames with the same
  compression in one process with OpenImageIO's own threads (both whole commands, interpreter
  start-up included); oiiotool's ``--colorconvert`` shown for comparison;
- a local Dask cluster with 2 workers >= 1.6x faster than 1 worker on 16 frames;
- peak memory (the process's own ``VmHWM``) independent of the sequence length.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks import cached_bytecode, fmt_ms, markdown_table, median_time

OFFSET = np.array([0.002, -0.001, 0.003])


def make_solution(folder: Path) -> Path:
    """Solve the simulator's incandescent environment; returns its solution folder."""
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("incandescent",))
    solution = solve_environment(m, m.environments[0], method="least-squares")
    write_solutions([solution], folder)
    return folder / solution.environment


def footage(height: int, width: int, seed: int) -> np.ndarray:
    """Smooth gradients plus 1% noise: compresses like real plates, not like white noise."""
    rng = np.random.default_rng(seed)
    y = np.linspace(0.0, 1.0, height, dtype=np.float32)[:, None, None]
    x = np.linspace(0.0, 1.0, width, dtype=np.float32)[None, :, None]
    base = 0.05 + 0.6 * x * np.array([1.0, 0.8, 0.6], np.float32) + 0.3 * y
    return base * (1 + 0.01 * rng.standard_normal((height, width, 3), dtype=np.float32))


def write_frames(folder: Path, count: int, height: int, width: int) -> list[Path]:
    import OpenImageIO as oiio

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i in range(count):
        spec = oiio.ImageSpec(width, height, 3, oiio.HALF)
        spec.attribute("compression", "zip")
        path = folder / f"plate.{1001 + i:04d}.exr"
        out = oiio.ImageOutput.create(str(path))
        out.open(str(path), spec)
        out.write_image(footage(height, width, i))
        out.close()
        paths.append(path)
    return paths


def _read(path: Path) -> np.ndarray:
    import OpenImageIO as oiio

    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT), dtype=np.float64)


def _tasks(post, frames, out: Path, threads: int):
    from ocio_vp.footage.apply import FrameTask

    return [
        FrameTask(str(f), str(out / f.name), post, overwrite=True, threads=threads) for f in frames
    ]


def _run_ours(post, frames, out: Path, *, workers=None, scheduler=None, threads=1) -> float:
    from ocio_vp.footage.apply import run_task
    from ocio_vp.footage.distributed import map_unordered

    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    results = list(
        map_unordered(
            run_task,
            _tasks(post, frames, out, threads),
            workers=workers,
            scheduler=scheduler,
        )
    )
    seconds = time.perf_counter() - start
    bad = [r for _, r in results if isinstance(r, BaseException) or r.status != "done"]
    if bad:
        raise RuntimeError(f"apply failed: {bad[0]}")
    return seconds


def in_memory(quick: bool) -> str:

    from ocio_vp.footage.apply import apply_in_place
    from ocio_vp.ocio.config import matrix_transform

    height, width = 2160, 4096
    repeats = 5 if quick else 9
    Q = np.array([[1.08, -0.06, 0.01], [0.02, 0.95, 0.03], [-0.01, 0.07, 1.04]])
    cpu = _processor(matrix_transform(Q, OFFSET), "F32")
    src = footage(height, width, 0)
    reference = src.astype(np.float64) @ Q.T + OFFSET
    dst = np.empty_like(src)
    QT, off = Q.T.astype(np.float32), OFFSET.astype(np.float32)

    def numpy_matmul():
        np.matmul(src, QT, out=dst)
        np.add(dst, off, out=dst)

    rows = []
    t_copy = median_time(lambda: np.copyto(dst, src), repeats=repeats)
    rows.append(("plain memory copy (`np.copyto`)", t_copy, 0.0))
    t_np = median_time(numpy_matmul, repeats=repeats)
    numpy_matmul()
    rows.append(
        (
            "numpy `matmul(out=)` + `+=` offset, float32",
            t_np,
            np.abs(dst - reference).max(),
        )
    )
    t_naive = median_time(lambda: src @ QT + off, repeats=max(3, repeats // 2))
    rows.append(
        (
            "numpy `rgb @ Q.T + offset`",
            t_naive,
            np.abs(src @ QT + off - reference).max(),
        )
    )
    t_ocio = {}
    for threads in (1, 2):
        work = src.copy()
        t_ocio[threads] = median_time(
            lambda w=work, n=threads: apply_in_place(cpu, w, threads=n), repeats=repeats
        )
        np.copyto(work, src)
        apply_in_place(cpu, work, threads=threads)
        rows.append(
            (
                f"OCIO CPU `apply(PackedImageDesc)` in place, {threads} thread(s)",
                t_ocio[threads],
                np.abs(work - reference).max(),
            )
        )
    best = min(t_ocio.values())
    half_rows, conversions = _half_frame(Q, src, repeats)
    rows += half_rows
    table = markdown_table(
        [
            "method (one 4096x2160 RGB frame, Q + offset; float32 unless half)",
            "median time",
            "max abs error vs float64",
        ],
        [(name, fmt_ms(t), f"{err:.2e}") for name, t, err in rows],
    )
    verdict_copy = "met" if best <= 2 * t_copy else "**not met**"
    verdict_np = "met" if t_np >= 2 * best else "**not met**"
    return "\n".join(
        [
            "### In memory: one 4K frame",
            "",
            table,
            "",
            f"- OCIO (best) / memory copy = **{best / t_copy:.2f}x** (target <= 2x: {verdict_copy}).",
            f"- numpy matmul / OCIO (best) = **{t_np / best:.2f}x** (target >= 2x: {verdict_np}); "
            f"the usual numpy expression `rgb @ Q.T + offset` / OCIO = {t_naive / best:.1f}x.",
            f"- On a half-float frame (what `ocio-vp apply` does to half EXRs) OCIO converts "
            f"half to float and back itself: {conversions}",
        ]
    )


def _processor(transform, depth: str):
    """OCIO's optimised CPU processor of ``transform`` on ``depth`` ("F32", "F16") in and out."""
    import PyOpenColorIO as OCIO

    bits = getattr(OCIO, f"BIT_DEPTH_{depth}")
    return (
        OCIO.Config.CreateRaw()
        .getProcessor(transform)
        .getOptimizedCPUProcessor(bits, bits, OCIO.OPTIMIZATION_DEFAULT)
    )


def _half_frame(Q, src: np.ndarray, repeats: int) -> tuple[list, str]:
    """Rows for Q + offset on a half frame in place (OCIO's half processor, one thread), the same
    processor shape with an identity matrix (its half conversions alone), and numpy's casts."""
    import PyOpenColorIO as OCIO

    from ocio_vp.footage.apply import OcioTransform, apply_in_place
    from ocio_vp.ocio.config import matrix_transform

    half = src.astype(np.float16)
    reference = half.astype(np.float64) @ Q.T + OFFSET
    work = half.copy()
    rows, times = [], {}
    for name, transform in (
        ("Q + offset", matrix_transform(Q, OFFSET)),
        ("identity (its half conversions alone)", OCIO.MatrixTransform()),
    ):
        apply = OcioTransform(f32=None, f16=_processor(transform, "F16"))  # half only
        times[name] = median_time(
            lambda a=apply: (np.copyto(work, half), apply_in_place(a, work)), repeats=repeats
        )
        np.copyto(work, half)
        apply_in_place(apply, work)
        target = reference if name == "Q + offset" else half.astype(np.float64)
        error = float(np.max(np.abs(work.astype(np.float64) - target)))
        rows.append((f"OCIO CPU on a half frame in place, 1 thread: {name}", times[name], error))
    t_copy = median_time(lambda: np.copyto(work, half), repeats=repeats)
    t_up = median_time(lambda: half.astype(np.float32), repeats=repeats)
    as_float = half.astype(np.float32)
    t_down = median_time(lambda: np.copyto(work, as_float, casting="same_kind"), repeats=repeats)
    round_trip = float(np.max(np.abs(as_float.astype(np.float16).astype(np.float64) - half)))
    rows.append(
        (
            "numpy half -> float32 + float32 -> half casts (for comparison)",
            t_up + t_down,
            round_trip,
        )
    )
    conversions = times["identity (its half conversions alone)"]
    text = (
        f"Q + offset on a half frame costs {fmt_ms(times['Q + offset'] - t_copy)} of one core "
        f"(the copy that restores the frame each run, {fmt_ms(t_copy)}, taken off) and an "
        f"identity matrix {fmt_ms(conversions - t_copy)}: the half conversions are the cost "
        f"({1e9 * (conversions - t_copy) / half.size:.1f} ns a value, there and back), not the "
        f"matrix; numpy's casts take {fmt_ms(t_up + t_down)} for the same round trip. This is "
        f"the CPU time file-to-file apply pays per frame over a plain read + write (the errors "
        f"of these rows are half's own rounding of the result)."
    )
    return rows, text


#: ``python -c CHILD plain|apply OUT ARGS...``: a plain OpenImageIO read + write of each frame
#: (the I/O limit) or ``ocio-vp apply``; prints its VmHWM in KiB and the exit code.
CHILD = textwrap.dedent(
    """
    import os, sys
    mode, out, *rest = sys.argv[1:]
    if mode == "plain":  # the I/O limit: read and write each frame as stored, nothing else
        import OpenImageIO as oiio
        os.makedirs(out, exist_ok=True)
        for src in rest:
            inp = oiio.ImageInput.open(src)
            spec = inp.spec()
            pixels = inp.read_image(0, 0, 0, spec.nchannels, spec.format)
            inp.close()
            dst = os.path.join(out, os.path.basename(src))
            output = oiio.ImageOutput.create(dst)
            output.open(dst, spec)
            output.write_image(pixels)
            output.close()
        rc = 0
    else:
        from ocio_vp.cli import main
        rc = main(["apply", *rest, "--out", out, "--overwrite", "--no-progress"])
    # VmHWM: this process's own high-water mark (ru_maxrss would include the parent's: it
    # survives the exec that started this interpreter).
    status = open("/proc/self/status").read().splitlines()
    print(next(l for l in status if l.startswith("VmHWM")).split()[1], rc)
    """
)


@dataclass
class Runs:
    """Wall and CPU seconds (the command and the processes it waited for) and peak KiB."""

    wall: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    peak_kib: list[int] = field(default_factory=list)


def _timed(cmd: list[str], runs: Runs, env: dict[str, str]) -> None:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, check=True, capture_output=True, text=True, env=env)
    runs.wall.append(time.perf_counter() - start)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    runs.cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    if cmd[1] == "-c":
        kib, rc = proc.stdout.split()[-2:]
        if rc != "0":
            raise RuntimeError(f"{cmd[3]} exited {rc}: {proc.stderr[-500:]}")
        runs.peak_kib.append(int(kib))


def _commands(post, frames: list[Path], root: Path, with_tools: bool) -> dict[str, list[str]]:
    solution = str(Path(post.config).parent)
    pattern = str(frames[0].parent / "plate.####.exr")
    child = [sys.executable, "-c", CHILD]
    commands = {
        "plain OpenImageIO read + write (the I/O limit)": [
            *child,
            "plain",
            str(root / "out_plain"),
            *map(str, frames),
        ],
        "`ocio-vp apply` (default: one process, frames pipelined)": [
            *child,
            "apply",
            str(root / "out_apply"),
            solution,
            pattern,
        ],
    }
    if with_tools:
        commands["`ocio-vp apply --workers 2` (process pool)"] = [
            *child,
            "apply",
            str(root / "out_pool"),
            solution,
            pattern,
            "--workers",
            "2",
        ]
        first, last = 1001, 1000 + len(frames)
        commands["`oiiotool --colorconvert` (its own threads)"] = [
            "oiiotool", "--colorconfig", post.config, "--frames", f"{first}-{last}",
            str(frames[0].parent / "plate.#.exr"), "--colorconvert", post.source, post.target,
            "-o", str(root / "out_oiiotool" / "plate.#.exr"),
        ]  # fmt: skip
        (root / "out_oiiotool").mkdir(parents=True, exist_ok=True)
    return commands


def _ulp_errors(post, frames: list[Path], ours: Path, other: Path | None) -> tuple[float, float]:
    """Max error in half ulps: ours vs numpy ``Q @ rgb`` (float64, rounded to half), vs other."""
    Q = np.asarray(json.loads((Path(post.config).parent / "solution.json").read_text())["Q"])
    err_np = err_other = 0.0
    for f in frames:
        got = _read(ours / f.name)
        expected = (_read(f) @ Q.T).astype(np.float16).astype(np.float64)
        ulp = np.abs(np.spacing(expected.astype(np.float16)).astype(np.float64))
        err_np = max(err_np, float(np.max(np.abs(got - expected) / ulp)))
        if other is not None:
            err_other = max(err_other, float(np.max(np.abs(got - _read(other / f.name)) / ulp)))
    return err_np, err_other


def file_to_file(quick: bool, post, root: Path, count: int, master: list[Path], env) -> tuple:
    """Interleaved repeats of the whole commands on ``count`` frames in ``env`` (see
    :func:`benchmarks.cached_bytecode`); (markdown, runs)."""
    height, width = (1080, 2048) if quick else (2160, 4096)
    folder = root / f"frames{count}"
    folder.mkdir(parents=True, exist_ok=True)
    # Distinct files (copies of a few rendered frames), so every read comes from its own pages.
    frames = []
    for i in range(count):
        frames.append(folder / f"plate.{1001 + i:04d}.exr")
        shutil.copyfile(master[i % len(master)], frames[-1])
    few = count <= 8
    commands = _commands(post, frames, root / f"out{count}", with_tools=few)
    # Short runs are noisier (a 4 s command on a shared machine): more rounds for the median.
    rounds = 1 if quick else (9 if few else 5)
    runs = {label: Runs() for label in commands}
    for cmd in commands.values():  # warm-up: page cache, bytecode cache
        subprocess.run(cmd, check=True, capture_output=True, env=env)
    load = os.getloadavg()[0]
    for _ in range(rounds):
        for label, cmd in commands.items():
            _timed(cmd, runs[label], env)
    load = (load + os.getloadavg()[0]) / 2
    labels = list(commands)
    plain, ours = runs[labels[0]], runs[labels[1]]
    ratio = float(np.median(plain.wall) / np.median(ours.wall))
    pairs = [p / o for p, o in zip(plain.wall, ours.wall, strict=True)]
    checked = frames if few else [frames[0], frames[-1]]
    tool = root / f"out{count}" / "out_oiiotool" if few else None
    err_np, err_tool = _ulp_errors(post, checked, root / f"out{count}" / "out_apply", tool)
    rows = [
        (
            label,
            fmt_ms(float(np.median(r.wall))),
            f"{float(np.median(r.cpu)):.3g} s",
            f"{count / float(np.median(r.wall)):.2f}",
            f"{float(np.median(plain.wall)) / float(np.median(r.wall)):.2f}x",
        )
        for label, r in runs.items()
    ]
    verdict = "met" if ratio >= 0.9 else "**not met**"
    lines = [
        f"### File to file: {count} frames, {width}x{height} half-float RGB EXR (zip)",
        "",
        markdown_table(
            [
                "command",
                f"wall (median of {rounds})",
                "CPU (user + sys)",
                "frames/s",
                "speed / I/O limit",
            ],
            rows,
        ),
        "",
        f"- `ocio-vp apply` / I/O limit (speed, medians) = **{ratio:.2f}x** (target >= 0.9x: "
        f"{verdict}); pair by pair: {', '.join(f'{p:.2f}' for p in pairs)}. Load average "
        f"(1 min) during these runs: {load:.1f} on {os.cpu_count()} cores.",
        f"- Accuracy ({len(checked)} frames checked): ours vs numpy `Q @ rgb` on the stored "
        f"half input, rounded to half: max {err_np:.2f} half ulp"
        + (f"; ours vs oiiotool's output: max {err_tool:.2f} half ulp." if few else "."),
    ]
    return "\n".join(lines), runs[labels[0]], runs[labels[1]], ratio


def dask_scaling(quick: bool, post, root: Path) -> str:
    from distributed import LocalCluster

    height, width = (1080, 2048) if quick else (2160, 4096)
    frames = write_frames(root / "frames16", 16, height, width)
    times, outputs = {}, {}
    for n in (1, 2):
        with LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster:
            out = root / f"dask{n}"
            _run_ours(post, frames[:2], out, scheduler=cluster.scheduler_address)  # warm up
            times[n] = _run_ours(post, frames, out, scheduler=cluster.scheduler_address)
            outputs[n] = out
    same = all(
        np.array_equal(_read(outputs[1] / f.name), _read(outputs[2] / f.name)) for f in frames
    )
    speedup = times[1] / times[2]
    verdict = "met" if speedup >= 1.6 else "**not met**"
    return "\n".join(
        [
            f"### Dask: 16 frames {width}x{height} half EXR, local cluster (1 thread per worker)",
            "",
            markdown_table(
                ["workers", "wall time", "frames/s"],
                [(n, fmt_ms(t), f"{16 / t:.2f}") for n, t in times.items()],
            ),
            "",
            f"- Speed-up 2 workers / 1 worker = **{speedup:.2f}x** (target >= 1.6x: {verdict}); "
            f"outputs of both runs bitwise identical: {same}.",
        ]
    )


def peak_memory(quick: bool, measured: dict[int, tuple[Runs, Runs]]) -> str:
    """Peak memory from the file-to-file runs above: each process's own VmHWM."""
    from ocio_vp.footage.stream import HELD, WRITERS

    height, width = (1080, 2048) if quick else (2160, 4096)
    rows = []
    peaks = {}
    for count, (plain, ours) in measured.items():
        peaks[count] = max(ours.peak_kib) / 1024
        rows.append((count, f"{max(plain.peak_kib) / 1024:.0f} MiB", f"{peaks[count]:.0f} MiB"))
    few, many = min(peaks), max(peaks)
    ratio = peaks[many] / peaks[few]
    frame_mib = height * width * 3 * 2 / 2**20
    verdict = "met" if ratio <= 1.1 else "**not met**"
    return "\n".join(
        [
            f"### Peak memory ({width}x{height} half RGB frames)",
            "",
            markdown_table(
                ["frames", "plain read + write (VmHWM)", "`ocio-vp apply` (VmHWM)"],
                rows,
            ),
            "",
            f"- `ocio-vp apply` peak with {many} frames / with {few} = **{ratio:.2f}** (target: "
            f"independent of the sequence length: {verdict}). One frame is {frame_mib:.0f} MiB "
            f"as stored (half); apply holds at most {HELD} (one read ahead, one transformed, "
            f"{WRITERS} being written), the plain loop one.",
        ]
    )


def run(quick: bool = False) -> str:
    from ocio_vp.footage.apply import load_post_correction

    parts = ["## `ocio-vp apply`: footage at the speed of reading and writing it", ""]
    parts += [in_memory(quick), ""]
    with tempfile.TemporaryDirectory() as tmp, cached_bytecode() as env:
        root = Path(tmp)
        post = load_post_correction(make_solution(root / "calib"))
        height, width = (1080, 2048) if quick else (2160, 4096)
        master = write_frames(root / "master", 6, height, width)
        measured = {}
        for count in (3, 12) if quick else (6, 48):
            text, plain, ours, _ = file_to_file(quick, post, root, count, master, env)
            measured[count] = (plain, ours)
            parts += [text, ""]
            shutil.rmtree(root / f"frames{count}")
            shutil.rmtree(root / f"out{count}")
        parts += [peak_memory(quick, measured), ""]
        parts += [dask_scaling(quick, post, root)]
    return "\n".join(parts)
