"""``ocio-vp apply SOLUTION_DIR FRAMES... --out DIR``: post-correct footage with Q."""

from __future__ import annotations

import argparse
import sys

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "apply",
        help="post-correct footage shot on the stage (Q) with OCIO, keeping every channel",
        description="Apply the solution's post-correction (its config's 'Stage Footage' -> "
        "reference) to frames, writing DIR/<frame name>. Alpha, depth and AOV channels, "
        "metadata, data window and compression are kept. Frames already in DIR are skipped "
        "(resume); a bad frame is reported and the others are still done (exit 2 at the end).",
    )
    parser.add_argument("solution", metavar="SOLUTION_DIR", help="an environment folder of solve")
    parser.add_argument(
        "frames",
        metavar="FRAMES",
        nargs="+",
        help="frame files or patterns: plate.####.exr (n '#' = n digits), plate.%%04d.exr",
    )
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument(
        "--frames",
        dest="frame_range",
        metavar="FIRST-LAST",
        help="frame range for patterns (default: the frames that exist); missing ones are errors",
    )
    parser.add_argument("--overwrite", action="store_true", help="redo frames already in --out")
    parser.add_argument(
        "--workers", type=int, default=None, help="local processes (default: one per core)"
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask cluster, e.g. tcp://farm-scheduler:8786 (see docs/distributed.md)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tqdm import tqdm

    from ocio_vp.footage.apply import FrameTask, load_post_correction, run_task
    from ocio_vp.footage.distributed import default_workers, map_unordered
    from ocio_vp.footage.sequences import expand_frames, output_paths, parse_frame_range

    post = load_post_correction(args.solution)
    frame_range = parse_frame_range(args.frame_range) if args.frame_range else None
    inputs = expand_frames(args.frames, frames=frame_range)
    outputs = output_paths(inputs, Path(args.out))
    workers = default_workers() if args.workers is None else args.workers
    # One frame at a time in this process: let it use every core; in a pool, one core each.
    threads = default_workers() if (workers == 1 and not args.scheduler) else 1
    tasks = [
        FrameTask(str(s), str(d), post, overwrite=args.overwrite, threads=threads)
        for s, d in zip(inputs, outputs, strict=True)
    ]
    counts = {"done": 0, "skipped": 0, "input-error": 0, "error": 0}
    bar = tqdm(total=len(tasks), unit="frame", disable=args.no_progress or None, file=sys.stderr)
    with bar:
        for i, result in map_unordered(run_task, tasks, workers=workers, scheduler=args.scheduler):
            if isinstance(result, BaseException):  # a worker died: count it, keep going
                counts["error"] += 1
                bar.write(f"ocio-vp apply: error: {tasks[i].src}: {result}", file=sys.stderr)
            else:
                counts[result.status] += 1
                if result.status in ("input-error", "error"):
                    bar.write(f"ocio-vp apply: error: {result.message}", file=sys.stderr)
            bar.update(1)
    failed = counts["input-error"] + counts["error"]
    print(
        f"{counts['done']} frame(s) written, {counts['skipped']} already done, "
        f"{failed} failed -> {args.out}"
    )
    if counts["error"]:
        return 1
    return 2 if counts["input-error"] else 0
