"""``ocio-vp simulate --out FILE``: a measurements file from the spectral stage simulator."""

from __future__ import annotations

import argparse
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from ocio_vp.commands.common import progress, warn
from ocio_vp.errors import InputError

if TYPE_CHECKING:
    from ocio_vp.simulator.stage import EnvironmentLight

__all__ = ["add_parser", "run"]

#: The plate options' defaults (a change warns that it has no effect without --plates).
_DEFAULTS = {"vignetting": 0.05, "noise": 0.01, "seed": 0}


class ListEnvironments(argparse.Action):
    """``--list-environments``: print them and exit before required options are checked."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        from ocio_vp.simulator.data import ENVIRONMENTS

        for spec in ENVIRONMENTS.values():
            print(f"{spec.name:22s} {spec.description}")
        from ocio_vp.simulator.panels import SCENES

        for scene in SCENES.values():
            print(f"{scene.name:22s} with --ceiling-leds: {scene.description}")
        parser.exit()


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "simulate",
        help="simulate a stage from spectra and write a measurements file",
        description="Simulate an RGB LED stage from spectra (colour-science's offline "
        "datasets) and write its exact measurements file (.yaml or .json) that `ocio-vp solve` "
        "reads; with --plates, also the calibration photographs a stage engineer would shoot "
        "(EXR, with perspective, vignetting and noise), a capture file for `ocio-vp measure` "
        "and a few frames of footage per environment for `ocio-vp apply`. Defaults: the "
        "paper-like stage of `ocio-vp demo`.",
    )
    parser.add_argument(
        "--out", required=True, help="measurements file to write (.yaml/.yml or .json)"
    )
    parser.add_argument(
        "--plates",
        metavar="DIR",
        default=None,
        help="also render the plates into DIR: DIR/capture.yaml, DIR/*.exr (flat fields, "
        "lit charts, target charts, black-level frames), DIR/footage/<env>.####.exr, and "
        "DIR/take/A001.####.exr: the wall playing the patterns filmed in one take (default: no "
        "plates)",
    )
    _add_plate_options(parser)
    _add_take_options(parser)
    parser.add_argument(
        "--camera",
        default=None,
        help="a camera: a colour.MSDS_CAMERA_SENSITIVITIES key or one shipped with ocio-vp "
        "(measured sensitivities from the rawtoaces project, e.g. 'ARRI D21 (rawtoaces)', "
        "'RED MX (rawtoaces)', 'Sony ILCE-7SM2 (rawtoaces)'; an unknown name lists them all) "
        "(default: Nikon 5100 (NPL))",
    )
    parser.add_argument(
        "--leds",
        default=None,
        help="R,G,B LEDs as PEAK/FWHM in nm, e.g. 630/20,525/35,460/22 (the default), or a CSV "
        "file of measured spectra with columns wavelength,red,green,blue",
    )
    parser.add_argument(
        "--chart", default=None, help="'ColorChecker N Ohta' (the default) or 'BabelColor Average'"
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
    _add_wall_gain(parser)
    _add_ceiling_options(parser)
    parser.add_argument(
        "--fixture",
        action="append",
        metavar="KIND",
        choices=("rgbw", "rgbww", "rgbacl", "rgbw-fluorescent"),
        help="add a simulated practical fixture (repeatable): rgbw (warm phosphor white), "
        "rgbww, rgbacl (amber, cyan, lime), rgbw-fluorescent; default: none",
    )
    parser.add_argument(
        "--list-environments",
        action=ListEnvironments,
        help="list the known environments and exit (no --out needed)",
    )
    parser.set_defaults(func=run)


def _add_wall_gain(parser: argparse.ArgumentParser) -> None:
    from ocio_vp.choices import SAMPLE_WALL_GAIN

    parser.add_argument(
        "--wall-gain",
        type=float,
        default=SAMPLE_WALL_GAIN,
        metavar="G",
        help="the wall's full-drive white in units of the location's white, i.e. where the "
        f"camera's exposure puts the wall's peak: {SAMPLE_WALL_GAIN:g} (the default, as a stage "
        "engineer sets a stage up) leaves content white two stops below it; 1 puts the wall's "
        "peak at the location's white, so content white clips",
    )


def _add_take_options(parser: argparse.ArgumentParser) -> None:
    """Options of the simulated camera takes (the wall playing a pattern sequence)."""
    parser.add_argument(
        "--sequence",
        metavar="SEQUENCE_YAML",
        default=None,
        help="with --plates: the patterns the take films, a sequence.yaml of `ocio-vp patterns` "
        "(default: a small built-in one, 64x36 pixels, 8 frames a patch, in DIR/patterns/)",
    )
    parser.add_argument(
        "--film",
        metavar="SEQUENCE_YAML",
        default=None,
        help="film this sequence (e.g. `ocio-vp patterns --validate` output) on the simulated "
        "stage, lit by the sequence's environment, into --take DIR (default: none)",
    )
    parser.add_argument(
        "--take",
        metavar="DIR",
        default=None,
        help="with --film: the folder the take's frames are written to (default: none)",
    )
    parser.add_argument(
        "--take-fps", type=float, default=25.0, help="the simulated camera's frame rate for takes"
    )
    parser.add_argument(
        "--take-format",
        choices=("exr", "prores4444", "prores422"),
        default="exr",
        help="with --plates: the take as linear half-float EXR frames (DIR/take/A001.####.exr), "
        "or as a camera would record it, DIR/take/A001.mov: ProRes 4444 or 422 HQ, 10-bit, "
        "ARRI LogC3, Rec.709 legal range, colour-tagged (default: exr)",
    )
    parser.add_argument(
        "--lit-format",
        choices=("exr", "dng"),
        default="exr",
        help="with --plates: the lit-chart plates as linear half-float EXR, or as camera raw "
        "DNG (the simulated Bayer mosaic, 14-bit, the sensor clipping at 1.0) (default: exr)",
    )


def _add_ceiling_options(parser: argparse.ArgumentParser) -> None:
    """A second panel type: the ceiling (docs/panels.md)."""
    parser.add_argument(
        "--ceiling-leds",
        default=None,
        metavar="LEDS",
        help="add a ceiling of another panel model (a measurements file with panels: wall and "
        "ceiling, docs/panels.md): its R,G,B LEDs as for --leds, e.g. 618/24,538/40,470/26; "
        "environments then default to scenes lit from above and the sides (overcast, "
        "clear_sky, golden_hour, interior, night_street); default: no ceiling",
    )
    parser.add_argument(
        "--ceiling-gain",
        type=float,
        default=None,
        help="with --ceiling-leds: the ceiling's brightness at the wall's drive (default 1.0: "
        "its processor matched to the wall's white)",
    )


def _add_plate_options(parser: argparse.ArgumentParser) -> None:
    """Options that only matter with --plates."""
    parser.add_argument(
        "--vignetting",
        type=float,
        default=_DEFAULTS["vignetting"],
        help="with --plates: lens fall-off at the frame corners (removed by the flat fields)",
    )
    parser.add_argument(
        "--noise",
        type=float,
        default=_DEFAULTS["noise"],
        help="with --plates: relative sensor noise (std; plus 1e-4 absolute read noise)",
    )
    parser.add_argument(
        "--seed", type=int, default=_DEFAULTS["seed"], help="with --plates: noise seed"
    )


def run(args: argparse.Namespace) -> int:
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.fixtures import with_simulated_fixtures
    from ocio_vp.simulator.options import environments_from_args, stage_options_from_args
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage

    options = stage_options_from_args(args)
    _check_take_options(args)
    if args.plates is None and args.film is None:
        for name in ("vignetting", "noise", "seed"):
            if getattr(args, name) != _DEFAULTS[name]:
                warn("simulate", f"--{name} has no effect without --plates")
    elif not (0 <= args.vignetting < 1 and 0 <= args.noise < 1):
        raise InputError("expected 0 <= value < 1", key="--vignetting/--noise")
    if args.plates is not None:  # checked before the measurements file is written
        from ocio_vp.staging import check_not_input, check_replaceable

        check_replaceable(args.plates)
        if args.sequence is not None:
            check_not_input([args.plates], [args.sequence])
    stage = spectral_stage(**options)
    if args.ceiling_leds is not None:
        measurements = _panel_measurements(stage, args)
    elif args.ceiling_gain is not None:
        raise InputError("only with --ceiling-leds", key="--ceiling-gain")
    else:
        environments = environments_from_args(args.environment)
        if args.environment is None:
            environments = _mixable_defaults(environments, stage)
        _check_no_scene(environments)
        measurements = simulate_measurements(environments, stage=stage)
    if args.fixture:
        measurements = with_simulated_fixtures(measurements, stage, args.fixture)
    try:
        save_measurements(measurements, args.out)
    except OSError as error:
        raise InputError(f"cannot write: {error.strerror}", source=args.out, key="--out") from None
    names = ", ".join(e.name for e in measurements.environments)
    print(
        f"wrote {args.out}: stage {measurements.stage.name}, environments {names}; the wall's "
        f"full white is {stage.wall_gain:g}x the location's white (--wall-gain)"
    )
    if args.plates is not None:
        capture = _write_plates(measurements, args)
        print(f"wrote {capture} and its plates; next: ocio-vp measure {capture} --out FILE.yaml")
    if args.film is not None:
        pattern = _film(measurements, args)
        print(f"wrote the take {pattern}")
    return 0


def _check_take_options(args: argparse.Namespace) -> None:
    if (args.film is None) != (args.take is None):
        raise InputError("give --film SEQUENCE and --take DIR together", key="--film/--take")
    if args.sequence is not None and args.plates is None:
        raise InputError("only with --plates (the take it films)", key="--sequence")
    if args.take_format != "exr" and args.plates is None:
        raise InputError("only with --plates (the take it writes)", key="--take-format")
    if args.lit_format != "exr" and args.plates is None:
        raise InputError("only with --plates (the plates it writes)", key="--lit-format")
    if args.take_fps != 25.0 and args.plates is None and args.film is None:
        raise InputError("only with --plates or --film", key="--take-fps")
    if not 1 <= args.take_fps <= 1000:
        raise InputError(f"expected 1 <= fps <= 1000, got {args.take_fps:g}", key="--take-fps")
    if args.take is not None:
        from ocio_vp.staging import check_replaceable

        check_replaceable(args.take)


def _take_options(args: argparse.Namespace, bounce=None):
    from ocio_vp.simulator.take import TakeOptions

    return TakeOptions(fps=args.take_fps, noise=args.noise, seed=args.seed, bounce=bounce)


def _film(measurements, args: argparse.Namespace) -> str:
    """Film --film's sequence into --take, the stage lit by the sequence's environment."""
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.simulator.take import take_frame_count, write_take
    from ocio_vp.staging import publish_dir, staged_dir

    sequence = load_sequence(args.film)
    bounce = None
    if sequence.validation is not None:
        name = sequence.validation.environment
        names = [e.name for e in measurements.environments]
        if name not in names:
            raise InputError(
                f"the sequence shows environment {name!r}, which this simulation does not have "
                f"({', '.join(names)})",
                source=args.film,
            )
        bounce = measurements.environment(name).black_level
    options = _take_options(args, None if bounce is None else tuple(float(v) for v in bounce))
    final = Path(args.take)
    with staged_dir(final.resolve().parent) as stage:
        with progress(total=take_frame_count(sequence, options), desc="take", unit="frame") as bar:
            name = write_take(
                sequence, measurements.SL, stage / "take", options, on_frame=lambda: bar.update(1)
            )
        publish_dir(stage / "take", final, inputs=[args.film])
    return str(final / name)


def _mixable_defaults(environments: dict, stage) -> dict:
    """The default environments without rgb_led_white when the stage's LEDs cannot mix a
    camera-neutral white (named with --environment, it is refused instead)."""
    import numpy as np

    from ocio_vp.simulator.data import camera_white_drive, describe_drive

    if "rgb_led_white" in environments:
        drive = camera_white_drive(stage.leds, stage.camera)
        if np.any(drive < 0):
            warn(
                "simulate",
                "rgb_led_white left out: this camera sees no mix of the stage's LEDs as "
                f"neutral ({describe_drive(drive)})",
            )
            return {k: v for k, v in environments.items() if k != "rgb_led_white"}
    return environments


def _check_no_scene(environments) -> None:
    """A scene (light from above and the sides) needs the ceiling that gives its light above."""
    from ocio_vp.simulator.panels import SCENES

    for name, value in environments.items():
        if isinstance(value, str) and value in SCENES:
            raise InputError(
                f"{name!r} is a scene lit from above and from the sides: only with --ceiling-leds",
                key="--environment",
            )


def _panel_measurements(wall, args: argparse.Namespace):
    """The wall and a ceiling of ``--ceiling-leds`` (ocio_vp.simulator.panels)."""
    from ocio_vp.simulator.options import ceiling_leds_from_arg, environments_from_args
    from ocio_vp.simulator.panels import (
        DEFAULT_CEILING_GAIN,
        SCENES,
        panel_stage,
        simulate_panel_measurements,
    )

    gain = DEFAULT_CEILING_GAIN if args.ceiling_gain is None else args.ceiling_gain
    stage = panel_stage(wall, ceiling_leds=ceiling_leds_from_arg(args.ceiling_leds), gain=gain)
    environments: Mapping[str, EnvironmentLight] = {name: name for name in SCENES}
    if args.environment:
        environments = environments_from_args(args.environment)
    return simulate_panel_measurements(stage, environments)


def _write_plates(measurements, args: argparse.Namespace):
    """Render the plates into a staging folder, then rename it to --plates (all or nothing)."""
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.simulator.plates import PlateOptions, plate_count, raw_clip_note, write_capture
    from ocio_vp.staging import publish_dir, staged_dir

    final = Path(args.plates)
    options = PlateOptions(
        vignetting=args.vignetting,
        noise=args.noise,
        seed=args.seed,
        take=_take_options(args),
        take_format=args.take_format,
        lit_format=args.lit_format,
    )
    sequence = ref = None
    inputs = []
    if args.sequence is not None:
        sequence = load_sequence(args.sequence)
        ref = Path(
            os.path.relpath(os.path.abspath(args.sequence), os.path.abspath(final))
        ).as_posix()
        inputs = [args.sequence, str(Path(args.sequence).parent)]
    with staged_dir(final.resolve().parent) as stage:
        total = plate_count(measurements, options, sequence)
        with progress(total=total, desc="plates", unit="plate") as bar:
            write_capture(
                measurements,
                stage / "plates",
                options,
                bar=bar,
                sequence=sequence,
                sequence_ref=ref,
            )
        publish_dir(stage / "plates", final, inputs=inputs)
    note = raw_clip_note(measurements, options)
    if note is not None:
        print(note)
    return final / "capture.yaml"
