"""``ocio-vp report SOLUTION... [--out DIR]``: an HTML report with the paper's charts."""

from __future__ import annotations

import argparse

from ocio_vp.commands.common import progress
from ocio_vp.errors import InputError

__all__ = ["add_parser", "run"]

SOLUTIONS_HELP = (
    "an environment folder (OUT/<environment>/), its solution.json, or an `ocio-vp solve` "
    "output folder (= all its environments); several allowed, e.g. calib/* (report, export "
    "and measurement files in there are skipped)"
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "report",
        help="write an HTML report (comparison charts, error plots) for solved environments",
        description="Write a self-contained HTML report (index.html + SVG figures + report.json, no "
        "network resources) with the paper's comparison charts and Fig. 11 error bars. "
        "Default place: SOLVE/report for all environments of a solve output folder, "
        "SOLVE/<environment>/report for one, SOLVE/report-<env>+<env> for some. A report on "
        "other environments is never replaced silently.",
    )
    parser.add_argument("solutions", nargs="+", metavar="SOLUTION", help=SOLUTIONS_HELP)
    parser.add_argument(
        "--out",
        default=None,
        help="report folder (default: chosen from the solutions, see above)",
    )
    parser.add_argument(
        "--replace",
        action="store_true",
        help="replace the report at --out even if it shows environments this one leaves out",
    )
    parser.add_argument(
        "--dpi",
        type=float,
        default=110,
        help="size of the figures on the page, pixels per inch (they are SVG, sharp at any zoom)",
    )
    parser.add_argument(
        "--no-match-white",
        action="store_true",
        help="show stage charts at their own exposure instead of matching the target white's "
        "green channel (the paper's figures match it)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.formats.solution_inputs import solution_folders
    from ocio_vp.report.build import build_report, default_report_dir

    if not 10 <= args.dpi <= 1200:  # outside, the figures are unreadably small or huge
        raise InputError(f"expected 10..1200, got {args.dpi:g}", key="--dpi")
    chosen = solution_folders(args.solutions)
    for note in chosen.notes():
        print(note)
    out = args.out or default_report_dir(chosen.folders)
    with progress(total=len(chosen.folders), desc="report", unit="environment") as bar:
        report = build_report(
            chosen.folders,
            out,
            dpi=args.dpi,
            match_white=not args.no_match_white,
            replace=args.replace,
            on_step=lambda: bar.update(1),
        )
    print(f"wrote {report.index} ({len(report.environments)} environment(s))")
    return 0
