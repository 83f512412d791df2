"""``ocio-vp simulate --out FILE``: a measurements file from the spectral stage simulator."""

from __future__ import annotations

import argparse

__all__ = ["add_parser", "run"]


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help="simulate a stage from spectra and write a measurements file",
        description="Simulate the calibration photographs of an RGB LED stage from spectra "
        "(colour-science's offline datasets) and write a measurements file (.yaml or .json) "
        "that `ocio-vp solve` reads. Defaults: the paper-like stage of `ocio-vp demo`.",
    )
    parser.add_argument("--out", help="measurements file to write (.yaml/.yml or .json)")
    parser.add_argument(
        "--camera", default=None, help="colour.MSDS_CAMERA_SENSITIVITIES key (Nikon 5100 (NPL))"
    )
    parser.add_argument(
        "--leds",
        default=None,
        help="R,G,B LEDs as PEAK/FWHM in nm, e.g. 630/20,525/35,460/22 (the default), or a CSV "
        "file of measured spectra with columns wavelength,red,green,blue",
    )
    parser.add_argument(
        "--chart", default=None, help="'ColorChecker N Ohta' (default) or 'BabelColor Average'"
    )
    parser.add_argument(
        "--environment",
        action="append",
        metavar="NAME[=CSV]",
        help="an environment (repeatable): a known name, or NAME=FILE.csv with columns "
        "wavelength,value; default: the paper's seven. Known: see --list-environments",
    )
    parser.add_argument(
        "--panel",
        default=None,
        metavar="WxHxD",
        help="calibration panel width x height x distance in metres (default 1x1x1)",
    )
    parser.add_argument(
        "--albedo",
        type=float,
        default=None,
        help="in-frustum panel albedo for the black level (default 0.04; 0 for none)",
    )
    parser.add_argument("--name", default=None, help="stage name (default simulated-stage)")
    parser.add_argument(
        "--list-environments", action="store_true", help="list the known environments and exit"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.errors import InputError
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.data import ENVIRONMENTS
    from ocio_vp.simulator.options import environments_from_args, stage_options_from_args
    from ocio_vp.simulator.stage import simulate_measurements

    if args.list_environments:
        for spec in ENVIRONMENTS.values():
            print(f"{spec.name:22s} {spec.description}")
        return 0
    if not args.out:
        raise InputError("--out FILE is required", key="--out")
    options = stage_options_from_args(args)
    measurements = simulate_measurements(environments_from_args(args.environment), **options)
    try:
        save_measurements(measurements, args.out)
    except OSError as error:
        raise InputError(f"cannot write: {error.strerror}", source=args.out, key="--out") from None
    names = ", ".join(e.name for e in measurements.environments)
    print(f"wrote {args.out}: stage {measurements.stage.name}, environments {names}")
    return 0
