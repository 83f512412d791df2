"""``ocio-vp target-chart MEASUREMENTS --environment NAME --hdri FILE --out FILE``.

Writes a copy of MEASUREMENTS in which environment NAME (added, or replaced) has a target chart
synthesized from the HDRI's light (or an average RGB), marked ``synthesized`` with its
assumptions. See docs/target_chart.md.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ocio_vp.errors import InputError

__all__ = ["add_parser", "run"]

_METHODS = ("auto", "daylight-planckian", "planckian", "smooth", "flat")


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "target-chart",
        help="synthesize a CG environment's target chart from its HDRI (no photograph)",
        description="Compute the chart a camera would record under an environment's light "
        "(the HDRI's diffuse integral, or an average RGB) from spectra, and write a copy of "
        "the measurements file with that environment added or replaced, marked as "
        "synthesized. See docs/target_chart.md.",
    )
    parser.add_argument("measurements", help="measurements file (.yaml/.yml/.json)")
    parser.add_argument("--environment", required=True, metavar="NAME", help="environment name")
    parser.add_argument(
        "--hdri",
        metavar="FILE",
        help="the environment's equirectangular HDRI (default: none; give it or --average-rgb)",
    )
    parser.add_argument(
        "--average-rgb",
        metavar="R,G,B",
        help="instead of --hdri: its diffuse integral (w_avg) (default: none)",
    )
    parser.add_argument(
        "--hdri-colorspace",
        default="camera",
        metavar="NAME",
        help="space of the HDRI / average RGB: 'camera' (the measurements' camera linear RGB, "
        "default), ACES2065-1, ACEScg, 'Linear Rec.709' or another colour.RGB_COLOURSPACES name "
        "(needs stage.camera_colorspace)",
    )
    parser.add_argument(
        "--camera",
        metavar="NAME",
        help="camera in colour.MSDS_CAMERA_SENSITIVITIES or shipped with ocio-vp (as simulate "
        "--camera) (default: from --camera-sensitivities, "
        "else approximated from stage.camera_colorspace)",
    )
    parser.add_argument(
        "--camera-sensitivities",
        metavar="CSV",
        help="camera sensitivities: wavelength,R,G,B (nm) (default: none)",
    )
    parser.add_argument(
        "--chart",
        default=None,
        metavar="NAME",
        help="colour.SDS_COLOURCHECKERS name of your physical chart (default: ColorChecker N Ohta)",
    )
    parser.add_argument(
        "--illuminant-method",
        default="auto",
        metavar="NAME",
        help=f"light spectrum estimate: {', '.join(_METHODS)} (default: auto)",
    )
    parser.add_argument(
        "--illuminant-spectrum",
        metavar="CSV",
        help="the light's known spectrum (wavelength,value), e.g. for LED, fluorescent or sodium "
        "(default: estimated, see --illuminant-method)",
    )
    parser.add_argument(
        "--hdri-width",
        type=int,
        default=None,
        metavar="N",
        help="HDRI integration width (default: 1024)",
    )
    parser.add_argument("--out", required=True, help="output measurements file (.yaml/.json)")
    parser.add_argument("--force", action="store_true", help="replace --out if it exists")
    parser.set_defaults(func=run)


def _average_rgb(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) and v >= 0 for v in values) or not any(values):
        raise InputError(
            f"expected R,G,B: three finite numbers >= 0, not all 0, got {text!r}",
            key="--average-rgb",
        )
    return values


def _check_options(args: argparse.Namespace) -> None:
    if (args.hdri is None) == (args.average_rgb is None):
        raise InputError("give exactly one of --hdri FILE and --average-rgb R,G,B", key="--hdri")
    if args.average_rgb is not None:
        _average_rgb(args.average_rgb)
    if args.camera is not None and args.camera_sensitivities is not None:
        raise InputError("give --camera or --camera-sensitivities, not both", key="--camera")
    if args.illuminant_method not in _METHODS:
        raise InputError(
            f"unknown method {args.illuminant_method!r}; valid: {', '.join(_METHODS)}",
            key="--illuminant-method",
        )
    if args.illuminant_spectrum is not None and args.illuminant_method != "auto":
        raise InputError(
            "give --illuminant-spectrum or --illuminant-method, not both",
            key="--illuminant-spectrum",
        )
    if args.hdri_width is not None and args.hdri_width < 4:
        raise InputError(f"expected a width >= 4, got {args.hdri_width}", key="--hdri-width")
    out = Path(args.out)
    if out.suffix.lower() not in (".yaml", ".yml", ".json"):
        raise InputError("expected a .yaml, .yml or .json file name", source=out, key="--out")
    for given in (
        args.measurements,
        args.hdri,
        args.camera_sensitivities,
        args.illuminant_spectrum,
    ):
        if given is not None and out.exists() and Path(given).exists() and out.samefile(given):
            raise InputError(
                "is an input of this command; choose another output", source=out, key="--out"
            )
    if out.exists() and not args.force:
        raise InputError("exists; choose another output or pass --force", source=out, key="--out")
    if out.exists() and out.is_dir():
        raise InputError("is a folder, not a file", source=out, key="--out")


def _camera(args: argparse.Namespace, measurements):
    from ocio_vp.synthesis import camera_from_colourspace, camera_from_csv, camera_from_dataset

    if args.camera is not None:
        return camera_from_dataset(args.camera)
    if args.camera_sensitivities is not None:
        return camera_from_csv(args.camera_sensitivities)
    if measurements.stage.camera_colorspace is not None:
        return camera_from_colourspace(measurements.stage.camera_colorspace)
    raise InputError(
        "name the camera: --camera NAME or --camera-sensitivities CSV (or set "
        "stage.camera_colorspace to approximate it by its gamut)",
        source=measurements.source,
        key="--camera",
    )


def _light(args: argparse.Namespace):
    from ocio_vp.synthesis import LightSource

    if args.average_rgb is not None:
        import numpy as np

        rgb = np.asarray(_average_rgb(args.average_rgb), dtype=np.float64)
        return LightSource(rgb, args.hdri_colorspace, "average-rgb")
    from ocio_vp.hdri.diffuse import DEFAULT_HDRI_WIDTH, w_avg_from_hdri

    rgb = w_avg_from_hdri(args.hdri, width=args.hdri_width or DEFAULT_HDRI_WIDTH)
    if not (rgb >= 0).all() or not (rgb > 0).any():
        raise InputError(
            f"its diffuse integral {rgb.round(6).tolist()} is not a light", source=args.hdri
        )
    return LightSource(rgb, args.hdri_colorspace, "hdri", hdri=Path(args.hdri).name)


def run(args: argparse.Namespace) -> int:
    from ocio_vp.formats.measurements import (
        check_safe_name,
        load_measurements,
        measurements_from_dict,
        measurements_to_dict,
        save_measurements,
    )
    from ocio_vp.simulator.options import read_spectra_csv
    from ocio_vp.synthesis import DEFAULT_CHART, synthesize_environment, with_environment

    check_safe_name(args.environment, key="--environment")
    _check_options(args)
    measurements = load_measurements(args.measurements)
    camera = _camera(args, measurements)
    spectrum = None
    if args.illuminant_spectrum is not None:
        spectrum = read_spectra_csv(args.illuminant_spectrum, columns=1)[:, 0]
    environment, synth = synthesize_environment(
        measurements,
        args.environment,
        _light(args),
        camera,
        chart=args.chart or DEFAULT_CHART,
        method=args.illuminant_method,
        spectrum=spectrum,
    )
    updated = with_environment(measurements, environment)
    measurements_from_dict(measurements_to_dict(updated), source=args.out)  # never write invalid
    save_measurements(updated, args.out, replace=args.force)
    _summary(args, environment, synth)
    return 0


def _summary(args: argparse.Namespace, environment, synth) -> None:
    record = environment.synthesized
    w_avg = environment.w_avg
    if w_avg is None:  # a stage of several panel types: each one's w_avg from solve --hdri
        w_avg_text = "w_avg per panel type: from `solve --hdri` and the panel types' regions"
    else:
        w_avg_text = f"w_avg {w_avg.round(6).tolist()} camera RGB"
    print(
        f"wrote {args.out}: environment {environment.name} with a synthesized target chart "
        f"({w_avg_text})"
    )
    print(f"  light: {record.illuminant}, CCT {record.cct:.0f} K, Duv {record.duv:+.4f}")
    print(f"  camera: {record.camera}; chart: {record.chart} (x{synth.chart_scale:.4f})")
    if not record.warnings:
        print(
            f"note: {environment.name}: assumes natural, smooth light of this colour; for LED, "
            "fluorescent or sodium light give its spectrum with --illuminant-spectrum CSV"
        )
    for warning in record.warnings:
        print(f"warning: {environment.name}: {warning}")
