"""``ocio-vp solve MEASUREMENTS --out DIR``: one OCIO config and solution.json per environment."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

__all__ = ["add_parser", "print_linearity", "print_table", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "solve",
        help="solve M, Q, N and the black level; write a config per environment",
        description="Solve every environment of a measurements file and write "
        "DIR/<environment>/config.ocio and solution.json.",
    )
    parser.add_argument("measurements", help="measurements file (.yaml/.yml/.json)")
    parser.add_argument("--out", required=True, help="output folder")
    parser.add_argument(
        "--method",
        default=None,
        help="Q-solve method (default: %(default)s = the library default; "
        "'least-squares' is the paper's eq. 5)",
    )
    parser.add_argument(
        "--black-level",
        choices=("exact", "paper"),
        default="exact",
        help="in-frustum black-level offset: exact (-M b, default) or the paper's b/w_camera",
    )
    parser.add_argument("--environment", action="append", help="solve only these (repeatable)")
    parser.add_argument(
        "--hdri",
        action="append",
        default=[],
        metavar="ENV=FILE",
        help="take ENV's w_avg from its equirectangular HDRI (camera linear RGB) instead of the "
        "white patch (repeatable; a bare FILE when solving one environment)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="solve the environments on a Dask cluster, e.g. tcp://host:8786 (docs/distributed.md)",
    )
    parser.add_argument(
        "--hdri-width",
        type=int,
        default=None,
        metavar="N",
        help="resolution the HDRI is integrated at (default 1024; see docs/performance.md)",
    )
    parser.add_argument(
        "--wall-encoding",
        choices=("linear", "gamma2.4", "srgb", "pq"),
        default="linear",
        help="signal the wall colorspaces output (after M/N and the linearity LUT): linear "
        "drive (default), gamma 2.4, sRGB (IEC 61966-2-1) or SMPTE ST 2084 PQ "
        "(see docs/linearity.md)",
    )
    parser.add_argument(
        "--peak-nits",
        type=float,
        default=1000.0,
        help="with --wall-encoding pq: luminance (cd/m2) of drive 1.0, the level of the "
        "measured primaries (default: %(default)s)",
    )
    parser.set_defaults(func=run)


def print_table(solutions: Sequence) -> None:
    """The terminal summary: one row per environment."""
    header = (
        "environment",
        "method",
        "model",
        "cond[SL]",
        "cond(Q)",
        "N",
        "lit error M-only",
        "lit error M+Q",
        "CV error",
        "drive<0",
        "clipped",
    )
    rows = []
    for s in solutions:
        d = s.diagnostics
        rows.append(
            (
                s.environment,
                s.method,
                d.get("model", s.method),
                f"{d['cond_SL']:.3g}",
                f"{d['cond_Q']:.3g}",
                ("= M" if d.get("N_equals_M") else "solved") if s.N is not None else "NOT solved",
                f"{100 * float(sum(d['lit_chart_error_baseline'])) / 3:.2f}%",
                f"{100 * float(sum(d['lit_chart_error'])) / 3:.2f}%",
                _percent(d.get("cross_validated_error")),
                ",".join("RGB"[c] for c in d.get("out_of_frustum_negative_channels") or []) or "-",
                str(len(d.get("clipped_patches") or [])),
            )
        )
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    for row in [header, *rows]:
        print("  ".join(str(v).ljust(w) for v, w in zip(row, widths, strict=True)))
    for s in solutions:
        for warning in s.diagnostics.get("warnings", []):
            print(f"warning: {s.environment}: {warning}")
    print_linearity(solutions)


def print_linearity(solutions: Sequence) -> None:
    """The panel-linearity summary, once: every environment shares the stage's ramps."""
    for s in solutions:
        linearity = s.linearity or {}
        if not linearity.get("measured"):
            continue
        print(f"linearity: {linearity['summary']}")
        for note in linearity.get("notes", []):
            print(f"  {note}")
        lut = linearity.get("lut")
        if lut:
            print(
                f"  LUT {lut['file']}: {lut['entries']} entries, {lut['domain']}; error vs the "
                f"exact inverse {100 * lut['max_error']:.2g}% of the level or less above 0.2% of peak"
            )
        for warning in linearity.get("warnings", []):
            print(f"warning: {warning}")
        return


def _percent(per_channel) -> str:
    """Mean of a per-channel error as a percentage ('-' when absent)."""
    if per_channel is None:
        return "-"
    return f"{100 * float(sum(per_channel)) / len(per_channel):.2f}%"


def run(args: argparse.Namespace) -> int:
    from ocio_vp.formats.measurements import load_measurements
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.pipeline import DEFAULT_METHOD, solve_environment

    measurements = load_measurements(args.measurements)
    environments = measurements.environments
    if args.environment:
        environments = tuple(measurements.environment(name) for name in args.environment)
    if args.hdri:
        from ocio_vp.hdri.diffuse import DEFAULT_HDRI_WIDTH, environments_with_hdri

        width = args.hdri_width or DEFAULT_HDRI_WIDTH
        environments, notes = environments_with_hdri(
            measurements, environments, args.hdri, width=width
        )
        print("\n".join(notes))
    method = args.method or DEFAULT_METHOD
    if args.scheduler:
        from ocio_vp.footage.distributed import solve_environments

        solutions = solve_environments(
            measurements,
            environments,
            scheduler=args.scheduler,
            method=method,
            black_level=args.black_level,
        )
    else:
        solutions = [
            solve_environment(measurements, env, method=method, black_level=args.black_level)
            for env in environments
        ]
    from ocio_vp.errors import InputError
    from ocio_vp.wall.encoding import with_wall_encoding

    if not 0 < args.peak_nits <= 10000:
        raise InputError(f"expected 0 < cd/m2 <= 10000, got {args.peak_nits:g}", key="--peak-nits")
    solutions = [
        with_wall_encoding(s, args.wall_encoding, peak_nits=args.peak_nits) for s in solutions
    ]
    written = write_solutions(solutions, args.out)
    print_table(written)
    print(f"wrote {len(written)} environment(s) to {args.out}")
    return 0
