"""The same pixels in every host: each host's rendering of the post-correction against the model.

    python -m benchmarks.bench_hosts [--quick] [--out docs/hosts.md]

For every Q method (:data:`ocio_vp.choices.Q_METHODS`) and environment (the paper's seven and
high-pressure sodium) of the simulator's paper stage, with and without ``--protect-emitters``:
solve, write the config (``ocio_vp.ocio.write_solutions``), export Resolve, and measure ΔE2000
against the exact float64 model (``correction.apply``) over the camera range footage spans
(:func:`ocio_vp.simulator.truth.stage_footage_range`: surfaces lit by the wall at 1/16-4x with
noise, near black with negative channels, highlights to 16x white, narrow-band emitters from
420 to 680 nm at 1/4, 1 and 4 times white's luminance and the wall's own primaries). Hosts:

- ``apply``: ``ocio-vp apply``'s pixel transform on float32 pixels (the model, or the config's
  processor for a matrix);
- ``config``: the config's ``Stage Footage`` -> reference processor (OCIO, CPU, float32), and
  the ``Post-Correction Q`` named transform (the same chain: its worst difference is listed);
- ``CLF``: Resolve's ``post_correction_Q.clf`` applied by ``oiiotool --ociofiletransform`` (the
  OpenColorIO bundled in OpenImageIO, another build) to a float EXR;
- ``DCTL``: ``post_correction_Q.dctl`` compiled by gcc in tests/test_exports_resolve.py's
  harness;
- ``cube``: ``post_correction_Q_33.cube`` where the export writes one (OCIO's reader,
  tetrahedral), on the pixels inside its input range;
- ``in-frustum``: content (the corrected camera range without near black, where every channel
  of the corrected side's mix is positive: ``ocio_vp.ocio.bake.content_range``) -> the
  config's in-frustum drive -> the wall [SL] -> the exact model, against the content, where N
  is solved.

Each cell is ``p99 / worst`` over all sets; a second table splits the non-linear models by set.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from ocio_vp.ocio.bake import processor_function  # noqa: E402
from ocio_vp.simulator.data import PAPER_ENVIRONMENTS  # noqa: E402

DOC = "hosts.md"
ENVIRONMENTS = (*PAPER_ENVIRONMENTS, "high_pressure_sodium")
QUICK_ENVIRONMENTS = ("incandescent", "direct_sun", "high_pressure_sodium")
QUICK_METHODS = ("least-squares", "auto", "root-polynomial")
HOSTS = ("apply", "config", "CLF", "DCTL", "cube", "in-frustum")


def _float32(function):
    def apply(rgb):
        return np.asarray(function(np.asarray(rgb, dtype=np.float32)), dtype=np.float64)

    return apply


def _ocio(config, src, dst):
    return processor_function(config.getProcessor(src, dst))


def ocio_function(transform):
    """An OCIO transform as a function on (n, 3) RGB (CPU, float32)."""
    import PyOpenColorIO as OCIO

    return processor_function(OCIO.Config.CreateRaw().getProcessor(transform))


def _apply_host(folder: Path):
    """``ocio-vp apply``'s own pixel transform for the solution in ``folder``."""
    from ocio_vp.footage.apply import load_post_correction, pixel_transform

    transform = pixel_transform(load_post_correction(folder))

    def apply(rgb):
        pixels = np.ascontiguousarray(np.asarray(rgb, dtype=np.float32).reshape(1, -1, 3))
        transform(pixels)
        return pixels.reshape(-1, 3).astype(np.float64)

    return apply


def _oiiotool(clf: Path, work: Path):
    """The CLF through oiiotool (OpenImageIO's own OpenColorIO) on a one-row float EXR."""
    import OpenImageIO as oiio

    def apply(rgb):
        rgb = np.asarray(rgb, dtype=np.float32).reshape(1, -1, 3)
        src, dst = work / "in.exr", work / "out.exr"
        out = oiio.ImageOutput.create(str(src))
        out.open(str(src), oiio.ImageSpec(rgb.shape[1], 1, 3, "float"))
        out.write_image(rgb)
        out.close()
        command = ["oiiotool", str(src), "--ociofiletransform", str(clf), "-d", "float"]
        subprocess.run([*command, "-o", str(dst)], check=True, capture_output=True)
        return oiio.ImageBuf(str(dst)).get_pixels(oiio.FLOAT).reshape(-1, 3).astype(np.float64)

    return apply


def _dctl(dctl: Path, work: Path):
    """The DCTL compiled by gcc in the test suite's harness (DCTL's types and math as C99)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_exports_resolve import MATH_HARNESS

    source, binary = work / "harness.c", work / "harness"
    source.write_text(MATH_HARNESS % dctl.resolve())
    subprocess.run(
        ["gcc", "-std=c99", "-O1", "-o", str(binary), str(source), "-lm"],
        check=True,
        capture_output=True,
    )

    def apply(rgb):
        rows = []
        for chunk in np.array_split(np.asarray(rgb, dtype=np.float32), max(1, len(rgb) // 500)):
            args = [f"{v!r}" for v in chunk.astype(float).ravel()]
            done = subprocess.run([str(binary), *args], capture_output=True, text=True, check=True)
            rows += [[float(v) for v in line.split()] for line in done.stdout.splitlines()]
        return np.asarray(rows, dtype=np.float64)

    return apply


def _cube(cube: Path):
    import PyOpenColorIO as OCIO

    OCIO.ClearAllCaches()  # OCIO caches files by path: every solve writes a cube of this name
    return ocio_function(OCIO.FileTransform(src=str(cube), interpolation=OCIO.INTERP_TETRAHEDRAL))


def _within(footage, low, high):
    from ocio_vp.model.footage_range import FootageRange

    sets = {k: v[np.all((v >= low) & (v <= high), axis=1)] for k, v in footage.sets.items()}
    return FootageRange(sets, footage.camera_to_xyz, footage.white)


def _in_frustum(solution, config, footage):
    """Content -> in-frustum drive -> [SL] -> the exact model, against the content."""
    from ocio_vp.model.footage_range import agreement
    from ocio_vp.ocio import IN_FRUSTUM, REFERENCE
    from ocio_vp.ocio.bake import content_range

    correction = solution.correction
    content = content_range(footage, correction)
    drive = _ocio(config, REFERENCE, IN_FRUSTUM)
    offset = solution.in_frustum_offset

    def seen(c):
        return correction.apply((drive(c) - offset) @ np.asarray(solution.SL).T)

    return agreement(content, lambda c: c, seen)


def measure(stage, measurements, environment, method, protect, work: Path) -> dict:
    """Every host's agreement for one solve (see the module docstring)."""
    import json

    import PyOpenColorIO as OCIO

    from ocio_vp.exports import export_solutions
    from ocio_vp.model.footage_range import agreement
    from ocio_vp.ocio import POST_CORRECTION_COLORSPACE, REFERENCE, write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.truth import stage_footage_range

    solution = solve_environment(
        measurements, measurements.environment(environment), method=method,
        protect_emitters=protect,
    )  # fmt: skip
    start = time.perf_counter()
    (solution,) = write_solutions([solution], work / "solved")
    written = time.perf_counter() - start
    folder = work / "solved" / environment
    export_solutions([folder], targets=["resolve"])
    resolve = folder / "exports" / "resolve"
    manifest = json.loads((resolve / "manifest.json").read_text())
    config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
    footage = stage_footage_range(stage, environment, solution)
    exact = solution.correction.apply
    hosts = {
        "apply": _apply_host(folder),
        "config": _ocio(config, POST_CORRECTION_COLORSPACE, REFERENCE),
        "CLF": _oiiotool(resolve / "post_correction_Q.clf", work),
        "DCTL": _dctl(resolve / "post_correction_Q.dctl", work),
    }
    row = {name: agreement(footage, exact, host) for name, host in hosts.items()}
    cube = next((k for k in manifest["files"] if k.startswith("post_correction_Q_")), None)
    if cube is not None:
        low, high = manifest["files"][cube]["accuracy"]["input_range"]
        row["cube"] = agreement(_within(footage, low, high), exact, _cube(resolve / cube))
    if solution.N is not None:
        row["in-frustum"] = _in_frustum(solution, config, footage)
    named = _named(config)
    x = footage.all()
    row["named_vs_config"] = float(np.abs(named(x) - hosts["config"](x)).max())
    row["kind"] = solution.correction.kind
    row["write_seconds"] = written
    shutil.rmtree(work / "solved")
    return row


def _named(config):
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio import POST_CORRECTION

    named = config.getNamedTransform(POST_CORRECTION)
    return processor_function(config.getProcessor(named, OCIO.TRANSFORM_DIR_FORWARD))


def _cell(measured) -> str:
    if measured is None:
        return "-"
    p99, worst = measured.overall
    flag = "" if measured.within(0.5, 2.0) else " **!**"
    return f"{p99:.2g} / {worst:.2g}{flag}"


def _tables(rows: list[tuple[str, str, bool, dict]]) -> str:
    from benchmarks import markdown_table
    from ocio_vp.model.footage_range import SETS

    out = []
    for protect in (False, True):
        body = [
            [method, env, row["kind"], *(_cell(row.get(h)) for h in HOSTS), _seconds(row)]
            for method, env, p, row in rows
            if p == protect
        ]
        title = "with `--protect-emitters`" if protect else "without emitter protection"
        out += [f"### Every host against the model, {title}", ""]
        out.append(markdown_table(["method", "environment", "kind", *HOSTS, "write"], body))
        out.append("")
    by_set = [
        [method + (" +protect" if p else ""), env, *(_set_cell(row["config"], s) for s in SETS)]
        for method, env, p, row in rows
        if row["kind"] != "matrix" and row["kind"] != "rank-deficient"
    ]
    out += ["### The config's LUT chain by set (non-linear models)", ""]
    out.append(markdown_table(["method", "environment", *SETS], by_set))
    return "\n".join(out)


def _seconds(row) -> str:
    return f"{row['write_seconds']:.2f} s"


def _set_cell(measured, name) -> str:
    return f"{measured.p99[name]:.2g} / {measured.worst[name]:.2g}"


def run(quick: bool = False) -> str:
    from ocio_vp.choices import Q_METHODS
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    environments = QUICK_ENVIRONMENTS if quick else ENVIRONMENTS
    methods = QUICK_METHODS if quick else Q_METHODS
    stage = paper_stage()
    measurements = simulate_measurements(environments, stage=stage)
    rows = []
    work = Path(tempfile.mkdtemp(prefix="bench_hosts_"))
    started = time.perf_counter()
    try:
        for protect in (False, True):
            for method in methods:
                for env in environments:
                    row = measure(stage, measurements, env, method, protect, work)
                    rows.append((method, env, protect, row))
                    print(f"bench_hosts: {method} {env} protect={protect} {row['kind']} "
                          f"config {_cell(row['config'])}", file=sys.stderr, flush=True)  # fmt: skip
    finally:
        shutil.rmtree(work, ignore_errors=True)
    named = max(row["named_vs_config"] for *_, row in rows)
    return "\n".join(
        [
            "# The same pixels in every host",
            "",
            "Generated by `python -m benchmarks.bench_hosts"
            + (" --quick" if quick else "")
            + " --out docs/hosts.md` (do not edit by hand; "
            f"{time.perf_counter() - started:.0f} s). ΔE2000 of each host against the exact "
            "float64 model, p99 / worst over the camera range of "
            "`ocio_vp.model.footage_range` on the simulator's paper stage (surfaces lit by "
            "the wall at 1/16-4x with noise, near black with negative channels, highlights "
            "to 16x white, narrow-band emitters 420-680 nm and the wall's primaries at 1/4, "
            "1 and 4 times white's luminance); **!** marks a cell beyond 0.5 (p99) or 2 "
            "(worst). `cube`: only on pixels inside the cube's input range, and only where "
            "the export writes one; `in-frustum`: content -> the config's in-frustum drive "
            "-> the wall -> the exact model, against the content (where N is solved). The "
            f"named transform and the colorspace differ by at most {named:.2g} on any pixel. "
            "`write`: writing the environment's config (its LUT chains and their check).",
            "",
            _tables(rows),
        ]
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    text = run(quick=args.quick)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
