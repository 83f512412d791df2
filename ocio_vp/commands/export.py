"""``ocio-vp export SOLUTION_DIR... --target unreal|nuke|resolve|lights|all``: files for the tools
studios run (Unreal nDisplay, Nuke, DaVinci Resolve) from solved environments."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from ocio_vp.choices import (
    CONTEXT_VARIABLE,
    DEFAULT_BASE_CONFIG,
    DEFAULT_CUBE_RANGE,
    DEFAULT_CUBE_SIZE,
    ENVIRONMENT_TARGETS,
    EXPORT_TARGETS,
)
from ocio_vp.commands.report import SOLUTIONS_HELP
from ocio_vp.errors import InputError

if TYPE_CHECKING:  # the exports import OCIO: not at start-up
    from ocio_vp.exports import ExportResult

__all__ = ["add_parser", "export_line", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export",
        help="write Unreal nDisplay, Nuke and Resolve files from solved environments",
        description="Export solved environments (OUT/<environment>/ from `ocio-vp solve`). "
        "Output: <environment>/exports/<target>/, or --out DIR/<environment>/<target>/; an "
        "earlier export of the same target is replaced.",
    )
    parser.add_argument("solution_dirs", nargs="+", metavar="SOLUTION", help=SOLUTIONS_HELP)
    parser.add_argument(
        "--target",
        choices=EXPORT_TARGETS,
        default="all",
        help="unreal: .ocioz + UNREAL.md + mapping JSON; nuke: .nk; resolve: CLF, DCTL, .cube; "
        "lights: fixture drives and DMX levels (solutions with fixtures); dit: a log-in log-out "
        ".cube of the post-correction for the DIT cart (solutions with a camera gamut, where it "
        "meets the cube accuracy limit); all: every target "
        "above that applies (default: all); show: OUT/show/config.ocio, one config for all the "
        "given environments on --base-config, the environment chosen by the context variable "
        f"{CONTEXT_VARIABLE} (needs --out)",
    )
    parser.add_argument(
        "--base-config",
        metavar="PATH|URI",
        default=None,
        help=f"base of --target show: a config file or ocio:// URI (default {DEFAULT_BASE_CONFIG}, "
        "OCIO's built-in ACES CG config; written out whole)",
    )
    parser.add_argument(
        "--out", default=None, help="output folder (default: exports/ inside each environment)"
    )
    parser.add_argument(
        "--cube-size",
        type=int,
        default=DEFAULT_CUBE_SIZE,
        help=f"3D LUT size of the baked .cube (default {DEFAULT_CUBE_SIZE})",
    )
    parser.add_argument(
        "--cube-range",
        type=float,
        nargs=2,
        metavar=("LO", "HI"),
        default=DEFAULT_CUBE_RANGE,
        help="linear input range the .cube covers (default {:g} {:g})".format(*DEFAULT_CUBE_RANGE),
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.exports import export_solutions
    from ocio_vp.formats.solution_inputs import solution_folders

    if args.base_config is not None and args.target != "show":
        raise InputError("applies only to --target show", key="--base-config")
    targets = ENVIRONMENT_TARGETS if args.target == "all" else (args.target,)
    chosen = solution_folders(args.solution_dirs)
    for note in chosen.notes():
        print(note)
    results = export_solutions(
        chosen.folders,
        targets=targets,
        out=args.out,
        cube_size=args.cube_size,
        cube_range=tuple(args.cube_range),
        base_config=args.base_config,
    )
    for result in results:
        print(export_line(result))
    for failure in results.failures:
        print(f"not exported: {failure.reason}", file=sys.stderr)
    return 0


def export_line(result: ExportResult) -> str:
    """One line per environment and target: where it went and what to use (each target's
    files, accuracies and the files not written, with why, are in its folder's manifest)."""
    summary = result.summary
    head = f"{result.environment}: {result.target} -> {result.folder}"
    if summary.line:
        return f"{head}: {summary.line}"
    for name, error in summary.cubes.items():
        return f"{head}: {name}, worst error {error.max_error:.2g} <= limit {error.limit:.2g}"
    for name, reason in summary.not_written.items():
        return f"{head}: {name} not written ({reason.split(';')[0]})"[:300]
    files = summary.files
    return f"{head}: {', '.join(files[:5])}" if files else head
