"""What a pipeline needs around the wall colour spaces: log spaces, roles and monitor displays.

With the camera gamut known, ``ACEScct`` and the camera's log encoding (corrected footage and
stage footage in it); always the look ``Post-Correction Q Look`` and the :data:`MONITORS`
displays of OCIO's built-in ACES CG config (docs/architecture.md, *Monitor displays*).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.choices import DEFAULT_BASE_CONFIG
from ocio_vp.ocio.camera_log import LogCurve, camera_log_for, log_transform
from ocio_vp.ocio.description import (
    ColourSpace,
    ConfigData,
    Look,
    Transform,
    View,
    ViewTransform,
    clamp,
    colour_space,
    colour_space_record,
    group,
    transform_record,
)
from ocio_vp.ocio.matrix import matrix_record
from ocio_vp.spectra import packaged_json

__all__ = [
    "ACESCCT",
    "ACES_CG_CONFIG",
    "FOOTAGE_VIEW_SUFFIX",
    "MONITORS",
    "POST_CORRECTION_LOOK",
    "Monitor",
    "add_camera_log_spaces",
    "add_monitor_displays",
    "camera_log_names",
    "footage_to_reference",
    "set_categories",
]

#: OCIO's built-in ACES CG config that every OCIO from 2.2 on has (profile 2.1).
ACES_CG_CONFIG = DEFAULT_BASE_CONFIG
ACESCCT = "ACEScct"
POST_CORRECTION_LOOK = "Post-Correction Q Look"
FOOTAGE_VIEW_SUFFIX = " - Stage Footage after Q"
#: View used without a camera gamut (no ACES output transform can apply).
UNTONEMAPPED_VIEW = "Un-tone-mapped (camera RGB as Rec.709)"


@dataclass(frozen=True)
class Monitor:
    """A monitor display of the ACES CG config and the ACES view its content is seen through."""

    display: str
    view: str


MONITORS = (
    Monitor("sRGB - Display", "ACES 1.0 - SDR Video"),
    Monitor("Rec.1886 Rec.709 - Display", "ACES 1.0 - SDR Video"),
    Monitor("ST2084-P3-D65 - Display", "ACES 1.1 - HDR Video (1000 nits & P3 lim)"),
)


@functools.lru_cache(maxsize=1)
def _aces_config() -> OCIO.Config:
    # Parsed once a process, not once an environment written; every caller only reads it.
    return OCIO.Config.CreateFromFile(ACES_CG_CONFIG)


def camera_log_names(curve: LogCurve) -> tuple[str, str]:
    """(corrected footage in the camera's log, stage footage in it): the colour space names."""
    return f"Camera Native ({curve.short})", f"Stage Footage ({curve.short})"


def footage_to_reference(footage: ColourSpace) -> tuple[Transform, Transform | None]:
    """``footage``'s conversion to the reference (Q, as it carries it) and its explicit
    inverse (None: OCIO's own)."""
    to_ref, from_ref = footage.to_reference, footage.from_reference
    if to_ref is None and from_ref is not None:  # only the other direction: OCIO inverts it
        to_ref, from_ref = dataclasses.replace(from_ref, inverse=True), None
    return (group([]) if to_ref is None else to_ref), from_ref


def add_camera_log_spaces(
    data: ConfigData, camera: str | None, *, reference: str, footage: str
) -> None:
    """Add ``Camera Native (LogC4)`` and ``Stage Footage (LogC4)`` (for ``camera``'s log curve;
    nothing without a known camera gamut)."""
    curve = camera_log_for(camera)
    if curve is None:
        return
    native_name, footage_name = camera_log_names(curve)
    encode = transform_record(log_transform(curve))
    native = colour_space(
        native_name,
        f"{reference} encoded as {curve.name} ({camera}): footage after Q, in "
        "the camera's own log encoding (the DIT cart's log out).",
        family="Camera",
        encoding="log",
        from_reference=encode,
    )
    forward, inverse = footage_to_reference(data.colour_space(footage))
    decode = transform_record(log_transform(curve, OCIO.TRANSFORM_DIR_INVERSE))
    stage = colour_space(
        footage_name,
        f"Footage recorded on the stage in {curve.name} ({camera}): converting it to "
        f"{reference} decodes it and applies the post-correction, exactly as {footage!r}.",
        family="Camera",
        encoding="log",
        to_reference=group([decode, forward]),
        from_reference=None if inverse is None else group([inverse, encode]),
    )
    data.colour_spaces += [native, stage]


#: OCIO 2.1 categories (what application menus filter on) by family, after ``ocio-vp/``.
CATEGORIES = {
    "Camera": ("file-io", "working-space"),
    "Working": ("file-io", "working-space"),
    "LED Wall": ("file-io",),
    "Utility": ("file-io",),
}


def set_categories(data: ConfigData) -> None:
    """Categories (by family) for every scene colour space and named transform that has none,
    so that hosts whose menus filter by category list them."""

    def categorised(cs: ColourSpace) -> ColourSpace:
        if cs.categories or cs.display_referred:
            return cs
        family = cs.family.split("/")[1] if "/" in cs.family else ""
        return dataclasses.replace(cs, categories=CATEGORIES.get(family, ("file-io",)))

    data.colour_spaces = [categorised(cs) for cs in data.colour_spaces]
    data.named_transforms = [
        nt if nt.categories else dataclasses.replace(nt, categories=("file-io",))
        for nt in data.named_transforms
    ]


def add_acescct(data: ConfigData, aces_to_camera: np.ndarray) -> None:
    """ACEScct (OCIO's builtin curve and AP1 -> AP0) then ACES2065-1 -> the camera gamut."""
    source = _aces_config().getColorSpace(ACESCCT)
    to_ref = transform_record(source.getTransform(OCIO.COLORSPACE_DIR_TO_REFERENCE))
    cs = colour_space(
        ACESCCT,
        "ACEScct (ACES log for grading and compositing), as in OCIO's built-in ACES "
        "CG config, then ACES2065-1 to the camera gamut.",
        family="Working",
        encoding="log",
        to_reference=group([to_ref, matrix_record(aces_to_camera)]),
    )
    data.colour_spaces.append(cs)


def _look(data: ConfigData, *, reference: str, footage: str) -> Look:
    forward, inverse = footage_to_reference(data.colour_space(footage))
    return Look(
        name=POST_CORRECTION_LOOK,
        process_space=reference,
        transform=forward,
        description=f"The post-correction Q, exactly as {footage!r} -> {reference!r}: for "
        "monitor views of footage recorded on the stage (tagged as the reference).",
        inverse=inverse,
    )


def add_monitor_displays(
    data: ConfigData,
    camera_to_aces: np.ndarray | None,
    *,
    reference: str,
    footage: str,
) -> None:
    """Add the :data:`MONITORS` displays, their view transforms and the Q look.

    ``camera_to_aces`` (the reference -> ACES2065-1 matrix) puts the ACES output transforms
    after it; None (camera gamut unknown) shows the reference as Rec.709, un-tone-mapped.
    """
    aces = _aces_config()
    data.looks.append(_look(data, reference=reference, footage=footage))
    added = set()
    for monitor in MONITORS:
        if not data.has_colour_space(monitor.display):
            display = colour_space_record(aces.getColorSpace(monitor.display))
            data.colour_spaces.append(_clamped_display(display))
        view = monitor.view if camera_to_aces is not None else UNTONEMAPPED_VIEW
        if view not in added:
            data.view_transforms.append(_view_transform(aces, view, camera_to_aces))
            added.add(view)
        data.views.append(View(monitor.display, view, monitor.display, view_transform=view))
        data.views.append(
            View(
                monitor.display,
                view + FOOTAGE_VIEW_SUFFIX,
                monitor.display,
                view_transform=view,
                looks=POST_CORRECTION_LOOK,
            )
        )


def _clamped_display(display: ColourSpace) -> ColourSpace:
    """An ACES config display colour space; a PQ one with its negative signal clamped to 0 both
    ways (OCIO versions disagree on PQ below 0; a monitor shows no negative signal)."""
    encode = display.from_reference
    if "ST2084" not in display.name or encode is None or display.to_reference is not None:
        return display
    floor = clamp(min_in=0.0, min_out=0.0)
    decode = dataclasses.replace(encode, inverse=True)
    return dataclasses.replace(
        display, from_reference=group([encode, floor]), to_reference=group([floor, decode])
    )


#: colour-science's ITU-R BT.709 RGB-to-XYZ matrix, in the package (written by
#: ``python -m benchmarks.make_sample_matrix``): the process writing configs imports no
#: colour-science for it.
REC709_MATRIX_FILE = "data/rec709_to_xyz.json"


@functools.lru_cache(maxsize=1)
def rec709_to_xyz() -> np.ndarray:
    """(3, 3) ITU-R BT.709 linear RGB to CIE XYZ (D65), as colour-science computes it (read
    from :data:`REC709_MATRIX_FILE`; tests/test_ocio_viewing.py checks every bit). Read-only."""
    matrix = np.array(packaged_json(REC709_MATRIX_FILE)["rgb_to_xyz"], dtype=np.float64)
    matrix.setflags(write=False)
    return matrix


def _view_transform(aces, name: str, camera_to_aces) -> ViewTransform:
    if camera_to_aces is None:
        # clamped to [0, 100] (10000 nits on the PQ monitor): there is no tone curve to bound it
        bound = clamp(min_in=0.0, max_in=100.0, min_out=0.0, max_out=100.0)
        return ViewTransform(
            name,
            "The camera gamut is not stated (set stage.camera_colorspace or solve "
            "--camera-colorspace): camera RGB is shown as if it were linear Rec.709, "
            "un-tone-mapped. Colours are only indicative.",
            group([matrix_record(rec709_to_xyz()), bound]),
        )
    source = aces.getViewTransform(name)
    builtin = source.getTransform(OCIO.VIEWTRANSFORM_DIR_FROM_REFERENCE)
    return ViewTransform(
        name,
        f"{source.getDescription().strip()}\n(after the camera gamut -> ACES2065-1)",
        group([matrix_record(camera_to_aces), transform_record(builtin)]),
    )
