"""Whole commands as a user runs them, side by side with another checkout (last round's).

Every row is a whole command in a fresh interpreter (``python -m ocio_vp.cli ...``, start-up
included), run in rounds that interleave every command, so a load that drifts hits them all
alike; a cell is the best wall time of its rounds, and the CPU time (user + system, the
command's own processes) of that run. ``apply`` is judged against the I/O limit: a plain
OpenImageIO read + write of the same frames in one process (``bench_apply``'s loop), as a
ratio of speeds (plain time / command time) measured in the same rounds; a long sequence runs
one round, each command right after a plain read + write of its own, so that the load's drift
over the minutes of the round falls on both sides of each ratio.

The other checkout: set ``OCIO_VP_BASELINE_PYTHON`` to the Python of an environment where it
is installed (the README says how to make one for last round's commit); without it
the baseline columns say so. Each checkout solves its own calibration for its ``apply`` rows
(solution files change between rounds); both read the same measurement files and frames.
"""

from __future__ import annotations

import dataclasses
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from benchmarks import cached_bytecode, markdown_table
from benchmarks.bench_apply import CHILD

#: The environment variable naming the baseline checkout's Python.
BASELINE_ENV = "OCIO_VP_BASELINE_PYTHON"
#: The commit the committed figures compare against (last round).
BASELINE_COMMIT = "1631fec"


@dataclasses.dataclass
class Cell:
    """Wall and CPU seconds of each round of one command."""

    wall: list[float] = dataclasses.field(default_factory=list)
    cpu: list[float] = dataclasses.field(default_factory=list)

    def best(self) -> tuple[float, float]:
        i = int(np.argmin(self.wall))
        return self.wall[i], self.cpu[i]


def _run(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd[:6])}... exited {proc.returncode}: {proc.stderr[-400:]}")
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def _inputs(root: Path, quick: bool, frames: bool = True) -> dict[str, Path]:
    """Measurement files (24 patches, 1000 patches, 150 environments) and 6 master frames
    (none when ``frames`` is false: only the ``apply`` rows read them)."""
    from benchmarks.bench_apply import write_frames
    from benchmarks.bench_solve_scaling import _mixtures
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.stage import simulate_measurements

    rng = np.random.default_rng(7)
    one = simulate_measurements(["incandescent"])
    env = one.environments[0]
    extra = _mixtures(rng, 976, 24)
    srl = np.concatenate([one.SRL, np.einsum("kj,jab->kab", extra, one.SRL)])
    target = np.concatenate([env.target_chart, extra @ env.target_chart])
    srl[24:] *= 1 + 0.005 * rng.standard_normal(srl[24:].shape)
    target[24:] *= 1 + 0.005 * rng.standard_normal(target[24:].shape)
    chart = dataclasses.replace(
        one, SRL=srl, environments=(dataclasses.replace(env, target_chart=target),)
    )
    names = ["incandescent", "direct_sun", "outdoor_shade", "indoor_daylight", "warm_white_led"]
    six = simulate_measurements([*names, "rgb_led_white"])
    count = 30 if quick else 150
    many = []
    for i in range(count):  # the paper's environments again, each chart with its own 1% noise
        e = six.environments[i % len(six.environments)]
        noisy = e.target_chart * (1 + 0.01 * rng.standard_normal(e.target_chart.shape))
        many.append(dataclasses.replace(e, name=f"{e.name}_{i:03d}", target_chart=noisy))
    files = {
        "one": root / "one24.yaml",
        "chart": root / "chart1000.yaml",
        "many": root / f"env{count}.yaml",
    }
    save_measurements(one, files["one"])
    save_measurements(chart, files["chart"])
    save_measurements(dataclasses.replace(six, environments=tuple(many)), files["many"])
    if not frames:
        return files
    height, width = (1080, 2048) if quick else (2160, 4096)
    files["master"] = write_frames(root / "master", 6, height, width)[0].parent
    return files


def _frames(root: Path, master: Path, count: int) -> list[Path]:
    """``count`` distinct frame files (copies of the 6 masters), so each read is its own."""
    folder = root / f"frames{count}"
    folder.mkdir(exist_ok=True)
    masters = sorted(master.glob("plate.*.exr"))
    out = []
    for i in range(count):
        out.append(folder / f"plate.{1001 + i:04d}.exr")
        shutil.copyfile(masters[i % len(masters)], out[-1])
    return out


def _commands(pythons, files, root: Path, frames: list[Path]) -> dict[tuple[str, str], list]:
    """(row, checkout) -> command."""
    pattern = str(frames[0].parent / "plate.####.exr")
    out = {}
    for who, py in pythons.items():
        cli = [py, "-m", "ocio_vp.cli"]
        calib = root / who
        rows = [("3x3 Q (least squares)", "least-squares", [])]
        rows.append(("default Q", "auto", []))
        if who == "this":  # the option is new
            rows.append(("default Q, `--via config`", "auto", ["--via", "config"]))
        for label, method, extra in rows:
            solution = calib / method / "incandescent"
            folder = root / "o" / who / f"{method}{len(extra)}"
            out[(f"`apply`, {label}", who)] = [
                *cli, "apply", str(solution), pattern, "--out", str(folder),
                "--overwrite", "--no-progress", *extra,
            ]  # fmt: skip
    return out


def _solve_commands(pythons, files, root: Path) -> dict[tuple[str, str], list]:
    out = {}
    for who, py in pythons.items():
        cli = [py, "-m", "ocio_vp.cli", "solve"]
        o = str(root / "s" / who)
        out[("`solve`, 24 patches, 1 environment, least squares", who)] = [
            *cli, str(files["one"]), "--out", o, "--method", "least-squares",
        ]  # fmt: skip
        out[("`solve`, 24 patches, 1 environment, default", who)] = [
            *cli, str(files["one"]), "--out", o,
        ]  # fmt: skip
        out[("`solve`, 1000 patches, least squares", who)] = [
            *cli, str(files["chart"]), "--out", o, "--method", "least-squares",
        ]  # fmt: skip
        out[("`solve`, 1000 patches, default", who)] = [*cli, str(files["chart"]), "--out", o]
        many = f"`solve`, {files['many'].stem.removeprefix('env')} environments, default"
        out[(many, who)] = [*cli, str(files["many"]), "--out", o]
    # What running OpenBLAS single-threaded (ocio_vp.cli.SMALL_MATRIX_COMMANDS) buys: the same
    # solve with a thread a core, as numpy would start them and as 1631fec ran.
    threads = ["env", f"OPENBLAS_NUM_THREADS={os.cpu_count()}"]
    out[(f"{many}, OpenBLAS on every core", "this")] = [*threads, *out[(many, "this")]]
    return out


def _rounds(commands: dict, rounds: int, env: dict, cwd: Path, warmup: bool = True) -> dict:
    cells = {key: Cell() for key in commands}
    for cmd in commands.values() if warmup else ():  # page cache, bytecode cache
        _run(cmd, env, cwd)
    for _ in range(rounds):
        for key, cmd in commands.items():
            wall, cpu = _run(cmd, env, cwd)
            cells[key].wall.append(wall)
            cells[key].cpu.append(cpu)
    return cells


def _paired(commands: dict, plain_key, env: dict, cwd: Path) -> tuple[dict, dict]:
    """One round where every command runs right after its own plain read + write: (cells,
    row -> the plain run just before it). On a shared machine the load drifts over a long
    sequence's round (minutes a command); a ratio to one plain run at the start of the round
    then measures where in the round a command ran more than the command (the 48-frame
    rows of a loaded run got slower in the order they ran, whichever checkout or Q)."""
    plain_cmd = commands[plain_key]
    cells, plains = {}, {}
    for key, cmd in commands.items():
        if key == plain_key:
            continue
        plain_wall, plain_cpu = _run(plain_cmd, env, cwd)
        plains[key] = Cell([plain_wall], [plain_cpu])
        wall, cpu = _run(cmd, env, cwd)
        cells[key] = Cell([wall], [cpu])
    return cells, plains


def _fmt(seconds: float) -> str:
    return f"{seconds:.2f} s"


def _table(
    cells: dict,
    rows: list[str],
    plain: Cell | None,
    targets: dict[str, str],
    plains: dict | None = None,
) -> str:
    header = ["command", "this checkout: wall (CPU)", f"{BASELINE_COMMIT}: wall (CPU)"]
    if plain is not None:
        header += ["speed / plain read + write: this", BASELINE_COMMIT]
    header.append("target")
    body = []
    for row in rows:
        line = [row]
        speeds = []
        for who in ("this", "baseline"):
            cell = cells.get((row, who))
            if cell is None:
                line.append("not run")
                speeds.append("-")
                continue
            wall, cpu = cell.best()
            line.append(f"{_fmt(wall)} ({_fmt(cpu)})")
            if plain is not None:
                reference = (plains or {}).get((row, who), plain)
                speeds.append(f"{reference.best()[0] / wall:.2f}x")
        if plain is not None:
            line += speeds
        line.append(targets.get(row, ""))
        body.append(line)
    return markdown_table(header, body)


def _apply_section(pythons, files, root, env, count: int, rounds: int) -> tuple[str, dict]:
    """The section's text, and (row, checkout) -> CPU seconds a frame (of the best run)."""
    frames = _frames(root, files["master"], count)
    commands = {("plain read + write", "this"): [
        pythons["this"], "-c", CHILD, "plain", str(root / "o" / "plain"), *map(str, frames),
    ]}  # fmt: skip
    commands.update(_commands(pythons, files, root, frames))
    load = os.getloadavg()[0]
    plain_key = ("plain read + write", "this")
    plains = None
    if count <= 8:
        cells = _rounds(commands, rounds, env, root)
        plain = cells.pop(plain_key)
    else:  # once, each command after its own plain run (frames in the page cache: just copied)
        cells, plains = _paired(commands, plain_key, env, root)
        plain = Cell(
            [w for c in plains.values() for w in c.wall],
            [u for c in plains.values() for u in c.cpu],
        )
    agreement = _agreement(root / "o" / "this", frames[0].name)
    rows = list(dict.fromkeys(row for row, _ in cells))
    targets = {
        "`apply`, 3x3 Q (least squares)": ">= 0.9x",
        "`apply`, default Q": ">= 0.5x",
        "`apply`, default Q, `--via config`": ">= 0.9x",
    }
    wall, cpu = plain.best()
    if plains is None:
        how = f"best of {rounds} rounds"
        plain_text = f"{_fmt(wall)} ({_fmt(cpu)} CPU)"
    else:
        how = "one round, each command right after its own plain read + write"
        walls = sorted(plain.wall)
        plain_text = (
            f"{_fmt(walls[0])} to {_fmt(walls[-1])} over the round (each speed below is against "
            "the plain run just before the command)"
        )
    per_frame = {key: cell.best()[1] / count for key, cell in cells.items()}
    per_frame[plain_key] = cpu / count
    floor = "" if plains is not None else _chain_floor(root, frames[0], cpu / count)
    text = "\n".join(
        [
            f"### `apply` on {count} frames ({_frame_size(files)} half-float zip EXR), {how}",
            "",
            f"Plain OpenImageIO read + write of the same frames: {plain_text}. "
            f"Load average (1 min) at the start: {load:.1f} on {os.cpu_count()} cores, at the "
            f"end: {os.getloadavg()[0]:.1f}.",
            "",
            _table(cells, rows, plain, targets, plains),
            "",
            agreement,
            *(["", floor] if floor else []),
        ]
    )
    return text, per_frame


def _per_frame_line(short: tuple[int, dict], long: tuple[int, dict]) -> str:
    """CPU a frame on the long sequence against the short one, per command: the load changes
    wall times far more than the CPU a frame costs, so a cost growing with the length of the
    sequence shows here even on a busy machine."""
    (n, few), (m, many) = short, long
    ratios = [
        f"{row.removeprefix('`apply`, ')} {many[(row, who)] / few[(row, who)]:.2f}x"
        + ("" if who == "this" else f" ({BASELINE_COMMIT})")
        for row, who in many
        if (row, who) in few
    ]
    return (
        f"- CPU a frame on {m} frames / on {n} frames, each command (a cost that grew with the "
        f"sequence's length would show here, whatever the load): {'; '.join(ratios)}."
    )


def _agreement(out: Path, name: str) -> str:
    """How far ``--via config`` (the config's LUT chain) is from the exact model on a frame."""
    import OpenImageIO as oiio

    exact = oiio.ImageBuf(str(out / "auto0" / name)).get_pixels(oiio.FLOAT).astype(np.float64)
    chain = oiio.ImageBuf(str(out / "auto2" / name)).get_pixels(oiio.FLOAT).astype(np.float64)
    scale = np.maximum(np.abs(exact).max(axis=-1), 1e-3)
    relative = np.abs(chain - exact).max(axis=-1) / scale
    return (
        f"- `--via config` against the exact model on {name} (half output): "
        f"{np.percentile(relative, 99) * 100:.3g}% of the pixel's largest channel at the 99th "
        f"percentile, {relative.max() * 100:.3g}% at worst; the model itself is computed in "
        "float32 on half frames (within 5e-7 of float64, tested)."
    )


def _cpu_best(work, frame: np.ndarray, repeats: int = 5) -> float:
    """Least CPU seconds of ``work`` on a fresh copy of ``frame`` (the copy not counted)."""
    best = np.inf
    for _ in range(repeats):
        buf = frame.copy()
        start = time.process_time()
        work(buf)
        best = min(best, time.process_time() - start)
    return best


def _chain_floor(root: Path, frame_path: Path, plain_cpu: float) -> str:
    """Why ``--via config`` cannot reach 0.9x here: the CPU a 4K half frame costs in each piece
    of its chain, against the plain read + write's CPU a frame (both cores are busy either
    way, so speed / plain is at most plain CPU / (plain CPU + the transform's))."""
    import OpenImageIO as oiio
    import PyOpenColorIO as OCIO

    from ocio_vp.footage.apply import OcioTransform, load_post_correction, pixel_transform

    frame = np.ascontiguousarray(oiio.ImageBuf(str(frame_path)).get_pixels(oiio.HALF)[..., :3])
    solution = root / "this" / "auto" / "incandescent"
    chain = pixel_transform(load_post_correction(solution, via="config"))
    half = OCIO.BIT_DEPTH_F16

    def ocio(transform) -> OcioTransform:
        processor = OCIO.Config.CreateRaw().getProcessor(transform)
        return OcioTransform(
            None, processor.getOptimizedCPUProcessor(half, half, OCIO.OPTIMIZATION_NONE)
        )

    costs = {
        "the config's chain (what `--via config` runs)": _cpu_best(chain, frame),
        "the exact model (the default)": _cpu_best(pixel_transform(load_post_correction(
            solution)), frame),
        "an identity-valued 33^3 3D LUT alone (the least a LUT chain costs)": _cpu_best(
            ocio(OCIO.Lut3DTransform(33)), frame),
        "an identity matrix (OCIO's half conversions alone, what a 3x3 Q costs)": _cpu_best(
            ocio(OCIO.MatrixTransform()), frame),
    }  # fmt: skip
    body = [
        [name, f"{cpu * 1000:.0f} ms", f"{plain_cpu / (plain_cpu + cpu):.2f}x"]
        for name, cpu in costs.items()
    ]
    return "\n".join(
        [
            f"CPU of one core for one {frame.shape[1]}x{frame.shape[0]} half frame in this "
            f"process (best of 5), against the plain read + write's {plain_cpu:.2f} s of CPU a "
            "frame in the rounds above. Where reading and writing keep both cores busy, a "
            "command's speed / plain read + write is at most plain CPU / (plain CPU + transform "
            "CPU), the speed bound below (a plain loop that leaves a core partly idle lets a "
            "command go faster than it):",
            "",
            markdown_table(["transform (one thread)", "CPU a frame", "speed bound"], body),
        ]
    )


def _frame_size(files) -> str:
    import OpenImageIO as oiio

    spec = oiio.ImageInput.open(str(sorted(files["master"].glob("*.exr"))[0])).spec()
    return f"{spec.width}x{spec.height}"


def _solve_section(pythons, files, root, env, rounds: int) -> str:
    commands = _solve_commands(pythons, files, root)
    load = os.getloadavg()[0]
    longest = {k: v for k, v in commands.items() if "environments" in k[0]}
    small = {k: v for k, v in commands.items() if k not in longest}
    cells = _rounds(small, rounds, env, root)
    cells.update(_rounds(longest, 1, env, root, warmup=False))  # the longest: once
    rows = list(dict.fromkeys(row for row, _ in commands))
    many = files["many"].stem.removeprefix("env")
    within = f"<= 1.05x {BASELINE_COMMIT}"
    targets = dict.fromkeys(rows[:2], within)
    targets.update({
        "`solve`, 1000 patches, least squares": f"<= 2 s, {within}",
        "`solve`, 1000 patches, default": f"<= 3 s, {within}",
        f"`solve`, {many} environments, default": (
            f"<= 20 s, {within}" if many == "150" else within
        ),
    })  # fmt: skip
    return "\n".join(
        [
            f"### `solve`, best of {rounds} rounds ({many} environments: one run)",
            "",
            f"Load average (1 min) at the start: {load:.1f} on {os.cpu_count()} cores.",
            "",
            _table(cells, rows, None, targets),
        ]
    )


#: ``export`` targets timed, each a row (every checkout has them; ``all`` differs between them).
EXPORT_TARGETS = ("unreal", "nuke", "resolve")


def _export_section(pythons, root: Path, env, rounds: int) -> str:
    """``export`` of each checkout's own default-Q solution (the calibrations its apply rows
    use), one row a target, rounds interleaved."""
    commands = {}
    for who, py in pythons.items():
        for target in EXPORT_TARGETS:
            commands[(f"`export --target {target}`, default Q", who)] = [
                py, "-m", "ocio_vp.cli", "export", str(root / who / "auto" / "incandescent"),
                "--target", target, "--out", str(root / "x" / who),
            ]  # fmt: skip
    load = os.getloadavg()[0]
    cells = _rounds(commands, rounds, env, root)
    rows = list(dict.fromkeys(row for row, _ in commands))
    return "\n".join(
        [
            f"### `export`, best of {rounds} rounds",
            "",
            f"Load average (1 min) at the start: {load:.1f} on {os.cpu_count()} cores.",
            "",
            _table(cells, rows, None, dict.fromkeys(rows, f"<= 1.05x {BASELINE_COMMIT}")),
        ]
    )


def _solve_calibrations(pythons, files, root: Path, env) -> None:
    """Each checkout's own solutions of the incandescent environment, for its apply rows."""
    for who, py in pythons.items():
        for method in ("least-squares", "auto"):
            cmd = [py, "-m", "ocio_vp.cli", "solve", str(files["one"]), "--out"]
            _run([*cmd, str(root / who / method), "--method", method], env, root)


#: The sections of :func:`run`, in the order they run.
SECTIONS = ("apply", "export", "solve")


def run(quick: bool = False, sections: Sequence[str] = SECTIONS, rounds: int | None = None) -> str:
    """The whole-command sections named in ``sections`` (all by default, as
    ``python -m benchmarks.run`` runs them); ``rounds`` overrides the rounds of the export
    and solve sections (``python -m benchmarks.bench_regression --sections export --rounds 5``
    times the export rows alone, a minute or so, to iterate on them)."""
    baseline = os.environ.get(BASELINE_ENV)
    pythons = {"this": sys.executable}
    if baseline:
        pythons["baseline"] = baseline = os.path.abspath(baseline)  # commands run elsewhere
    repeats = rounds or (1 if quick else 2)
    with tempfile.TemporaryDirectory() as tmp, cached_bytecode() as env:
        root = Path(tmp)
        env = {**env, "PYTHONPATH": ""}  # each interpreter imports its own checkout
        files = _inputs(root, quick, frames="apply" in sections)
        if "apply" in sections or "export" in sections:
            _solve_calibrations(pythons, files, root, env)
        parts = [
            "## Whole commands against last round",
            "",
            __doc__.split("\n\n", 1)[1].replace("\n", " ").strip(),
            "",
            f"Baseline: {'`' + baseline + '`' if baseline else f'not run ({BASELINE_ENV} unset)'}.",
            "",
        ]
        costs = []
        for count in () if "apply" not in sections else (3,) if quick else (6, 48):
            apply_rounds = 1 if (quick or count > 8) else 3
            text, per_frame = _apply_section(pythons, files, root, env, count, apply_rounds)
            costs.append((count, per_frame))
            parts += [text, ""]
            shutil.rmtree(root / f"frames{count}")
            shutil.rmtree(root / "o", ignore_errors=True)
        if len(costs) == 2:
            parts[-1:] = [_per_frame_line(*costs), ""]
        if "export" in sections:
            parts += [_export_section(pythons, root, env, repeats), ""]
        if "solve" in sections:
            parts += [_solve_section(pythons, files, root, env, repeats)]
    return "\n".join(parts)


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.bench_regression",
        description="Some of the whole-command sections alone, printed (docs/performance.md "
        "is written by python -m benchmarks.run --only regression --update).",
    )
    parser.add_argument("--quick", action="store_true", help="smaller inputs, one round")
    parser.add_argument("--sections", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    parser.add_argument("--rounds", type=int, default=None, help="rounds of export and solve")
    args = parser.parse_args(argv)
    print(run(quick=args.quick, sections=args.sections, rounds=args.rounds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
