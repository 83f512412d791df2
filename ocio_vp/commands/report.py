"""``ocio-vp report SOLUTION_DIR... [--out DIR]``: an HTML report with the paper's charts."""

from __future__ import annotations

import argparse

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "report",
        help="write an HTML report (comparison charts, error plots) for solved environments",
        description="Write a self-contained HTML report (index.html + PNGs, no network "
        "resources) with the paper's comparison charts and Fig. 11 error bars for every "
        "solution: a solution.json, an environment folder, or an `ocio-vp solve` output folder.",
    )
    parser.add_argument("solutions", nargs="+", metavar="SOLUTION_DIR", help="solutions to show")
    parser.add_argument(
        "--out",
        default=None,
        help="report folder (default: report/ beside the first environment folder)",
    )
    parser.add_argument("--dpi", type=float, default=110, help="PNG resolution (default 110)")
    parser.add_argument(
        "--no-match-white",
        action="store_true",
        help="show stage charts at their own exposure instead of matching the target white's "
        "green channel (the paper's figures match it)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.errors import InputError
    from ocio_vp.report.build import build_report, default_report_dir

    if not args.dpi > 0:
        raise InputError(f"expected a positive number, got {args.dpi}", key="--dpi")
    out = args.out or default_report_dir(args.solutions)
    report = build_report(args.solutions, out, dpi=args.dpi, match_white=not args.no_match_white)
    print(f"wrote {report.index} ({len(report.environments)} environment(s))")
    return 0
