"""Do the exported configs give the same numbers in every OpenColorIO a studio runs?

    python -m benchmarks.ocio_compat [--versions 2.2.1 2.3.2 2.4.2 2.5.2 2.6.0]
                                     [--venvs DIR] [--solves DIR ...] [--keep]

Creates one throwaway venv per OCIO version (``pip install opencolorio==V numpy`` from PyPI;
``--venvs DIR`` keeps and reuses them), solves and exports a test matrix unless ``--solves``
names folders already exported (the demo's seven environments, and the demo stage with a
``ramps`` section solved for a linear, gamma 2.4, sRGB and PQ wall, and without ramps for gamma
2.4 and PQ: 49 environments), then runs :mod:`benchmarks.ocio_compat_worker` in each venv. The worker
loads every ``.ocio`` and ``.ocioz``, builds every processor (colorspace pairs, display/views
both ways, named transforms both ways, every ``.clf``/``.cube`` as a FileTransform), applies it
on the CPU to inputs in [-1, 16] (out-of-gamut and HDR included) and extracts its HLSL shader
as Unreal does.

Pass: in every version every config loads and validates, every processor builds, gives finite
values no larger than 1e6 and a shader, all copies of one config agree exactly, and every
number is within ``1e-5 * max(1, |newest|)`` of the newest version's. Prints a Markdown table
(the one in docs/exports.md) and exits 1 on any failure. It is not a unit test (installing five
OCIO wheels takes minutes); ``tests/test_ocio_compat.py`` checks the same invariants with the
installed OCIO.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # `python benchmarks/ocio_compat.py` from anywhere
    sys.path.insert(0, str(ROOT))

WORKER = Path(__file__).resolve().parent / "ocio_compat_worker.py"
VERSIONS = ("2.2.1", "2.3.2", "2.4.2", "2.5.2", "2.6.0")
#: Cross-version tolerance: absolute below 1, relative above (float32 spacing grows with size).
TOLERANCE = 1e-5
#: No processor may take longer than this to build from cold (a host that offers it hangs).
MAX_BUILD_SECONDS = 1.0
LOW, HIGH = -1.0, 16.0


def test_inputs(seed: int = 0) -> np.ndarray:
    """RGB rows in [-1, 16]: a grid through black, mid-grey, white, HDR and negative values,
    uniform random points of the whole cube, and of [0, 1]^3 (SDR content)."""
    levels = np.array([-1.0, -0.05, 0.0, 0.01, 0.18, 0.5, 1.0, 2.0, 4.0, 16.0])
    grid = np.stack(np.meshgrid(levels, levels, levels, indexing="ij"), -1).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    return np.concatenate(
        [grid, rng.uniform(LOW, HIGH, (500, 3)), rng.uniform(0.0, 1.0, (500, 3))]
    ).astype(np.float32)


def make_venv(folder: Path, version: str) -> Path:
    """A venv with ``opencolorio==version`` (reused when it already has it)."""
    python = folder / "bin" / "python"
    check = [str(python), "-c", "import PyOpenColorIO as O, numpy; print(O.__version__)"]
    if python.exists():
        found = subprocess.run(check, capture_output=True, text=True)
        if found.returncode == 0 and found.stdout.strip() == version:
            return python
    subprocess.run([sys.executable, "-m", "venv", "--clear", str(folder)], check=True)
    subprocess.run(
        [str(python), "-m", "pip", "install", "-q", f"opencolorio=={version}", "numpy"],
        check=True,
    )
    return python


def add_ramps(document: dict) -> dict:
    """A ``ramps`` section measured on a wall whose red is d^1.1 and blue d^0.95 (flare 0.002)."""
    drive = np.linspace(0.0, 1.0, 17)
    curves = (drive**1.1, drive, drive**0.95)
    channels = ("red", "green", "blue")
    SL = np.array([document["primaries"][c] for c in channels], dtype=np.float64).T
    document = dict(document)
    document["ramps"] = {
        c: {"drive": drive.tolist(), "camera": (np.outer(curves[k], SL[:, k]) + 0.002).tolist()}
        for k, c in enumerate(channels)
    }
    return document


def build_solves(root: Path) -> list[Path]:
    """Solve and export the test matrix into ``root``; returns the solve folders."""
    import yaml

    from ocio_vp.cli import main as cli

    def run(*args: str) -> None:
        if cli(list(args)) != 0:
            raise SystemExit(f"ocio-vp {' '.join(args)} failed")

    run("demo", "--out", str(root / "demo"), "--no-report")
    stage = root / "demo" / "paper_stage.yaml"
    # the non-linear models: emitter-protected (auto), and the root-polynomial everywhere (a
    # rank-deficient one under sodium vapour, where N is not solved)
    models = [
        (root / "protect", ["--protect-emitters"]),
        (root / "rp", ["--method", "root-polynomial"]),
    ]
    for out, options in models:
        run("solve", str(stage), "--out", str(out), *options)
    ramps = root / "paper_stage_ramps.yaml"
    document = yaml.safe_load(stage.read_text())
    ramps.write_text(yaml.safe_dump(add_ramps(document)))
    solves = [root / "demo", *(out for out, _ in models)]
    for measurements, encoding in [(ramps, "linear"), (ramps, "gamma2.4"), (ramps, "srgb"),
                                   (ramps, "pq"), (stage, "gamma2.4"), (stage, "pq")]:  # fmt: skip
        out = root / f"{measurements.stem}_{encoding}"
        run("solve", str(measurements), "--out", str(out), "--wall-encoding", encoding)
        solves.append(out)
    for solve in solves:
        environments = sorted(str(p.parent) for p in solve.glob("*/solution.json"))
        run("export", *environments, "--target", "all")
    return solves


def run_worker(python: Path, inputs: Path, result: Path, solves: list[Path]) -> dict:
    started = time.perf_counter()
    done = subprocess.run(
        [str(python), str(WORKER), str(inputs), str(result), *map(str, solves)],
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        raise RuntimeError(f"worker failed with {python}:\n{done.stderr[-3000:]}")
    data = np.load(result)
    meta = json.loads(str(data["__meta__"]))
    meta["values"] = {k: data[k] for k in data.files if k != "__meta__"}
    meta["seconds"] = time.perf_counter() - started
    return meta


def compare(results: dict[str, dict], newest: str) -> list[dict]:
    """One row per version: its problems plus its worst difference to ``newest``."""
    reference = results[newest]["values"]
    rows = []
    for meta in results.values():
        problems = list(meta["problems"])
        worst, worst_key = 0.0, ""
        for key, ref in reference.items():
            got = meta["values"].get(key)
            if got is None:
                problems.append(f"{key}: missing")
                continue
            scale = np.maximum(1.0, np.abs(ref.astype(np.float64)))
            diff = np.abs(got.astype(np.float64) - ref) / scale
            finite = np.isfinite(diff)
            if not finite.all():
                problems.append(f"{key}: non-finite")
            if finite.any() and diff[finite].max() > worst:
                worst, worst_key = float(diff[finite].max()), key
        extra = set(meta["values"]) - set(reference)
        problems += [f"{key}: not in {newest}" for key in sorted(extra)]
        if worst > TOLERANCE:
            problems.append(f"worst difference {worst:.3g} > {TOLERANCE:g} ({worst_key})")
        if meta["slowest_build"][0] > MAX_BUILD_SECONDS:
            problems.append(f"slowest build {meta['slowest_build'][0]:.2f} s > "
                            f"{MAX_BUILD_SECONDS:g} s: {meta['slowest_build'][1]}")  # fmt: skip
        rows.append({"version": meta["version"], "processors": meta["processors"],
                     "worst": worst, "worst_key": worst_key, "problems": problems,
                     "seconds": meta["seconds"], "slowest": meta["slowest_build"]})  # fmt: skip
    return rows


def table(rows: list[dict], newest: str, samples: int) -> str:
    lines = [
        f"| OCIO | processors | worst difference to {newest} (x max(1, abs)) "
        "| slowest cold build (both directions of every colorspace and named transform) "
        "| problems | result |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        status = "pass" if not row["problems"] else "FAIL"
        seconds, what = row["slowest"]
        where = what.split("/")[-2] + ": " + what.split(": ", 1)[-1] if "/" in what else what
        lines.append(
            f"| {row['version']} | {row['processors']} | {row['worst']:.2g} "
            f"| {seconds * 1e3:.0f} ms ({where}) | {len(row['problems'])} | {status} |"
        )
    lines.append(f"\n{samples} inputs per processor in [{LOW:g}, {HIGH:g}]^3.")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--versions", nargs="+", default=list(VERSIONS))
    parser.add_argument("--venvs", type=Path, help="keep the venvs here and reuse them")
    parser.add_argument("--solves", type=Path, nargs="+", help="exported solve folders to check")
    parser.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = parser.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="ocio-compat-"))
    try:
        solves = args.solves or build_solves(work / "solves")
        inputs = work / "inputs.npy"
        np.save(inputs, test_inputs())
        results = {}
        for version in args.versions:
            python = make_venv((args.venvs or work / "venvs") / f"ocio-{version}", version)
            results[version] = run_worker(python, inputs, work / f"{version}.npz", solves)
            print(f"OCIO {version}: {results[version]['processors']} processors, "
                  f"{len(results[version]['problems'])} problems, "
                  f"{results[version]['seconds']:.0f} s", flush=True)  # fmt: skip
        newest = args.versions[-1]
        rows = compare(results, newest)
        for row in rows:
            for problem in row["problems"][:20]:
                print(f"  {row['version']}: {problem}")
            if len(row["problems"]) > 20:
                print(f"  {row['version']}: ... {len(row['problems']) - 20} more")
        print(table(rows, newest, len(np.load(inputs))))
        return 1 if any(row["problems"] for row in rows) else 0
    finally:
        if args.keep:
            print(f"kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
