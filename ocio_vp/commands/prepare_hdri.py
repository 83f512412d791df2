"""``ocio-vp prepare-hdri IN.exr --peak 1.0 --out OUT.exr``: fit an HDRI under the wall's peak."""

from __future__ import annotations

import argparse

__all__ = ["add_parser", "run"]

#: Normals the summary reports w_avg for (ocio_vp.hdri.diffuse convention: +y up, +z image centre).
SUMMARY_NORMALS = {"front": (0.0, 0.0, 1.0), "up": (0.0, 1.0, 0.0), "right": (1.0, 0.0, 0.0)}


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "prepare-hdri",
        help="spread over-range light sources so the wall can show the HDRI (energy kept)",
        description="Move the excess of every pixel above --peak into the pixels nearest to its "
        "light source, keeping the total solid-angle-weighted energy and the source's colour, "
        "so no pixel exceeds the LED wall's peak. Equirectangular (2:1) input; other channels "
        "and metadata pass through. See docs/hdri.md.",
    )
    parser.add_argument("input", help="equirectangular HDRI (any format OpenImageIO reads)")
    parser.add_argument(
        "--peak",
        type=float,
        default=1.0,
        help="largest value the wall can show, in the map's units (default %(default)s)",
    )
    parser.add_argument("--out", required=True, help="output image (e.g. OUT.exr)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ocio_vp.hdri.prepare import prepare_hdri_file

    prepared = prepare_hdri_file(args.input, args.out, peak=args.peak, normals=SUMMARY_NORMALS)
    print(f"wrote {args.out}: peak {prepared.peak:g}, {len(prepared.sources)} over-range source(s)")
    for i, s in enumerate(prepared.sources[:10]):
        print(
            f"  source {i + 1}: {s.pixels} px, excess {np.round(s.excess, 6).tolist()} "
            f"(x dOmega), spread within {s.radius_deg:.2f} deg of it ({s.filled_pixels} px)"
        )
    if len(prepared.sources) > 10:
        print(f"  ... and {len(prepared.sources) - 10} more")
    for name, (before, after) in prepared.w_avg.items():
        change = 100.0 * (after / np.where(before == 0, 1.0, before) - 1.0)
        print(
            f"  w_avg({name}): {np.round(after, 6).tolist()}, change {np.round(change, 3).tolist()}%"
        )
    return 0
