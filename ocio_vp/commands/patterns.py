"""``ocio-vp patterns --out DIR``: the frames a wall plays for calibration (or validation)."""

from __future__ import annotations

import argparse
import re
from collections import Counter
from pathlib import Path

from ocio_vp.choices import WALL_ENCODINGS
from ocio_vp.commands.common import progress
from ocio_vp.errors import InputError, excerpt

__all__ = ["add_parser", "parse_size", "run"]


def parse_size(text: str) -> tuple[int, int]:
    """``"1920x1080"`` -> (1920, 1080)."""

    m = re.fullmatch(r"\s*(\d{1,5})\s*[xX]\s*(\d{1,5})\s*", text)
    if not m:
        raise InputError(
            f"expected WIDTHxHEIGHT, e.g. 1920x1080, got {excerpt(text)}", key="--size"
        )
    return int(m.group(1)), int(m.group(2))


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "patterns",
        help="write the calibration patterns the wall plays (frames + sequence.yaml)",
        description="Write the calibration sequence as image frames for a media server or "
        "Unreal: sync flashes, black, red, green and blue at full drive, white, one ramp per "
        "channel (spaced in the wall's signal, dense near black), and DIR/sequence.yaml, which "
        "`ocio-vp measure` reads to find them in a camera take. With --validate, the chart of "
        "a solved environment through its own config instead (for `ocio-vp validate`). Play "
        "the frames with every colour transform bypassed (docs/patterns.md).",
    )
    parser.add_argument("--out", required=True, help="output folder (a re-run replaces it)")
    parser.add_argument(
        "--wall-encoding",
        type=str.lower,
        choices=WALL_ENCODINGS,
        default="linear",
        help="the wall's signal: ramps are spaced in it, and TIFF/DPX frames hold it "
        "(EXR frames always hold linear drive)",
    )
    parser.add_argument(
        "--peak-nits",
        type=float,
        default=None,
        help="cd/m2 of drive 1.0: required with --wall-encoding pq, an error otherwise (no "
        "default)",
    )
    parser.add_argument("--size", default="1920x1080", help="frame size WIDTHxHEIGHT")
    parser.add_argument(
        "--format",
        type=str.lower,
        choices=("exr", "tiff", "dpx"),
        default="exr",
        help="exr: half-float linear drive; tiff: 16-bit signal; dpx: 10-bit signal (full range)",
    )
    parser.add_argument("--fps", type=float, default=24.0, help="the player's frame rate")
    parser.add_argument("--hold", type=int, default=12, help="frames each patch is held")
    parser.add_argument(
        "--steps", type=int, default=17, help="ramp steps per channel (zero and full included)"
    )
    parser.add_argument("--first-frame", type=int, default=1, help="number of the first frame")
    parser.add_argument(
        "--validate",
        metavar="ENVIRONMENT_DIR",
        default=None,
        help="write the validation sequence of a solved environment (calib/<environment>): its "
        "target chart through its config.ocio, in-frustum; the wall encoding is the solve's "
        "(default: the calibration sequence)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.patterns.design import PatternOptions, calibration_sequence
    from ocio_vp.patterns.frames import write_sequence_folder
    from ocio_vp.staging import check_not_input, check_replaceable, publish_dir, staged_dir

    if not 0 <= args.first_frame <= 10**8:
        raise InputError("expected a frame number from 0 to 1e8", key="--first-frame")
    options = PatternOptions(
        fps=args.fps,
        hold=args.hold,
        steps=args.steps,
        encoding=args.wall_encoding,
        peak_nits=args.peak_nits,
        size=parse_size(args.size),
        file_format=args.format,
        first_frame=args.first_frame,
        name="validation" if args.validate else "patterns",
    )
    final = Path(args.out)
    inputs = [args.validate] if args.validate else []
    check_not_input([final], inputs)
    check_replaceable(final)
    if args.validate:
        from ocio_vp.patterns.validation import validation_sequence

        sequence = validation_sequence(args.validate, options)
    else:
        sequence = calibration_sequence(options)
    count = sequence.last_frame - sequence.first_frame + 1
    with staged_dir(final.resolve().parent) as stage:
        with progress(total=count, desc="frames", unit="frame") as bar:
            write_sequence_folder(sequence, stage / "out", on_frame=lambda: bar.update(1))
        publish_dir(stage / "out", final, inputs=inputs)
    _print_summary(sequence, final)
    return 0


def _print_summary(sequence, final) -> None:
    kinds = Counter(patch.kind for patch in sequence.patches)
    count = sequence.last_frame - sequence.first_frame + 1
    peak = f" at {sequence.peak_nits:g} cd/m2" if sequence.peak_nits else ""
    content = (
        "EXR: linear drive"
        if sequence.file_format == "exr"
        else (f"{sequence.file_format.upper()}: {sequence.encoding} signal, full range")
    )
    print(
        f"wrote {final}/: {count} frames ({sequence.duration:.1f} s at {sequence.fps:g} fps, "
        f"{sequence.size[0]}x{sequence.size[1]}, {content}); wall encoding "
        f"{sequence.encoding}{peak}; " + ", ".join(f"{n} {k}" for k, n in kinds.items())
    )
    then = (
        f"then run ocio-vp validate ENVIRONMENT TAKE --sequence {final}/sequence.yaml"
        if sequence.validation is not None
        else f"then point a capture file's take.sequence at {final}/sequence.yaml"
    )
    print(
        f"play {final}/{sequence.frames} with every colour transform bypassed, record it in one "
        f"take, {then} (docs/patterns.md)"
    )
