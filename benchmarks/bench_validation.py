"""What ``ocio-vp validate`` reports for right and wrong calibrations on the simulated stage.

Writes ``docs/validation_study.md``: ``python -m benchmarks.bench_validation --out
docs/validation_study.md`` (or ``python -m benchmarks.run``, which writes it too). The day
runs as a user runs it: ``simulate --plates`` (the calibration take included), ``measure``,
``solve``, ``patterns --validate``, ``simulate --film``, ``validate``; then the same take is
filmed with one thing wrong each time:

- the camera 1/3 stop brighter than during calibration;
- the player not bypassing its colour transforms: the wall shown sRGB-decoded EXR values;
- the wrong environment's config playing the chart (incandescent's for direct sun);
- a solve without the ramps (the wall's darkening near black not corrected).

Two stages: the paper-like default and one the sample data does not use (Sigma SDMerill
camera, LEDs 620/535/455 nm).
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

DOC = "validation_study.md"
STAGES = {
    "paper-like (Nikon 5100, 630/525/460 nm)": [],
    "other (Sigma SDMerill, 620/535/455 nm)": [
        "--camera",
        "Sigma SDMerill (NPL)",
        "--leds",
        "620/25,535/30,455/20",
    ],
}
ENVIRONMENTS = ("direct_sun", "incandescent", "warm_white_led", "outdoor_shade")


def _cli(*args: str) -> int:
    from ocio_vp.cli import main

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return main(list(args))


def _validate(root: Path, calib: Path, env: str, take: Path, sequence: Path, out: str) -> dict:
    _cli(
        "validate",
        str(calib / env),
        str(take / "A001.####.exr"),
        "--sequence",
        str(sequence),
        "--out",
        str(root / out),
    )
    return json.loads((root / out / "validation.json").read_text())["delta_e2000"]


def _film(root: Path, stage_args: list[str], sequence, name: str, **take) -> Path:
    """Film ``sequence`` (an object: drives as given) on the simulated stage of the day."""
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
    from ocio_vp.simulator.take import TakeOptions, write_take

    kwargs = {}
    if stage_args:
        kwargs = {"camera": stage_args[1], "leds": [(620, 25), (535, 30), (455, 20)]}
    stage = spectral_stage(**kwargs)
    env = sequence.validation.environment
    measurements = simulate_measurements([env], stage=stage)
    bounce = tuple(float(v) for v in measurements.environments[0].black_level)
    options = TakeOptions(bounce=bounce, **take)
    write_take(sequence, measurements.SL, root / name, options)
    return root / name


def _day(root: Path, stage_args: list[str], ramps: bool = True) -> Path:
    envs = [a for e in ENVIRONMENTS for a in ("--environment", e)]
    _cli(
        "simulate",
        "--out",
        str(root / "truth.yaml"),
        "--plates",
        str(root / "plates"),
        *envs,
        *stage_args,
    )
    _cli("measure", str(root / "plates" / "capture.yaml"), "--out", str(root / "stage.yaml"))
    stage = root / "stage.yaml"
    if not ramps:
        data = yaml.safe_load(stage.read_text())
        data.pop("ramps")
        stage = root / "stage_noramps.yaml"
        stage.write_text("# Written by ocio-vp\n" + yaml.safe_dump(data))
    calib = root / ("calib" if ramps else "calib_noramps")
    _cli("solve", str(stage), "--out", str(calib), "--method", "least-squares")
    return calib


def _patterns(root: Path, calib: Path, env: str, name: str):
    from ocio_vp.patterns.sequence import load_sequence

    _cli("patterns", "--out", str(root / name), "--validate", str(calib / env), "--size", "16x9")
    return load_sequence(root / name / "sequence.yaml")


def _with_drives(sequence, drives: dict):
    """The sequence with other drives on some patches (frames not read: ``source`` None)."""
    patches = tuple(
        dataclasses.replace(p, drive=drives.get(p.name, p.drive)) for p in sequence.patches
    )
    return dataclasses.replace(sequence, patches=patches, source=None)


def _scenarios(root: Path, stage_args: list[str]) -> list[tuple[str, str, dict]]:
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.patterns.validation import wall_signal

    rows = []
    calib = _day(root, stage_args)
    for env in ENVIRONMENTS:
        seq = _patterns(root, calib, env, f"check_{env}")
        take = _film(root, stage_args, seq, f"take_{env}")
        rows.append((env, "right", _validate(root, calib, env, take, seq.source, f"v_{env}")))
    env = "direct_sun"
    seq = _patterns(root, calib, env, "check")
    take = _film(root, stage_args, seq, "bright", exposure=2 ** (1 / 3))
    rows.append(
        (env, "camera 1/3 stop brighter", _validate(root, calib, env, take, seq.source, "v1"))
    )
    srgb = {
        p.name: tuple(
            float(v)
            for v in np.where(
                np.array(p.drive) <= 0.04045,
                np.array(p.drive) / 12.92,
                ((np.array(p.drive) + 0.055) / 1.055) ** 2.4,
            )
        )
        for p in seq.of_kind("chart", "black")
    }
    take = _film(root, stage_args, _with_drives(seq, srgb), "srgb")
    rows.append((env, "player decodes sRGB", _validate(root, calib, env, take, seq.source, "v2")))
    other = load_solution(calib / "incandescent")
    charts = seq.of_kind("chart")
    content = np.array([p.content for p in charts])
    drives = wall_signal(calib / "incandescent" / "config.ocio", other, content)
    wrong = {
        p.name: tuple(float(v) for v in np.maximum(d, 0))
        for p, d in zip(charts, drives, strict=True)
    }
    take = _film(root, stage_args, _with_drives(seq, wrong), "wrongenv")
    rows.append(
        (env, "incandescent's config played", _validate(root, calib, env, take, seq.source, "v3"))
    )
    plain = _day(root, stage_args, ramps=False)
    seq = _patterns(root, plain, env, "check_plain")
    take = _film(root, stage_args, seq, "plain")
    rows.append(
        (env, "solved without the ramps", _validate(root, plain, env, take, seq.source, "v4"))
    )
    return rows


def run(quick: bool = False) -> str:
    lines = [
        "# Validation on the simulated stage: right and wrong calibrations",
        "",
        "Generated by `python -m benchmarks.bench_validation --out docs/validation_study.md` "
        "(do not edit by hand). The commands of the README's day, on two simulated stages; each "
        "validation take is filmed at 25 fps against the 24 fps patterns, with flicker, noise and "
        "the environment's light bouncing off the wall. ΔE2000 over the chart patches the wall "
        "can show (`ocio-vp validate`); verdict at p95 <= 3.",
        "",
        "| stage | environment | case | mean | p95 | worst | patches judged | verdict |",
        "|---|---|---|---:|---:|---:|---:|---|",
    ]
    stages = dict(list(STAGES.items())[:1]) if quick else STAGES
    for label, args in stages.items():
        root = Path(tempfile.mkdtemp(prefix="ocio-vp-bench-validation-"))
        try:
            for env, case, stats in _scenarios(root, args):
                verdict = "pass" if stats["p95"] <= 3 else "**fail**"
                lines.append(
                    f"| {label} | {env} | {case} | {stats['mean']:.2f} | {stats['p95']:.2f} | "
                    f"{stats['max']:.2f} | {stats['patches_judged']} | {verdict} |"
                )
        finally:
            shutil.rmtree(root, ignore_errors=True)
    lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.bench_validation", description=__doc__
    )
    parser.add_argument("--quick", action="store_true", help="the paper-like stage only")
    parser.add_argument("--out", help="write the markdown here (default: print it)")
    args = parser.parse_args(argv)
    text = run(quick=args.quick)
    if args.out:
        Path(args.out).write_text(text + "\n", encoding="utf-8")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
