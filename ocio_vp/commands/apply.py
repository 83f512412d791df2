"""``ocio-vp apply SOLUTION... FRAMES... --out DIR``: post-correct footage with Q."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from ocio_vp.choices import DEFAULT_FOOTAGE_ENCODING, canonical_encoding
from ocio_vp.commands.common import warn
from ocio_vp.commands.report import SOLUTIONS_HELP
from ocio_vp.errors import InputError

if TYPE_CHECKING:  # footage imports OCIO: not at start-up
    from ocio_vp.footage.apply import FrameResult

__all__ = [
    "FREE_SPACE_MARGIN",
    "add_parser",
    "check_free_space",
    "post_correction_caveats",
    "run",
    "split_inputs",
    "write_failure_error",
]

#: ``apply`` refuses to start when the output disk has less free space than this fraction of
#: the frames' estimated size (their inputs' size): clearly too little, not a guess's margin.
FREE_SPACE_MARGIN = 0.8


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "apply",
        help="post-correct footage shot on the stage (Q) with OCIO, keeping every channel",
        description="Apply the solution's post-correction (its config's 'Stage Footage' -> "
        "reference; a root-polynomial Q is computed exactly, not through the config's LUT) to "
        "frames, writing DIR/<frame name> (DIR/<environment>/<frame name> when "
        "several environments are given). Alpha, depth and AOV channels, metadata, data window "
        "and compression are kept. Frames already in DIR are skipped (resume); a bad frame is "
        "reported and the others are still done (exit 2 at the end). A write failure (disk "
        "full, read-only, no permission) stops the run on one line naming the first frame not "
        "written (exit 2); the frames written before stay, complete, and the same command "
        "continues from there. A disk clearly too small for the frames is refused at the start.",
    )
    parser.add_argument(
        "inputs",
        metavar="SOLUTION... FRAMES",
        nargs="+",
        help=f"first the solutions ({SOLUTIONS_HELP}), then frame files or patterns: "
        "plate.####.exr (n '#' = n digits), plate.%%04d.exr",
    )
    parser.add_argument(
        "--out", required=True, help="output folder (created; never one of the input frames)"
    )
    parser.add_argument(
        "--frames",
        dest="frame_range",
        metavar="FIRST-LAST",
        help="frame range for patterns (default: the frames that exist); missing ones are errors",
    )
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="redo frames already in --out (without it, frames there made with another "
        "solution are refused: their header names the solution)",
    )
    parser.add_argument(
        "--footage-encoding",
        metavar="NAME",
        default=DEFAULT_FOOTAGE_ENCODING,
        help="the frames' encoding: linear (default) or a colour-science decoding name such as "
        "'ARRI LogC4', 'S-Log3', 'Log3G10' (as the capture file's encoding:); encoded frames "
        "are decoded, post-corrected exactly and encoded again",
    )
    parser.add_argument(
        "--via",
        choices=("model", "config"),
        default="model",
        help="how a non-linear Q (root-polynomial, emitter-protected) is computed: its exact "
        "model (default), or the solution's config, the OCIO LUT chain every host runs (the "
        "same pixels as Nuke or oiiotool; its agreement with the model is in solution.json; "
        "speeds of both in docs/performance.md). A 3x3 Q is the config's matrix either way",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help="local processes, one frame and one core each (default 1: this process, frames "
        "pipelined on every core)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask cluster, e.g. tcp://farm-scheduler:8786 (see docs/distributed.md; "
        "default: local processes)",
    )
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (there is none anyway when stderr is not a terminal)",
    )
    parser.set_defaults(func=run)


def split_inputs(inputs: list[str]) -> tuple[list[str], list[str]]:
    """Leading folders (and ``solution.json`` files) are solutions; the rest are frames."""
    count = 0
    for raw in inputs:
        path = Path(raw)
        if not (path.is_dir() or path.name == "solution.json"):
            break
        count += 1
    return inputs[:count], inputs[count:]


def post_correction_caveats(solution) -> list[str]:
    """Why post-correcting with this solution's Q may harm a shot (empty when it is safe)."""
    d = solution.diagnostics
    caveats = []
    rank = d.rank_Q
    if rank is not None and rank < 3:
        cond = float("inf") if d.cond_Q is None else d.cond_Q
        caveats.append(
            f"Q is rank {rank} (cond {cond:.3g}): it maps every colour "
            "onto a line or plane, so corrected footage loses colours the camera recorded"
        )
    if solution.N is None:
        caveats.append(
            "N was not solved, so the wall's in-frustum content was not pre-corrected: do not "
            "post-correct shots with the wall in frame (the background would be wrong)"
        )
    return caveats


def run(args: argparse.Namespace) -> int:
    from ocio_vp.footage.apply import FrameTask, load_post_correction
    from ocio_vp.footage.distributed import default_workers
    from ocio_vp.footage.sequences import expand_frames, output_paths, parse_frame_range
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.formats.solution_inputs import solution_folders

    solutions, frames = split_inputs(args.inputs)
    if not solutions:
        raise InputError("expected the solution(s) first, then the frames", key="SOLUTION")
    if not frames:
        raise InputError("no frames given after the solution(s)", key="FRAMES")
    chosen = solution_folders(solutions, key="SOLUTION")
    encoding = canonical_encoding(args.footage_encoding, key="--footage-encoding")
    frame_range = parse_frame_range(args.frame_range) if args.frame_range else None
    inputs = expand_frames(frames, frames=frame_range)
    workers = 1 if args.workers is None else args.workers
    # In this process: frames pipelined on every core; in a pool or on Dask, one core each.
    threads = default_workers() if (workers == 1 and not args.scheduler) else 1
    tasks = []
    for folder in chosen.folders:
        for caveat in post_correction_caveats(load_solution(folder)):
            warn("apply", f"{folder.name}: {caveat}")
        post = load_post_correction(folder, encoding, via=args.via)
        out = Path(args.out) if len(chosen.folders) == 1 else Path(args.out) / folder.name
        tasks += [
            FrameTask(str(s), str(d), post, overwrite=args.overwrite, threads=threads)
            for s, d in zip(inputs, output_paths(inputs, out), strict=True)
        ]
    _refuse_foreign([Path(task.dst) for task in tasks])
    if not args.overwrite:
        _refuse_other_solutions(tasks)
    check_free_space(tasks)
    return _run_tasks(tasks, args, workers)


def _refuse_other_solutions(tasks: list) -> None:
    """Before any work: frames in --out made with another post-correction are never kept as
    done; without --overwrite the run stops on one line naming the first and how many."""
    from ocio_vp.footage.apply import other_solution_reason
    from ocio_vp.footage.sequences import output_solution

    other = []
    for task in tasks:
        if os.path.lexists(task.dst):
            made_by = output_solution(task.dst)
            if made_by != task.post_correction.solution:
                other.append((task, made_by))
    if other:
        task, made_by = other[0]
        more = f" ({len(other)} frames in all)" if len(other) > 1 else ""
        reason = other_solution_reason(task.dst, made_by, task.post_correction.solution)
        raise InputError(f"{reason}{more}; nothing was written")


def _refuse_foreign(outputs: list[Path]) -> None:
    """Before any work: an output name taken by a file ocio-vp did not write is an error (each
    frame checks again when it runs)."""
    from ocio_vp.footage.sequences import foreign_output_reason, foreign_outputs

    foreign = foreign_outputs(outputs)
    if foreign:
        raise InputError(
            f"{foreign_output_reason(len(foreign))}; nothing was written", source=str(foreign[0])
        )


def _run_tasks(tasks: list, args: argparse.Namespace, workers: int) -> int:
    from ocio_vp.commands.common import progress
    from ocio_vp.footage.apply import run_task
    from ocio_vp.footage.distributed import map_unordered
    from ocio_vp.footage.stream import apply_frames

    counts = {"done": 0, "skipped": 0, "input-error": 0, "error": 0}
    finished: set[int] = set()  # frames done or already there
    write_error = None
    bar = progress(total=len(tasks), unit="frame", disable=args.no_progress or None, leave=True)
    with bar:
        results: Iterator[tuple[int, FrameResult | BaseException]]
        if workers == 1 and not args.scheduler:
            results = apply_frames(tasks, threads=tasks[0].threads if tasks else 1)
        else:
            results = map_unordered(run_task, tasks, workers=workers, scheduler=args.scheduler)
        for i, result in results:
            if isinstance(result, BaseException):  # a worker died: count it, keep going
                counts["error"] += 1
                bar.write(f"ocio-vp apply: error: {tasks[i].src}: {result}", file=sys.stderr)
            elif result.status == "write-error":
                write_error = result  # the disk or folder fails every later frame too: stop
                break
            else:
                counts[result.status] += 1
                if result.status in ("done", "skipped"):
                    finished.add(i)
                elif result.status in ("input-error", "error"):
                    bar.write(f"ocio-vp apply: error: {result.message}", file=sys.stderr)
            bar.update(1)
        close = getattr(results, "close", None)
        if close is not None:
            close()  # frames being written finish (complete, under their names); no new one
    if write_error is not None:
        raise write_failure_error(tasks, finished, write_error)
    failed = counts["input-error"] + counts["error"]
    print(
        f"{counts['done']} frame(s) written, {counts['skipped']} already done, "
        f"{failed} failed -> {args.out}"
    )
    if counts["error"]:
        return 1
    return 2 if counts["input-error"] else 0


def write_failure_error(tasks: list, finished: set[int], failure) -> Exception:
    """The one-line error that ends a run whose output could not be written (``failure``, a
    ``write-error`` FrameResult): the first frame not written and how many are done (frames
    still being written count where their output is there now, with this post-correction)."""
    from ocio_vp.footage.sequences import output_solution

    done = set(finished)
    for i, task in enumerate(tasks):
        if i not in done and os.path.lexists(task.dst):
            if output_solution(task.dst) == (task.post_correction.solution or None):
                done.add(i)
    first = next((i for i in range(len(tasks)) if i not in done), None)
    first_dst = tasks[first].dst if first is not None else failure.dst
    where = "" if first_dst == failure.dst else f" (writing {os.path.basename(failure.dst)})"
    return InputError(
        f"not written: {failure.message}{where}; {len(done)} of {len(tasks)} frames done "
        "(complete, kept), the others not: fix it, then the same command continues from here",
        source=first_dst,
    )


def check_free_space(tasks: list, *, margin: float = FREE_SPACE_MARGIN) -> None:
    """Refuse, before any frame is written, a run the output disk clearly cannot hold: free
    space below ``margin`` times the outputs' size, estimated at their inputs' (less what
    replaced outputs give back; skipped ones need nothing)."""
    import shutil

    need: dict[int, tuple[int, str]] = {}  # device -> (bytes, a folder on it)
    for task in tasks:
        if os.path.lexists(task.dst) and not task.overwrite:
            continue  # skipped (or refused before this check)
        try:
            size = os.path.getsize(task.src) - (
                os.path.getsize(task.dst) if os.path.lexists(task.dst) else 0
            )
        except OSError:  # a missing input is reported by its frame
            continue
        folder = os.path.dirname(os.path.abspath(task.dst))
        while not os.path.isdir(folder):
            folder = os.path.dirname(folder)
        device = os.stat(folder).st_dev
        total, _ = need.get(device, (0, folder))
        need[device] = (total + size, folder)
    for total, folder in need.values():
        free = shutil.disk_usage(folder).free
        if free < margin * total:
            raise InputError(
                f"not enough free space: the frames need about {_size(total)}, "
                f"{_size(free)} free; nothing was written",
                source=folder,
            )


def _size(count: float) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if count < 1024:
            return f"{count:.0f} {unit}" if unit == "bytes" else f"{count:.1f} {unit}"
        count /= 1024
    return f"{count:.1f} TiB"
