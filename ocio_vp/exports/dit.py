"""``dit``: a 3D LUT for the DIT cart, log in and log out (footage in the camera's log
encoding -> the same footage post-corrected, in the same encoding).

Baked from the environment's config over the log range [0, 1] and kept only where it meets
:data:`~ocio_vp.exports.cube.CUBE_LIMIT`; otherwise ``dit.json`` says why. Only for
environments whose camera gamut (and so log curve) is known.
"""

from __future__ import annotations

from pathlib import Path

from ocio_vp.errors import InputError
from ocio_vp.exports.cube import CUBE_LIMIT, fit_cube
from ocio_vp.exports.source import (
    DEFAULT_CUBES,
    CubeOptions,
    ExportSource,
    ExportSummary,
    write_json,
)
from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.ocio.camera_log import camera_log_for
from ocio_vp.ocio.viewing import camera_log_names

__all__ = ["DIT_MANIFEST", "has_camera_log", "write_dit"]

DIT_MANIFEST = "dit.json"
#: The log signal's range (a log encoding maps scene-linear footage into [0, 1]).
LOG_RANGE = (0.0, 1.0)


def has_camera_log(source: ExportSource) -> bool:
    """Whether the environment's config carries its camera's log footage spaces."""
    curve = camera_log_for(source.solution.camera_colorspace)
    return curve is not None and source.config.getColorSpace(camera_log_names(curve)[1]) is not None


def write_dit(
    source: ExportSource, folder: Path, cubes: CubeOptions = DEFAULT_CUBES
) -> ExportSummary:
    """Write the log-in log-out cube (where it meets the limit) and ``dit.json``."""
    solution = source.solution
    curve = camera_log_for(solution.camera_colorspace)
    if curve is None or not has_camera_log(source):
        raise InputError(
            "no camera log encoding in this solution (solve with --camera-colorspace NAME)",
            source=str(source.directory),
        )
    native, footage = camera_log_names(curve)
    name = f"{solution.environment}_{curve.short}_post_correction_{cubes.size}.cube"
    result = fit_cube(
        source.config.getProcessor(footage, native),
        folder / name,
        size=cubes.size,
        input_range=LOG_RANGE,
        title=f"ocio-vp DIT {solution.environment}: {footage} -> {native}",
    )
    not_written = (
        None
        if result.path is not None
        else f"{result.reason}; use the config's {footage!r} -> {native!r} (exact)"
    )
    manifest: JsonObject = {
        "format": "ocio-vp/dit-export",
        "version": 1,
        "stage": solution.stage,
        "environment": solution.environment,
        "encoding": curve.name,
        "from": footage,
        "to": native,
        "cube_limit": CUBE_LIMIT,
        "cube": name if result.path is not None else None,
        "accuracy": None
        if result.errors is None or result.path is None
        else result.errors.to_dict(),
        "not_written": not_written,
    }
    write_json(folder / DIT_MANIFEST, manifest)
    if result.path is not None and result.errors is not None:
        return ExportSummary(files=(DIT_MANIFEST, name), cubes={name: result.errors})
    return ExportSummary(files=(DIT_MANIFEST,), not_written={name: str(not_written)})
