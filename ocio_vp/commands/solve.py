"""``ocio-vp solve MEASUREMENTS --out DIR``: one OCIO config and solution.json per environment."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable, Iterator, Sequence

from ocio_vp.choices import (
    BLACK_LEVEL_METHODS,
    DEFAULT_BLACK_LEVEL,
    DEFAULT_PEAK_NITS,
    DEFAULT_PRIORITY,
    DEFAULT_WALL_ENCODING,
    PRIORITIES,
    WALL_ENCODINGS,
)
from ocio_vp.commands.common import add_method_argument, progress
from ocio_vp.commands.summary import print_summary
from ocio_vp.errors import InputError, excerpt

__all__ = [
    "add_parser",
    "print_camera_gamut",
    "print_content_scale",
    "print_fixtures",
    "print_linearity",
    "print_panels",
    "run",
    "wall_encoding",
]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "solve",
        help="solve M, Q, N and the black level; write a config per environment",
        description="Solve every environment of a measurements file and write "
        "DIR/<environment>/config.ocio and solution.json.",
    )
    parser.add_argument(
        "measurements",
        nargs="+",
        help="measurements file(s) (.yaml/.yml/.json); several are merged, e.g. the wall from "
        "one and the charts from another (docs/measurements.md)",
    )
    parser.add_argument(
        "--out",
        required=True,
        help="output folder (created if needed; DIR/<environment>/ of a re-run is replaced)",
    )
    add_method_argument(parser)
    parser.add_argument(
        "--no-fixtures",
        action="store_true",
        help="light with the wall alone even if the measurements have a fixtures section "
        "(default: drive the fixtures with the wall, docs/fixtures.md)",
    )
    parser.add_argument(
        "--protect-emitters",
        action="store_true",
        help="for scenes with practicals, screens or neon in frame: the post-correction fades to "
        "the identity where no reflective surface lit by the wall can be (brighter than white in "
        "an LED channel, or needing negative light); by default it fades to the 3x3 there "
        "(docs/stability.md)",
    )
    _add_skin_arguments(parser)
    parser.add_argument(
        "--black-level",
        choices=BLACK_LEVEL_METHODS,
        default=DEFAULT_BLACK_LEVEL,
        help="in-frustum black-level offset: exact (-M b, default) or the paper's b/w_camera",
    )
    parser.add_argument(
        "--keep-all-patches",
        action="store_true",
        help="fit every unclipped chart patch, even ones inconsistent with the rest (by default "
        "they are excluded and named; docs/stability.md)",
    )
    parser.add_argument(
        "--environment",
        action="append",
        metavar="NAME",
        help="solve only this environment (repeatable; default: all)",
    )
    _add_light_arguments(parser)
    _add_wall_arguments(parser)
    parser.set_defaults(func=run)


def _add_light_arguments(parser: argparse.ArgumentParser) -> None:
    """Where the light comes from (HDRIs), where the solve runs, the camera's gamut."""
    parser.add_argument(
        "--hdri",
        action="append",
        default=[],
        metavar="ENV=FILE",
        help="take ENV's w_avg from its equirectangular HDRI (camera linear RGB) instead of the "
        "white patch; with panels, each panel type's from the directions of its region "
        "(repeatable; a bare FILE when solving one environment; default: none)",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="solve the environments on a Dask cluster, e.g. tcp://host:8786 (docs/distributed.md;"
        " default: here, one after the other)",
    )
    parser.add_argument(
        "--hdri-width",
        type=int,
        default=None,
        metavar="N",
        help="resolution the HDRI is integrated at (default 1024; see docs/performance.md)",
    )
    parser.add_argument(
        "--camera-colorspace",
        metavar="NAME",
        default=None,
        help="the camera's gamut, a colour.RGB_COLOURSPACES name such as 'ARRI Wide Gamut 4' "
        "(default: stage.camera_colorspace of the measurements or capture file). With it the "
        "configs carry ACES2065-1, ACEScg, Linear Rec.709 and ACEScct, the interchange and log "
        "roles, the camera's log footage and ACES monitor views, and content can be rendered "
        "in a working space; without it content must be in the camera's native linear RGB",
    )


def _add_wall_arguments(parser: argparse.ArgumentParser) -> None:
    """The wall's signal encoding, peak luminance and soft clip."""
    parser.add_argument(
        "--wall-encoding",
        choices=WALL_ENCODINGS,
        type=str.lower,
        default=None,
        help="signal the wall colorspaces output (after M/N and the linearity LUT): linear "
        "drive, gamma 2.4, sRGB (IEC 61966-2-1) or SMPTE ST 2084 PQ (docs/linearity.md). "
        "Default: stage.wall_encoding of the measurements file (measure copies it from the "
        "take's sequence.yaml), else linear, said once; a value contradicting the file is "
        "refused",
    )
    parser.add_argument(
        "--peak-nits",
        type=float,
        default=None,
        help="with a PQ wall only: luminance (cd/m2) of drive 1.0, the level of the measured "
        "primaries (default: stage.peak_nits of the measurements file, else "
        f"{DEFAULT_PEAK_NITS:g}); a value contradicting the file is refused",
    )
    parser.add_argument(
        "--soft-clip",
        type=float,
        default=None,
        metavar="KNEE",
        help="compress each channel's drive above KNEE (0 < KNEE < 1, a fraction of the panel's "
        "full drive) smoothly towards full drive instead of clipping it there, in both wall "
        "colorspaces (default: off, drive above full clips; docs/headroom.md)",
    )


def print_fixtures(solutions: Sequence) -> None:
    """One line per environment with fixtures: on or off, the drives, the error change."""
    for solution in solutions:
        if not solution.fixtures:
            continue
        notes = solution.diagnostics.fixtures
        if notes is None or not notes.applied:
            reason = "not solved" if notes is None else notes.reason
            print(f"fixtures, {solution.environment}: off ({reason})")
            continue
        drives = "; ".join(
            f"{name} " + " ".join(f"{c}={block.drive[c]:.3f}" for c in block.channels)
            for name, block in solution.fixtures.items()
        )
        limits = ", ".join(notes.active_limits) or "none"
        print(
            f"fixtures, {solution.environment}: {drives} (error Q cannot remove "
            f"{100 * notes.error_reduction:.0f}% lower; active limits: {limits})"
        )


def _add_skin_arguments(parser: argparse.ArgumentParser) -> None:
    """``--priority`` and what skin may be computed from (docs/skin.md)."""
    parser.add_argument(
        "--priority",
        choices=PRIORITIES,
        default=DEFAULT_PRIORITY,
        help="what the default post-correction puts first: general colours (default; it never "
        "renders skin worse than least squares) or skin (faces first, general reflectances at "
        "a bounded cost); an environment's own 'priority' in the measurements file wins "
        "(docs/skin.md)",
    )
    parser.add_argument(
        "--led-spectra",
        metavar="FILE.csv",
        help="the panel's measured LED spectra (wavelength in nm, then red, green, blue): skin "
        "is then also computed from spectra, with --camera-sensitivities (default: skin from "
        "the chart alone, docs/skin.md)",
    )
    parser.add_argument(
        "--camera-sensitivities",
        metavar="FILE.csv|NAME",
        help="the camera's spectral sensitivities (wavelength in nm, then R, G, B) or a camera "
        "of the bundled database (default: none; docs/skin.md)",
    )
    parser.add_argument(
        "--location-light",
        action="append",
        default=[],
        metavar="ENV=FILE.csv",
        help="the measured light of an environment (wavelength in nm, then its power); "
        "by default estimated from its target chart (repeat per environment)",
    )


def print_panels(solutions: Sequence) -> None:
    """One line per environment of a stage of several panel types: each type's share of the
    light, the lit white with each type's own M and with the first type's M everywhere, and
    how the in-frustum types match in camera."""

    def percent(values) -> str:
        return "/".join(f"{100 * v:.1f}" for v in values) + "%"

    for solution in solutions:
        notes = solution.diagnostics.panels if solution.panels else None
        if notes is None:
            continue
        shares = " + ".join(f"{name} {100 * v:.0f}%" for name, v in notes.shares.items())
        line = (
            f"panels, {solution.environment}: {shares} of the light; lit white before Q "
            f"{percent(notes.lit_white_error)} off per channel ("
            f"{percent(notes.lit_white_error_primary_M)} with {notes.primary}'s M for all)"
        )
        match = notes.in_frustum_match
        reference, types = ("", {}) if match is None else (match.reference, match.types)
        for name, block in types.items():
            line += (
                f"; in camera {name} vs {reference}: mean ΔE2000 "
                f"{block.delta_E_2000_mean:.2f} (max {block.delta_E_2000_max:.2f})"
            )
        print(line)


def print_linearity(solutions: Sequence) -> None:
    """The panel-linearity summary, once: every environment shares the stage's ramps."""
    for s in solutions:
        linearity = s.linearity
        if linearity is None or not linearity.measured:
            continue
        print(f"linearity: {linearity.summary}")
        for note in linearity.notes or []:
            print(f"  {note}")
        lut = linearity.lut
        if lut:
            print(
                f"  LUT {lut.file}: {lut.entries} entries, {lut.domain}; error vs the "
                f"exact inverse {100 * lut.max_error:.2g}% of the level or less above 0.2% of peak"
            )
        for warning in linearity.warnings or []:
            print(f"warning: {warning}")
        return


def print_content_scale(solutions: Sequence) -> None:
    """Per environment what content white needs of the wall (stdout); one warning naming the
    environments where it clips (stderr)."""
    from ocio_vp.calibration.headroom import content_scale, content_scale_lines

    out, err = content_scale_lines([content_scale(s) for s in solutions])
    for line in out:
        print(line)
    for line in err:
        print(line, file=sys.stderr)


def print_camera_gamut(solutions: Sequence) -> None:
    """Say once what a config without a camera gamut lacks (and how to state it)."""
    if solutions and not solutions[0].camera_colorspace:
        print(
            "note: the camera gamut is not stated (stage.camera_colorspace, or solve "
            "--camera-colorspace NAME): the configs have no working spaces (ACEScg, ACES2065-1), "
            "no interchange or log roles and no camera log footage, monitors show camera RGB as "
            "Rec.709, and content for the wall must be rendered in the camera's native linear RGB"
        )


def run(args: argparse.Namespace) -> int:
    if args.peak_nits is not None and not 0 < args.peak_nits <= 10000:
        raise InputError(f"expected 0 < cd/m2 <= 10000, got {args.peak_nits:g}", key="--peak-nits")
    if args.soft_clip is not None and not 0.0 < args.soft_clip < 1.0:
        raise InputError(
            f"expected a knee in (0, 1), a fraction of full drive, got {args.soft_clip:g}",
            key="--soft-clip",
        )
    if args.hdri_width is not None and not args.hdri:
        raise InputError("applies only with --hdri", key="--hdri-width")
    picked = args.environment or []
    for i, name in enumerate(picked):
        if name in picked[:i]:  # its folder would be written twice
            raise InputError(f"{excerpt(name)} is given more than once", key="--environment")
    written = _solve_and_write(args)
    print_summary(written)
    print_fixtures(written)
    print_panels(written)
    print_linearity(written)
    print_camera_gamut(written)
    print_content_scale(written)
    print(f"wrote {len(written)} environment(s) to {args.out}")
    from ocio_vp.formats.provenance import stale_outputs

    for line in stale_outputs(args.out, [s.environment for s in written]):
        print(f"warning: {line}", file=sys.stderr)
    return 0


def wall_encoding(args: argparse.Namespace, measurements) -> tuple[str, float]:
    """(encoding, peak nits) of the wall: the measurements file's (``stage.wall_encoding``,
    ``peak_nits``: what the wall was sent while it was measured), the command line's where the
    file says nothing, linear drive where neither does (said once). A flag contradicting the
    file, or ``--peak-nits`` for a wall that is not PQ, is refused on one line."""

    stated = measurements.stage.wall
    source = measurements.source or "the measurements file"
    if stated.encoding and args.wall_encoding and args.wall_encoding != stated.encoding:
        raise InputError(
            f"{args.wall_encoding} contradicts stage.wall_encoding {stated.describe()} of "
            f"{source} (what the wall played while it was measured): leave the flag out, or "
            "correct the file if the wall really played another signal",
            key="--wall-encoding",
        )
    encoding = args.wall_encoding or stated.encoding
    if encoding is None:
        encoding = DEFAULT_WALL_ENCODING
        if not (measurements.panels and all(p.encoding for p in measurements.panels)):
            print(
                f"note: {source} states no wall encoding (a wall measured from plates): "
                f"{encoding} drive assumed; give stage.wall_encoding or --wall-encoding"
            )
    if args.peak_nits is not None and encoding != "pq":
        raise InputError(f"applies only to a PQ wall, this one is {encoding}", key="--peak-nits")
    peak = args.peak_nits if args.peak_nits is not None else stated.peak_nits
    if stated.peak_nits is not None and peak != stated.peak_nits:
        raise InputError(
            f"{peak:g} contradicts stage.peak_nits {stated.peak_nits:g} of {source}: leave the "
            "flag out, or correct the file",
            key="--peak-nits",
        )
    return encoding, DEFAULT_PEAK_NITS if peak is None else float(peak)


def _solve_and_write(args: argparse.Namespace) -> list:
    """Load, solve every environment asked for, and write them to ``args.out``."""
    from ocio_vp.formats.measurements import with_camera_colorspace
    from ocio_vp.formats.merge import load_measurement_files
    from ocio_vp.ocio.writer import writer_pool

    measurements = load_measurement_files(args.measurements)
    if args.camera_colorspace is not None:
        measurements = with_camera_colorspace(
            measurements, args.camera_colorspace, key="--camera-colorspace"
        )
    environments = measurements.environments
    if args.environment:
        environments = tuple(measurements.environment(name) for name in args.environment)
    # The writing helper starts before solving, so that its imports overlap the solves; one
    # environment is written here, with no helper.
    with writer_pool(
        args.method, protect_emitters=args.protect_emitters, environments=len(environments)
    ) as pool:
        return _solve_environments(args, measurements, environments, pool)


def _solve_environments(args: argparse.Namespace, measurements, environments, pool) -> list:
    """Solve ``environments`` (HDRIs, wall encoding, soft clip as asked) and write them."""
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.wall.encoding import with_wall_encoding
    from ocio_vp.wall.softclip import with_soft_clip

    if args.hdri:
        from ocio_vp.hdri.diffuse import DEFAULT_HDRI_WIDTH, environments_with_hdri

        width = DEFAULT_HDRI_WIDTH if args.hdri_width is None else args.hdri_width
        if not 16 <= width <= 16384:
            raise InputError(f"expected 16..16384, got {width}", key="--hdri-width")
        environments, notes = environments_with_hdri(
            measurements, environments, args.hdri, width=width
        )
        print("\n".join(notes))
    encoding, peak_nits = wall_encoding(args, measurements)
    solved = _solve(measurements, environments, _options(measurements, args), args.scheduler)
    solutions: Iterable = (
        with_soft_clip(with_wall_encoding(s, encoding, peak_nits=peak_nits), args.soft_clip)
        for s in solved
    )  # with the helper, solved as they are written: it writes while this process solves
    if pool is None:
        solutions = list(solutions)
    hdri_files = [spec.partition("=")[2] or spec for spec in args.hdri]
    return write_solutions(solutions, args.out, inputs=[*args.measurements, *hdri_files], pool=pool)


def _options(measurements, args: argparse.Namespace):
    """The :class:`~ocio_vp.pipeline.SolveOptions` of the command line."""
    from ocio_vp.correction.skin_spectra import stage_spectra
    from ocio_vp.pipeline import SolveOptions

    spectra = stage_spectra(args.led_spectra, args.camera_sensitivities, args.location_light)
    if spectra is not None:
        names = {e.name for e in measurements.environments}
        for name in spectra.lights:
            if name not in names:
                raise InputError(f"no environment named {name!r}", key="--location-light")
    return SolveOptions(
        method=args.method,
        black_level=args.black_level,
        fixtures=not args.no_fixtures,
        keep_all_patches=args.keep_all_patches,
        protect_emitters=args.protect_emitters,
        priority=args.priority,
        spectra=spectra,
    )


def _solve(measurements, environments, options, scheduler: str | None = None) -> Iterator:
    """Every environment, on a Dask cluster or here (with a progress bar on a terminal), one
    at a time as they are asked for (:func:`ocio_vp.ocio.writer.write_solutions` writes each
    while the next is solved)."""
    from ocio_vp.pipeline import solve_environment

    if scheduler:
        from ocio_vp.footage.distributed import solve_environments

        yield from solve_environments(measurements, environments, options, scheduler=scheduler)
        return
    for env in progress(environments, desc="solving", unit="environment"):
        yield solve_environment(measurements, env, options)
