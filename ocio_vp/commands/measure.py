"""``ocio-vp measure CAPTURE --out MEASUREMENTS``: calibration plates to a measurements file."""

from __future__ import annotations

import argparse

from ocio_vp.commands.common import progress
from ocio_vp.errors import InputError

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "measure",
        help="sample the calibration plates of a capture file into a measurements file",
        description="Read the plates a capture file names (docs/capture.md), sample the chart "
        "patches and regions, and write a measurements file plus an overlay PNG per plate "
        "(OUT_STEM.overlays/) showing exactly which pixels were sampled.",
    )
    parser.add_argument(
        "capture",
        help="capture file (.yaml/.yml/.json), format ocio-vp/capture (see docs/capture.md; "
        "`ocio-vp simulate --plates DIR` writes a sample one)",
    )
    parser.add_argument("--out", required=True, help="measurements file to write (.yaml or .json)")
    parser.add_argument(
        "--overlays", default=None, help="overlay folder (default: next to --out, STEM.overlays)"
    )
    parser.add_argument(
        "--write-corners",
        action="store_true",
        help="write auto-detected chart corners back into the capture file (rewritten: its "
        "comments are lost); by default the capture file is left alone and the corners are "
        "recorded in the overlay folder's samples.json",
    )
    # Earlier versions wrote the corners back by default; their opt-out is the default now.
    parser.add_argument("--no-write-back", action="store_true", help=argparse.SUPPRESS)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.plates.capture import load_capture, save_capture_document, with_corners
    from ocio_vp.plates.measure import (
        measure_capture,
        measure_steps,
        overlay_folder,
        write_measure_outputs,
    )
    from ocio_vp.staging import check_file_replaceable, check_not_input, check_replaceable

    capture = load_capture(args.capture)
    overlays = overlay_folder(args.out, args.overlays)
    # Before any plate is read: no output may be an input or a file ocio-vp did not write.
    check_not_input((args.out, overlays), [capture.source, *capture.plate_paths()])
    check_replaceable(overlays)
    check_file_replaceable(args.out)
    from ocio_vp.plates.detection import DetectionError

    take_bar = TakeProgress()
    with progress(total=measure_steps(capture), desc="measuring", unit="plate") as bar:
        try:
            result = measure_capture(capture, on_step=lambda: bar.update(1), on_take=take_bar)
        except DetectionError as error:
            raise detection_failed(error, overlays) from None
        finally:
            take_bar.close()
    folder = write_measure_outputs(result, args.out, overlays=args.overlays)
    if result.detected and args.write_corners:
        save_capture_document(with_corners(capture.document, result.detected), capture.source)
        print(f"wrote {len(result.detected)} detected chart corner set(s) to {capture.source}")
    for warning in result.warnings:
        print(f"warning: {warning}")
    if result.take is not None:
        print(take_summary(result.take))
    kind = ""
    if result.measurements is None:
        parts = ", ".join(k for k in result.document if k not in ("format", "version", "stage"))
        kind = f" (a part: {parts}; solve it with the other files, docs/measurements.md)"
    from ocio_vp.plates.contact_sheet import SHEET

    sheet = f" and {SHEET}" if result.take is not None else ""
    print(
        f"wrote {args.out}{kind} ({len(result.plates)} plates sampled); overlays{sheet} in {folder}"
    )
    return 0


def detection_failed(error, overlays) -> Exception:
    """Publish the failed search's overlay alone in the overlay folder
    (``<plate>.detection.png``; nothing else is written) and return the one-line error
    naming it."""
    from ocio_vp.plates.detection import detection_overlay
    from ocio_vp.plates.overlay import write_png
    from ocio_vp.staging import publish_dir, staged_dir

    path = overlays / f"{error.name}.detection.png"
    with staged_dir(overlays.parent) as staged:
        write_png(staged / path.name, detection_overlay(error.detection))
        publish_dir(staged, overlays)
    where = f"{overlays.name}/{path.name}"  # beside --out: short, so the line keeps it
    return InputError(f"{error.problem}; overlay: {where}", source=error.source, key=error.key)


class TakeProgress:
    """``on_progress`` for :func:`ocio_vp.plates.take.measure_take`: one bar per pass."""

    def __init__(self) -> None:
        self.bar = None

    def __call__(self, stage: str, frames: int) -> None:
        if stage == "frame":
            if self.bar is not None:
                self.bar.update(frames)
            return
        self.close()
        self.bar = progress(total=frames, desc=f"take: {stage}", unit="frame")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def take_summary(reading) -> str:
    """One line: how the take was placed and measured."""
    a = reading.alignment
    kept = sum(len(p.frames) for p in reading.patches.values())
    return (
        f"take: {len(reading.numbers)} frames, wall region {list(reading.region)}"
        f"{' (found)' if reading.region_found else ''}; {a.rate:.5f} camera frames per player "
        f"frame, {len(a.marks_found)} of {a.marks_expected} sync marks, {a.changes_used} patch "
        f"changes timed; {len(reading.patches)} patches from {kept} frames"
    )
