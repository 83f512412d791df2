"""``ocio-vp validate ENVIRONMENT TAKE --sequence SEQ --out DIR``: the calibration on the wall."""

from __future__ import annotations

import argparse
from pathlib import Path

from ocio_vp.commands.common import warn
from ocio_vp.errors import InputError

__all__ = ["FAILED_STATUS", "add_parser", "run"]

#: Exit status of a validation that ran and failed its threshold (2 is a user mistake).
FAILED_STATUS = 3


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    # Not from ocio_vp.validation: that package loads numpy and the readers at every start.
    from ocio_vp.choices import DEFAULT_VALIDATION_THRESHOLD as DEFAULT_THRESHOLD

    parser = subparsers.add_parser(
        "validate",
        help="measure a take of the validation sequence and judge the calibration on the wall",
        description="Measure a camera take of the validation sequence (`ocio-vp patterns "
        "--validate ENVIRONMENT`: the environment's chart through its own config, in-frustum), "
        "post-correct it as the solve prescribes, and compare every patch with what it should "
        "read, in CIE ΔE2000 (mean, 95th percentile, worst patch). Writes DIR/validation.json, "
        "DIR/index.html and the take's contact sheet. Exit status 0 when it passes, "
        f"{FAILED_STATUS} when it fails, 2 on bad input (docs/validation.md).",
    )
    parser.add_argument("environment", help="a solved environment folder, e.g. calib/direct_sun")
    parser.add_argument("take", help="the take's frames, e.g. take/B001.####.exr")
    parser.add_argument(
        "--sequence", required=True, help="the validation sequence.yaml that was played"
    )
    parser.add_argument("--out", required=True, help="output folder (a re-run replaces it)")
    parser.add_argument(
        "--region",
        type=int,
        nargs=4,
        metavar=("X0", "Y0", "X1", "Y1"),
        default=None,
        help="the wall's region in pixels, end-exclusive (default: found automatically)",
    )
    parser.add_argument(
        "--encoding",
        default=None,
        help="the take's encoding, a colour.CCTF_DECODINGS name such as 'ARRI LogC3' (default: "
        "linear)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=DEFAULT_THRESHOLD,
        help="pass when the 95th percentile of ΔE2000 is at most this",
    )
    parser.set_defaults(func=run)


def _check_sequence(sequence, environment_dir, solution) -> None:
    import hashlib

    v = sequence.validation
    if v is None:
        raise InputError(
            "a calibration sequence, not a validation one: write it with ocio-vp patterns "
            "--validate ENVIRONMENT",
            source=sequence.source,
        )
    from ocio_vp.formats.provenance import SolutionIdentity, solution_identity

    path = Path(environment_dir) / "solution.json"
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != v.solution_sha256:
        made = SolutionIdentity(v.environment, v.model or "?", v.solved or "?")
        differs = made.differences(solution_identity(environment_dir, solution))
        raise InputError(
            f"made from another solution: {differs}; write the patterns again from this solve "
            "and film them",
            source=sequence.source,
            key="validation.solution_sha256",
        )


def run(args: argparse.Namespace) -> int:
    from ocio_vp.choices import canonical_encoding
    from ocio_vp.commands.measure import TakeProgress
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.plates.take import TakeRef, measure_take
    from ocio_vp.staging import check_not_input, check_replaceable, publish_dir, staged_dir
    from ocio_vp.validation.compare import compare_take
    from ocio_vp.validation.write import write_validation

    if not 0 < args.threshold < 100:
        raise InputError(f"expected 0 < ΔE2000 < 100, got {args.threshold:g}", key="--threshold")
    final = Path(args.out)
    take_folder = Path(args.take).parent
    check_not_input([final], [args.environment, args.sequence, take_folder])
    check_replaceable(final)
    solution = load_solution(args.environment)
    sequence = load_sequence(args.sequence)
    _check_sequence(sequence, args.environment, solution)
    encoding = (
        None if args.encoding is None else canonical_encoding(args.encoding, key="--encoding")
    )
    region = None if args.region is None else tuple(args.region)
    if region is not None and not (region[2] > region[0] >= 0 and region[3] > region[1] >= 0):
        raise InputError(
            f"expected x1 > x0 >= 0 and y1 > y0 >= 0, got {list(region)}", key="--region"
        )
    take = TakeRef(
        frames=Path(args.take), sequence=Path(args.sequence), region=region, encoding=encoding
    )
    bar = TakeProgress()
    try:
        reading = measure_take(take, source=args.take, on_progress=bar)
    finally:
        bar.close()
    result = compare_take(solution, sequence, reading, threshold=args.threshold)
    assert sequence.validation is not None  # _check_sequence refused a calibration sequence
    sources = {
        "solution_sha256": sequence.validation.solution_sha256,
        "sequence_sha256": sequence.sha256,
        "take": Path(args.take).name,
    }
    with staged_dir(final.resolve().parent) as stage:
        lines = write_validation(
            result, reading, stage / "out", sources=sources, pulled=sequence.validation.pulled
        )
        publish_dir(stage / "out", final, inputs=[args.environment, args.sequence, take_folder])
    for warning in reading.warnings:
        warn("validate", warning)
    print("\n".join(lines))
    from ocio_vp.plates.contact_sheet import SHEET

    print(f"wrote {final}/validation.json, index.html and {SHEET}")
    return 0 if result.passed else FAILED_STATUS
