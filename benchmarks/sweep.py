"""A robustness sweep of the whole tool: ``python -m benchmarks.sweep [--quick]``.

Runs ``ocio-vp`` as a user would (one subprocess per command, in a scratch folder) over a grid
of simulated stages the project's data does not contain, and checks the standards' promises on
every run (docs/robustness.md):

- **spectral** stages: every camera ``simulate --camera`` accepts, each on two of four LED
  sets (the default, shifted, wide, narrow), three of the environments
  ``simulate --list-environments`` offers (rotating), a ``--method`` rotating through all of
  them, ``--protect-emitters`` on a quarter and ``--camera-colorspace "ARRI Wide Gamut 4"`` on
  a third; then ``export --target all``, ``export --target show``, ``report``;
- **plates** stages: ``simulate --plates``, ``measure`` the plates, ``solve`` in the camera's
  gamut, the exports, ``apply`` on the simulated footage (linear, and LogC4-encoded with
  ``--footage-encoding``), ``report``, ``validate`` (``patterns --validate``,
  ``simulate --film``, ``validate``);
- **encoding** stages: ``patterns --wall-encoding E``, a take of them (ramps), ``measure``,
  ``solve --wall-encoding E`` for linear, gamma2.4, srgb and pq;
- **ceiling** stages: ``simulate --ceiling-leds`` (two panel types, the scenes lit from above);
- **edge** stages: LEDs no stage should have (identical, 10 nm apart, a 400 nm blue).

For every command it records the exit status, a traceback or "internal error" on stderr, any
non-finite number in a JSON/YAML file it wrote (and in the configs, CLFs, cubes, Nuke scripts,
DCTLs and corrected EXR frames), staging folders or partial files left behind, an output
folder changed by a command that failed, and the wall time. A refusal (exit 2, one line) is not
a failure; it is counted and listed by message. The failures are printed grouped by the first
line of the error, each with the smallest command chain that reproduces it (a chain on many
environments is retried on the one environment the error names).

``--quick`` runs six stages, one of each kind (a few minutes on 2 cores); the full sweep (35
stages, about 10 minutes on 2 busy cores) also writes its tables into docs/robustness.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from ocio_vp.choices import Q_METHODS, WALL_ENCODINGS  # noqa: E402

DOC = ROOT / "docs" / "robustness.md"
BEGIN, END = "<!-- sweep:begin -->", "<!-- sweep:end -->"

LED_SETS = {
    "default": None,
    "shifted": "620/20,535/35,455/22",
    "wide": "610/30,545/50,470/30",
    "narrow": "640/15,515/25,450/15",
}
# LEDs no stage should have: refused on one line, or warned about.
EDGE_LEDS = {
    "identical": "530/30,530/30,530/30",
    "close": "520/30,530/30,540/30",
    "deep-blue": "630/20,525/35,400/5",
}
CEILING_LEDS = ("618/24,538/40,470/26", "640/15,515/25,450/15")
CAMERA_GAMUT = "ARRI Wide Gamut 4"
FOOTAGE_ENCODING = "ARRI LogC4"
PATTERN_SIZE = "64x36"
STEP_TIMEOUT = 600.0
# Files scanned for non-finite numbers: parsed (JSON, YAML) or searched as text.
PARSED = (".json", ".yaml", ".yml")
TEXT = (".ocio", ".clf", ".cube", ".nk", ".dctl", ".ctf", ".spi1d", ".spi3d", ".html", ".svg")
TEXT += (".md", ".txt", ".csv")
NON_FINITE_TEXT = re.compile(r"(?<![\w.])[-+]?(?:nan|inf|infinity)(?![\w(])", re.IGNORECASE)
# The one documented non-finite figure: cond_Q of a singular Q is the string "inf"
# (docs/stability.md; the terminal and the report say "> 1e+12").
ALLOWED_NON_FINITE = ("diagnostics.cond_Q",)
NON_FINITE_WORD = re.compile(r"[-+]?(?:nan|inf|infinity)", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class Step:
    """One command of a stage's chain; ``argv`` starts with ``ocio-vp`` or ``python``."""

    name: str
    argv: tuple[str, ...]
    outputs: tuple[str, ...] = ()  # paths (relative to the stage folder) the command writes
    needs: tuple[str, ...] = ()  # earlier steps that must have succeeded


@dataclasses.dataclass(frozen=True)
class Stage:
    """A simulated stage and what is run on it."""

    kind: str  # spectral, plates, encoding, ceiling
    camera: str
    leds: str  # a LED_SETS key
    environments: tuple[str, ...]
    method: str = "auto"
    protect: bool = False
    gamut: bool = False
    encoding: str = "linear"
    ceiling: str | None = None
    validate: bool = False
    fixture: str | None = None  # simulate --fixture KIND
    paper_black: bool = False  # solve --black-level paper

    @property
    def label(self) -> str:
        parts = [self.kind, self.camera.split(" (")[0], self.leds, self.method]
        parts += ["protect"] * self.protect + ["gamut"] * self.gamut
        parts += [self.fixture or ""] * bool(self.fixture) + ["paper-black"] * self.paper_black
        parts += [self.encoding] * (self.kind == "encoding")
        return "/".join(parts)


@dataclasses.dataclass(frozen=True)
class Run:
    """What one command did."""

    stage: Stage
    step: str
    command: str  # the chain up to this command, as a user would type it
    status: int | None  # None: skipped (an earlier step failed)
    seconds: float
    error: str  # the first line that says what went wrong ('' if none)
    problems: tuple[str, ...]  # traceback, internal error, non-finite, half-written, timeout


# ---------------------------------------------------------------------------------------------
# The grid


def _names() -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    from ocio_vp.simulator.data import ENVIRONMENTS
    from ocio_vp.simulator.panels import SCENES
    from ocio_vp.spectra import camera_names

    return camera_names(), tuple(ENVIRONMENTS), tuple(SCENES)


def grid(quick: bool) -> list[Stage]:
    """The stages of the sweep (``quick``: one of each kind)."""
    cameras, environments, scenes = _names()
    leds = tuple(LED_SETS)
    spectral = []
    for k, (ci, li) in enumerate((c, (c + 2 * j) % 4) for j in range(2) for c in range(12)):
        spectral.append(
            Stage(
                "spectral",
                cameras[ci % len(cameras)],
                leds[li],
                tuple(environments[(3 * k + j) % len(environments)] for j in range(3)),
                method=Q_METHODS[k % len(Q_METHODS)],
                protect=k % 4 == 1,
                gamut=k % 3 == 0,
                fixture=("rgbw", "rgbacl", "rgbww", "rgbw-fluorescent")[k // 6]
                if k % 6 == 2
                else None,
                paper_black=k % 5 == 3,
            )
        )
    plates = [
        Stage("plates", cameras[1], "shifted", ("direct_sun", "high_pressure_sodium"),
              method="root-polynomial", protect=True, gamut=True, validate=True),
        Stage("plates", cameras[4], "narrow", ("incandescent", "sodium_vapour"),
              method="least-squares", protect=True, gamut=True, validate=True),
    ]  # fmt: skip
    encoding = [
        Stage("encoding", cameras[(3 * i + 2) % len(cameras)], leds[(i + 1) % 4],
              ("direct_sun", "incandescent"), method=("auto", "root-polynomial")[i % 2],
              gamut=i % 2 == 1, encoding=enc)
        for i, enc in enumerate(WALL_ENCODINGS)
    ]  # fmt: skip
    ceiling = [
        Stage("ceiling", cameras[5], "wide", scenes, method="root-polynomial", protect=True,
              gamut=True, ceiling=CEILING_LEDS[0]),
        Stage("ceiling", cameras[1], "shifted", scenes, method="least-squares",
              ceiling=CEILING_LEDS[1]),
    ]  # fmt: skip
    edge = [
        Stage("edge", cameras[0], name, ("direct_sun", "sodium_vapour", "rgb_led_white"))
        for name in EDGE_LEDS
    ]
    if quick:
        return [spectral[1], spectral[9], plates[0], encoding[3], ceiling[0], edge[0]]
    return spectral + plates + encoding + ceiling + edge


def _simulate(stage: Stage, *, plates: bool = False, sequence: str | None = None) -> Step:
    argv = ["ocio-vp", "simulate", "--out", "stage.yaml", "--camera", stage.camera]
    spectra = LED_SETS.get(stage.leds) or EDGE_LEDS.get(stage.leds)
    if spectra:
        argv += ["--leds", spectra]
    if stage.ceiling:
        argv += ["--ceiling-leds", stage.ceiling]
    for env in stage.environments:
        argv += ["--environment", env]
    if stage.fixture:
        argv += ["--fixture", stage.fixture]
    outputs = ["stage.yaml"]
    if plates:
        argv += ["--plates", "plates"] + (["--sequence", sequence] if sequence else [])
        outputs.append("plates")
    return Step("simulate", tuple(argv), tuple(outputs), ("patterns",) if sequence else ())


def _solve(stage: Stage, measurements: str, needs: str) -> Step:
    argv = ["ocio-vp", "solve", measurements, "--out", "calib", "--method", stage.method]
    if stage.protect:
        argv.append("--protect-emitters")
    if stage.gamut:
        argv += ["--camera-colorspace", CAMERA_GAMUT]
    if stage.paper_black:
        argv += ["--black-level", "paper"]
    if stage.encoding != "linear":
        argv += ["--wall-encoding", stage.encoding]
    if stage.encoding == "pq":
        argv += ["--peak-nits", "1000"]
    return Step("solve", tuple(argv), ("calib",), (needs,))


def _outputs_steps(stage: Stage) -> list[Step]:
    steps = [
        Step("export all", ("ocio-vp", "export", "calib", "--target", "all"), ("calib",),
             ("solve",)),
        Step("export show", ("ocio-vp", "export", "calib", "--target", "show", "--out", "show"),
             ("show",), ("solve",)),
        Step("report", ("ocio-vp", "report", "calib"), ("calib/report",), ("solve",)),
    ]  # fmt: skip
    return steps


def _footage_steps(stage: Stage) -> list[Step]:
    env = stage.environments[0]
    frames = f"plates/footage/{env}.####.exr"
    encoded = f"logc4/{env}.####.exr"
    return [
        Step("apply", ("ocio-vp", "apply", f"calib/{env}", frames, "--out", "applied"),
             ("applied",), ("solve",)),
        Step("encode footage", (sys.executable, "-m", "benchmarks.sweep", "encode-footage",
                                frames, "logc4", "--encoding", FOOTAGE_ENCODING),
             ("logc4",), ("simulate",)),
        Step("apply log", ("ocio-vp", "apply", f"calib/{env}", encoded, "--out", "applied_log",
                           "--footage-encoding", FOOTAGE_ENCODING),
             ("applied_log",), ("solve", "encode footage")),
    ]  # fmt: skip


def _validate_steps(stage: Stage) -> list[Step]:
    env = f"calib/{stage.environments[0]}"
    film = list(_simulate(stage).argv)
    film[film.index("stage.yaml")] = "truth.yaml"
    return [
        Step("patterns validate", ("ocio-vp", "patterns", "--out", "check", "--size",
                                   PATTERN_SIZE, "--validate", env), ("check",), ("solve",)),
        Step("simulate film", (*film, "--film", "check/sequence.yaml", "--take", "check_take"),
             ("truth.yaml", "check_take"), ("patterns validate",)),
        Step("validate", ("ocio-vp", "validate", env, "check_take/A001.####.exr", "--sequence",
                          "check/sequence.yaml", "--out", "validation"),
             ("validation",), ("simulate film",)),
    ]  # fmt: skip


def steps(stage: Stage) -> list[Step]:
    """The chain of commands run on ``stage``, in order."""
    if stage.kind in ("spectral", "ceiling", "edge"):
        return [_simulate(stage), _solve(stage, "stage.yaml", "simulate"), *_outputs_steps(stage)]
    chain = []
    if stage.kind == "encoding":
        argv = ["ocio-vp", "patterns", "--out", "patterns", "--size", PATTERN_SIZE,
                "--wall-encoding", stage.encoding]  # fmt: skip
        argv += ["--peak-nits", "1000"] if stage.encoding == "pq" else []
        chain.append(Step("patterns", tuple(argv), ("patterns",)))
    sequence = "patterns/sequence.yaml" if stage.kind == "encoding" else None
    chain += [
        _simulate(stage, plates=True, sequence=sequence),
        Step("measure", ("ocio-vp", "measure", "plates/capture.yaml", "--out", "measured.yaml"),
             ("measured.yaml",), ("simulate",)),
        _solve(stage, "measured.yaml", "measure"),
        *_outputs_steps(stage),
    ]  # fmt: skip
    if stage.kind == "plates":
        chain += _footage_steps(stage)
    if stage.validate:
        chain += _validate_steps(stage)
    return chain


# ---------------------------------------------------------------------------------------------
# Running a stage and checking what each command left


def _snapshot(folder: Path, outputs: tuple[str, ...]) -> dict[str, tuple[int, int]]:
    """Every file under the step's outputs: relative path -> (size, mtime_ns)."""
    found = {}
    for output in outputs:
        path = folder / output
        for file in [path] if path.is_file() else path.rglob("*") if path.is_dir() else []:
            if file.is_file():
                st = file.stat()
                found[str(file.relative_to(folder))] = (st.st_size, st.st_mtime_ns)
    return found


def _first_error(stderr: str) -> str:
    lines = stderr.strip().splitlines()
    if any(line.startswith("Traceback") for line in lines):
        return next((ln for ln in reversed(lines) if ln and not ln.startswith(" ")), lines[-1])
    return next((ln for ln in lines if ": error: " in ln), lines[-1] if lines else "")


def _walk_non_finite(value, key: str) -> Iterator[str]:
    # A non-finite number written as text ("-inf") is one too.
    text = isinstance(value, str) and NON_FINITE_WORD.fullmatch(value.strip())
    if text or (isinstance(value, float) and not math.isfinite(value)):
        yield key or "(top)"
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _walk_non_finite(v, f"{key}.{k}" if key else str(k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _walk_non_finite(v, f"{key}[{i}]")


def non_finite(path: Path) -> list[str]:
    """Where ``path`` holds a NaN or an infinity (keys for JSON/YAML, lines for text, 'pixels'
    for an EXR frame)."""
    suffix = path.suffix.lower()
    if suffix in PARSED:
        text = path.read_text(encoding="utf-8", errors="replace")
        try:
            data = json.loads(text) if suffix == ".json" else _load_yaml(text)
        except ValueError as error:
            return [f"unreadable ({str(error).splitlines()[0]})"]
        found = [k for k in _walk_non_finite(data, "") if not k.endswith(ALLOWED_NON_FINITE)]
        return found[:3]
    if suffix in TEXT:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
        return [f"line {i + 1}" for i, ln in enumerate(lines) if NON_FINITE_TEXT.search(ln)][:3]
    if suffix == ".exr":
        import numpy as np
        import OpenImageIO as oiio

        pixels = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)
        return [] if np.isfinite(pixels).all() else ["pixels"]
    return []


def _load_yaml(text: str):
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        return yaml.load(text, Loader=loader)
    except yaml.YAMLError as error:
        raise ValueError(str(error)) from None


def _leftovers(folder: Path) -> list[str]:
    """Staging folders and partial files anywhere in the stage folder."""
    names = []
    for path in folder.rglob(".*"):
        name = path.name
        if name.startswith(".ocio-vp-staging-") or ".partial-" in name or name.endswith(".tmp"):
            names.append(str(path.relative_to(folder)))
    return names


def check_step(folder: Path, step: Step, status: int, stderr: str, before: dict) -> list[str]:
    """The problems one command left: see the module docstring."""
    problems = []
    if "Traceback (most recent call last)" in stderr:
        problems.append("traceback")
    if "internal error" in stderr:
        problems.append("internal error")
    if status not in (0, 2):
        problems.append(f"exit {status}")
    after = _snapshot(folder, step.outputs)
    for name in sorted(k for k, v in after.items() if before.get(k) != v):
        for where in non_finite(folder / name):
            problems.append(f"non-finite: {name}: {where}")
    problems += [f"half-written: {name}" for name in _leftovers(folder)]
    if status != 0 and after != before and not step.name.startswith("apply"):
        changed = sorted(set(after) ^ set(before) | {k for k in after if after[k] != before.get(k)})
        problems.append(f"half-written: output changed by a failed run: {changed[0]}")
    return problems


def _chain_text(done: list[Step]) -> str:
    return " && ".join(shlex.join(("ocio-vp", *s.argv[1:])) if s.argv[0] == "ocio-vp"
                       else shlex.join(("python", *s.argv[1:])) for s in done)  # fmt: skip


def _needed(done: list[Step]) -> list[Step]:
    """The last step of ``done`` and the earlier ones it needs, directly or not, in order."""
    wanted = {done[-1].name}
    for step in reversed(done):
        if step.name in wanted:
            wanted.update(step.needs)
    return [step for step in done if step.name in wanted]


def _run_step(folder: Path, step: Step) -> tuple[int, str, float]:
    argv = list(step.argv)
    if argv[0] == "ocio-vp":
        argv[:1] = [sys.executable, "-m", "ocio_vp"]
    env = {k: v for k, v in os.environ.items() if k != "OCIO_VP_TRACEBACK"}
    env.update(PYTHONPATH=str(ROOT), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    start = time.perf_counter()
    try:
        done = subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True,
                              timeout=STEP_TIMEOUT, check=False)  # fmt: skip
    except subprocess.TimeoutExpired as error:
        stderr = error.stderr.decode() if isinstance(error.stderr, bytes) else error.stderr or ""
        return -9, stderr + f"\ntimeout after {STEP_TIMEOUT:.0f} s", time.perf_counter() - start
    return done.returncode, done.stderr, time.perf_counter() - start


def run_stage(stage: Stage, scratch: Path) -> list[Run]:
    """Run ``stage``'s chain in a fresh folder under ``scratch``; one :class:`Run` per step."""
    folder = Path(tempfile.mkdtemp(prefix="stage-", dir=scratch))
    runs, ok, done = [], set(), []
    for step in steps(stage):
        done.append(step)
        if not all(n in ok for n in step.needs):
            runs.append(Run(stage, step.name, _chain_text(_needed(done)), None, 0.0, "", ()))
            continue
        before = _snapshot(folder, step.outputs)
        status, stderr, seconds = _run_step(folder, step)
        problems = check_step(folder, step, status, stderr, before)
        if status == -9:
            problems.append("timeout")
        if status == 0:
            ok.add(step.name)
        error = _first_error(stderr) if status or problems else ""
        runs.append(Run(stage, step.name, _chain_text(_needed(done)), status, seconds, error,
                        tuple(problems)))  # fmt: skip
        named = [e for e in stage.environments if re.search(rf"\b{e}\b", error)]
        if step.name == "simulate" and status == 2 and len(named) == 1:
            # Do what the refusal says: leave that environment out, as a user would.
            shutil.rmtree(folder, ignore_errors=True)
            rest = tuple(e for e in stage.environments if e != named[0])
            return runs + run_stage(dataclasses.replace(stage, environments=rest), scratch)
    shutil.rmtree(folder, ignore_errors=True)
    return runs


# ---------------------------------------------------------------------------------------------
# Grouping and shrinking failures


def failure_key(run: Run) -> str:
    """A failure's group: the first line of its error (numbers and this stage's names masked)
    or, with no error, its first problem."""
    text = run.error if run.error and run.status not in (0, None) else run.problems[0]
    text = re.sub(r"/tmp/\S*stage-\w+/", "", text)
    for env in run.stage.environments:
        text = text.replace(env, "ENV")
    text = re.sub(r"\[\d+\]", "[#]", text)
    return re.sub(r"(?<![\w.])[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", text)


def _failed(run: Run) -> bool:
    return bool(run.problems)


def shrink(run: Run, scratch: Path) -> str:
    """The smallest chain that still fails the same way: ``run``'s chain on the one environment
    its error names (or on the first), else the chain itself."""
    key = failure_key(run)
    named = [e for e in run.stage.environments if e in run.error + " ".join(run.problems)]
    if len(run.stage.environments) > 1:
        for env in (named or run.stage.environments)[:1]:
            small = dataclasses.replace(run.stage, environments=(env,))
            for again in run_stage(small, scratch):
                if again.step == run.step and _failed(again) and failure_key(again) == key:
                    return again.command
    return run.command


# ---------------------------------------------------------------------------------------------
# Tables


def summary_tables(stages: list[Stage], runs: list[Run], seconds: float) -> list[str]:
    """Markdown: the sweep's size, the runs per command, the refusals."""
    executed = [r for r in runs if r.status is not None]
    lines = [
        f"{len(stages)} stages ({_count(s.kind for s in stages)}), {len(executed)} commands run "
        f"({sum(r.status is None for r in runs)} skipped after a failure), "
        f"{sum(map(_failed, executed))} failed a check; wall time {seconds:.0f} s with "
        f"{JOBS} jobs.",
        "",
        "| command | runs | exit 0 | exit 2 (refused) | failed a check | total s | slowest s |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    by_step = defaultdict(list)
    for run in executed:
        by_step[run.step].append(run)
    for name, group in by_step.items():
        lines.append(
            f"| {name} | {len(group)} | {sum(r.status == 0 for r in group)} | "
            f"{sum(r.status == 2 for r in group)} | {sum(map(_failed, group))} | "
            f"{sum(r.seconds for r in group):.0f} | {max(r.seconds for r in group):.1f} |"
        )
    refusals = Counter(failure_key(r) for r in executed if r.status == 2 and not _failed(r))
    if refusals:
        lines += ["", "Refusals (exit 2, one line), by message:", ""]
        lines += ["| runs | message |", "|---:|---|"]
        lines += [f"| {n} | {_cell(k)} |" for k, n in refusals.most_common()]
    return lines


def failure_table(runs: list[Run], scratch: Path, do_shrink: bool) -> list[str]:
    """Markdown: the failures only, grouped by the first line of the error."""
    groups = defaultdict(list)
    for run in runs:
        if run.status is not None and _failed(run):
            groups[failure_key(run)].append(run)
    if not groups:
        return ["No failures."]
    lines = ["| failure | runs | checks | smallest reproducing command |", "|---|---:|---|---|"]
    for key, group in sorted(groups.items(), key=lambda kv: -len(kv[1])):
        smallest = min(group, key=lambda r: (len(r.stage.environments), len(r.command)))
        command = shrink(smallest, scratch) if do_shrink else smallest.command
        checks = sorted({p.split(":")[0] for r in group for p in r.problems})
        lines.append(f"| {_cell(key)} | {len(group)} | {', '.join(checks)} | `{command}` |")
    return lines


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")[:300]


def _count(items) -> str:
    return ", ".join(f"{n} {k}" for k, n in Counter(items).items())


# ---------------------------------------------------------------------------------------------
# Commands


def encode_footage(pattern: str, out: str, encoding: str) -> None:
    """Write ``pattern``'s EXR frames (camera linear) into ``out``, encoded with colour-science's
    ``encoding`` (independent of ocio-vp): the log footage ``apply --footage-encoding`` takes."""
    import colour
    import OpenImageIO as oiio

    src = Path(pattern)
    regex = re.compile(re.escape(src.name).replace("\\#\\#\\#\\#", r"\d{4}") + "$")
    Path(out).mkdir(exist_ok=True)
    for path in sorted(p for p in src.parent.iterdir() if regex.match(p.name)):
        image = oiio.ImageBuf(str(path))
        pixels = image.get_pixels(oiio.FLOAT)
        encoded = colour.cctf_encoding(pixels[..., :3], function=encoding)
        pixels[..., :3] = encoded
        spec = image.spec()
        result = oiio.ImageBuf(spec)
        result.set_pixels(oiio.ROI(), pixels)
        if not result.write(str(Path(out) / path.name)):
            raise SystemExit(f"cannot write {out}/{path.name}: {result.geterror()}")


def _write_doc(lines: list[str]) -> None:
    text = DOC.read_text(encoding="utf-8")
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    DOC.write_text(f"{head}{BEGIN}\n" + "\n".join(lines) + f"\n{END}{tail}", encoding="utf-8")


JOBS = 2


def sweep(quick: bool, jobs: int, do_shrink: bool) -> int:
    global JOBS
    JOBS = jobs
    stages = grid(quick)
    scratch = Path(tempfile.mkdtemp(prefix="ocio-vp-sweep-"))
    start = time.perf_counter()
    runs: list[Run] = []
    try:
        with ThreadPoolExecutor(jobs) as pool:
            for stage_runs in pool.map(lambda s: run_stage(s, scratch), stages):
                runs += stage_runs
                bad = sum(map(_failed, stage_runs))
                print(f"  {stage_runs[0].stage.label}: {len(stage_runs)} commands, {bad} failed",
                      file=sys.stderr, flush=True)  # fmt: skip
        seconds = time.perf_counter() - start
        lines = summary_tables(stages, runs, seconds)
        lines += ["", "Failures, by the first line of the error:", ""]
        lines += failure_table(runs, scratch, do_shrink)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    print("\n".join(lines))
    if not quick:
        _write_doc(lines)
    return 1 if any(map(_failed, runs)) else 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["encode-footage"]:
        parser = argparse.ArgumentParser(prog="python -m benchmarks.sweep encode-footage")
        parser.add_argument("frames")
        parser.add_argument("out")
        parser.add_argument("--encoding", default=FOOTAGE_ENCODING)
        args = parser.parse_args(argv[1:])
        encode_footage(args.frames, args.out, args.encoding)
        return 0
    parser = argparse.ArgumentParser(prog="python -m benchmarks.sweep", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="one stage of each kind")
    parser.add_argument("--jobs", type=int, default=2, help="stages run at once (default 2)")
    parser.add_argument("--no-shrink", action="store_true", help="do not re-run failures")
    args = parser.parse_args(argv)
    return sweep(args.quick, args.jobs, not args.no_shrink)


if __name__ == "__main__":
    sys.exit(main())
