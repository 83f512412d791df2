"""One OpenColorIO config per environment, as data (:mod:`ocio_vp.ocio.description`).

Layout (names are module constants so other tools can rely on them):

- ``Camera Native Linear``: the reference, the camera's linear RGB everything was measured in;
- ``LED Wall - Outer Frustum``: reference -> panel drive through M (lights the actors);
- ``LED Wall - Inner Frustum``: through N plus the black-level offset (the background);
- ``Stage Footage``: footage shot on the stage; to the reference applies Q (also the named
  transform ``Post-Correction Q``);
- an ``LED Wall`` display with ``Outer Frustum`` / ``Inner Frustum`` views, for hosts (Unreal
  nDisplay) that pick display/views but not looks or named transforms.

Profile version 2.1, so that Unreal 5.1+ and other OCIO 2.1 hosts load it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.calibration.diagnostics import is_identity, offset_is_negligible
from ocio_vp.calibration.equations import condition_text
from ocio_vp.deprecation import deprecated_names, warn_deprecated
from ocio_vp.formats.linearity import Linearity
from ocio_vp.formats.solution import CONFIG_FILENAME, OcioNames, Solution
from ocio_vp.metrics import rgb_to_rgb_cat02
from ocio_vp.model.correction import MAX_CONDITION_INVERSE, truncated_pseudo_inverse
from ocio_vp.ocio import WORKING_SPACE_NAMES
from ocio_vp.ocio.description import (
    FAMILY,
    ColourSpace,
    ConfigData,
    NamedTransform,
    Transform,
    View,
    build,
    clamp,
    colour_space,
    file,
    group,
    one,
)
from ocio_vp.ocio.matrix import format_matrix, matrix_record, matrix_transform
from ocio_vp.ocio.softclip import soft_clip_text, soft_clip_transforms
from ocio_vp.ocio.viewing import (
    ACESCCT,
    MONITORS,
    add_acescct,
    add_camera_log_spaces,
    add_monitor_displays,
    set_categories,
)
from ocio_vp.spectra import CIE_OBSERVER
from ocio_vp.wall.encoding import WallEncoding
from ocio_vp.wall.softclip import soft_clip_knee

if TYPE_CHECKING:
    from ocio_vp.ocio.bake import ModelOutputs

__all__ = [
    "DISPLAY",
    "IN_FRUSTUM",
    "OUT_OF_FRUSTUM",
    "POST_CORRECTION",
    "POST_CORRECTION_COLORSPACE",
    "RAW",
    "REFERENCE",
    "build_config",
    "config_data",
    "matrix_transform",
    "post_correction_transforms",
    "wall_chains",
    "wall_signal_tail",
    "write_config",
]

REFERENCE = "Camera Native Linear"
OUT_OF_FRUSTUM = "LED Wall - Outer Frustum"
IN_FRUSTUM = "LED Wall - Inner Frustum"
POST_CORRECTION = "Post-Correction Q"
POST_CORRECTION_COLORSPACE = "Stage Footage"
RAW = "Raw"
DISPLAY = "LED Wall"
VIEW_OUTER = "Outer Frustum"
VIEW_INNER = "Inner Frustum"


def _wall_signal_encodings() -> dict[str, str]:
    from ocio_vp.choices import WALL_ENCODINGS

    return {name: WallEncoding(name).ocio_encoding for name in WALL_ENCODINGS}


__getattr__ = deprecated_names(
    __name__,
    {
        "WALL_SIGNAL_ENCODINGS": (
            "ocio_vp.wall.WallEncoding(name).ocio_encoding",
            _wall_signal_encodings,
        ),
        "MAX_CONDITION_Q_FOR_N": (
            "ocio_vp.calibration.MAX_CONDITION_Q_FOR_N",
            "ocio_vp.calibration:MAX_CONDITION_Q_FOR_N",
        ),
        "ModelFiles": (
            "ocio_vp.ocio.bake.ModelOutputs (model_outputs)",
            lambda: _ModelFiles,
        ),
        "wall_tail": (
            "ocio_vp.ocio.config.wall_chains (it appends each wall colour space's tail)",
            lambda: _wall_tail,
        ),
    },
)


@dataclass(frozen=True)
class _ModelFiles:
    """The old ``ModelFiles`` (a non-linear Q's sidecar names and its note), which
    :func:`config_data` still reads, as the three things of ``ModelOutputs`` it uses."""

    q: str
    q_inverse: str | None
    note: str = ""


class _ModelFilesOutputs:
    """``_ModelFiles`` read as ``ModelOutputs`` (file names, ``note()``)."""

    def __init__(self, files: _ModelFiles) -> None:
        self.q_file, self.q_inverse_file, self._note = files.q, files.q_inverse, files.note

    def note(self) -> str:
        return self._note


def _wall_tail(solution: Solution, extra: list[Transform]) -> Chains:
    """The old ``wall_tail``: (drive -> wall signal, wall signal -> drive), the soft clip then
    :func:`wall_signal_tail`, as :func:`wall_chains` appends them."""
    signal = wall_signal_tail(solution, extra)
    undo = [group(signal, inverse=True)] if signal else []
    knee = soft_clip_knee(solution.linearity)
    if knee is None:
        return signal, undo
    clip, unclip = soft_clip_transforms(knee)
    return [*clip, *signal], [*undo, *unclip]


Chains = tuple[list[Transform], list[Transform]]


def post_correction_transforms(
    solution: Solution, model: ModelOutputs | None = None
) -> tuple[Transform, Transform, str]:
    """Q as transform records: (footage -> corrected, corrected -> footage, a note on the
    second), both explicit so that OCIO never inverts a chain (a LUT) by search.

    The inverse is Q^-1 for a 3x3 Q, the baked Q^-1 for a non-linear one (``model``, required:
    ValueError without it), and Q's truncated pseudo-inverse, a bounded stand-in said to be
    one, where Q or the model has no inverse (cond(Q) above :data:`MAX_CONDITION_INVERSE`).
    """
    correction = solution.correction
    Q = correction.matrix
    if not correction.linear and model is None:
        raise ValueError(
            f"a {correction.kind} post-correction needs its LUT files (ocio_vp.ocio.bake); "
            "the config would otherwise carry only its 3x3"
        )
    forward = matrix_record(Q) if model is None else file(model.q_file)
    if model is not None and model.q_inverse_file is not None:
        text = f"The inverse direction is the baked Q^-1 ({model.q_inverse_file})."
        return forward, file(model.q_inverse_file), text
    if correction.invertible and model is None:
        return forward, matrix_record(Q, inverse=True), ""
    pinv, rank = truncated_pseudo_inverse(Q)
    if model is not None:
        text = (
            f"The inverse direction (reference -> Stage Footage) is NOT PROVIDED as the model's "
            f"inverse: the {correction.kind} model has none (its 3x3 has rank {rank} at cond <= "
            f"{MAX_CONDITION_INVERSE:g}). That direction is a bounded stand-in, the 3x3's "
            f"truncated pseudo-inverse {format_matrix(pinv)}, so that a host asking for it gets finite "
            "numbers at once; do not use it to undo the post-correction."
        )
        return forward, matrix_record(pinv), text
    text = (
        f"Q has rank {rank} at cond <= {MAX_CONDITION_INVERSE:g} (cond(Q) "
        f"{condition_text(float(np.linalg.cond(Q)))}): it cannot be inverted, so the inverse "
        "direction (reference -> Stage Footage, the inverse of the named transform) is Q's "
        f"truncated pseudo-inverse {format_matrix(pinv)}, bounded, not a true inverse."
    )
    return forward, matrix_record(pinv), text


def wall_signal_tail(solution: Solution, extra: list[Transform]) -> list[Transform]:
    """``extra`` (the wall's LUT and encoding) between clamps to the encoding's domain (drive
    in [0, top], signal in [0, 1]), outside which OCIO versions disagree (PQ below 0); empty
    without ``extra`` (a linear wall stays affine)."""
    if not extra:
        return []
    top = WallEncoding.of(solution.linearity).signal_top
    if top is None:
        return [clamp(min_in=0.0, min_out=0.0), *extra]
    return [
        clamp(min_in=0.0, max_in=top, min_out=0.0, max_out=top),
        *extra,
        clamp(min_in=0.0, max_in=1.0, min_out=0.0, max_out=1.0),
    ]


def wall_chains(
    solution: Solution, extra: dict[str, list[Transform]], model: ModelOutputs | None
) -> dict[str, Chains]:
    """(reference -> wall signal, wall signal -> reference) chains of the two wall colour
    spaces: the drive (M; N and the offset), then the soft clip the solve asked for
    (:mod:`ocio_vp.ocio.softclip`) and :func:`wall_signal_tail` of ``extra`` (that space's LUT
    and encoding), undone before the other direction.

    With ``model`` (a non-linear Q's sidecars) and N solved, the in-frustum drive is
    ``[SL]^-1 Q^-1(c)`` (the Q^-1 file, then the calibrated ``[SL]^-1``) and its other
    direction ``Q([SL] d)``: OCIO never inverts a LUT file.
    """
    outer = [matrix_record(solution.M)]
    outer_back = [matrix_record(solution.M, inverse=True)]
    # an offset the camera cannot see is left out (docs/stability.md); solution.json keeps it
    offset = solution.black_level_offset
    if offset_is_negligible(offset, solution.SL):
        offset = None
    inner = [matrix_record(solution.in_frustum_matrix, offset)]
    inner_back = [matrix_record(solution.in_frustum_matrix, offset, inverse=True)]
    if model is not None and solution.N is not None:
        if model.q_inverse_file is None:
            raise ValueError("N is solved but the non-linear Q has no baked inverse")
        # N inverts Q for the calibrated wall, [SL]^-1, whatever M lights with (joint's M)
        calibrated = np.linalg.inv(np.asarray(solution.SL, dtype=np.float64))
        inner = [file(model.q_inverse_file), matrix_record(calibrated, offset)]
        inner_back = [matrix_record(calibrated, offset, inverse=True), file(model.q_file)]
    knee = soft_clip_knee(solution.linearity)
    clip, unclip = ([], []) if knee is None else soft_clip_transforms(knee)
    chains = {}
    for name, there, back in ((OUT_OF_FRUSTUM, outer, outer_back), (IN_FRUSTUM, inner, inner_back)):
        signal = wall_signal_tail(solution, list(extra.get(name, [])))
        undo = [group(signal, inverse=True)] if signal else []
        chains[name] = ([*there, *clip, *signal], [*undo, *unclip, *back])
    return chains


def build_config(
    solution: Solution,
    *,
    extra_wall_transforms: dict[str, list[Transform]] | None = None,
    search_path: str | None = None,
    model: ModelOutputs | None = None,
) -> OCIO.Config:
    """The validated OCIO config of :func:`config_data`."""
    return build(
        config_data(
            solution,
            extra_wall_transforms=extra_wall_transforms,
            search_path=search_path,
            model=model,
        )
    )


def config_data(
    solution: Solution,
    *,
    extra_wall_transforms: dict[str, list[Transform]] | None = None,
    search_path: str | None = None,
    model: ModelOutputs | None = None,
) -> ConfigData:
    """What the config of one solved environment holds, as data.

    Parameters
    ----------
    solution
        The solved environment.
    extra_wall_transforms
        Records appended to each wall colour space's chain (its linearity LUT and encoding).
    search_path
        The config's search path for sidecar files (e.g. ``"luts"``).
    model
        A non-linear post-correction's LUT sidecars, in place of the matrices Q and N.

    Raises
    ------
    ValueError
        A non-linear post-correction without ``model``.
    """
    if isinstance(model, _ModelFiles):  # the deprecated ModelFiles
        model = cast("ModelOutputs", _ModelFilesOutputs(model))
    origin = _origin(solution)
    data = ConfigData(
        name=f"ocio-vp_{solution.stage}_{solution.environment}",
        description=f"ocio_vp calibration of {origin}. Q method: {solution.method} "
        f"(model {solution.model}). LeGendre, Lepicovsky & Debevec, DigiPro 2022.",
        search_path=search_path or "",
    )
    data.colour_spaces += _camera_spaces(solution.camera_colorspace)
    chains = wall_chains(solution, extra_wall_transforms or {}, model)
    outer = f"M = [SL]^-1 {format_matrix(solution.M)}"
    inner = _in_frustum_text(solution, model)
    for name, inside, drive in ((OUT_OF_FRUSTUM, False, outer), (IN_FRUSTUM, True, inner)):
        text = drive_description(inside, drive, solution.linearity, origin)
        data.colour_spaces.append(wall_space(name, text, solution.linearity, chains[name]))
    _add_post_correction(data, solution, origin, model)
    camera_to_aces = _set_roles(data, solution.camera_colorspace)
    _add_displays(data, camera_to_aces)
    set_categories(data)
    return data


def _add_displays(data: ConfigData, camera_to_aces: np.ndarray | None) -> None:
    """Monitor displays first (the viewer's default is a monitor view), then ``LED Wall``."""
    add_monitor_displays(
        data, camera_to_aces, reference=REFERENCE, footage=POST_CORRECTION_COLORSPACE
    )
    for view, space in ((VIEW_OUTER, OUT_OF_FRUSTUM), (VIEW_INNER, IN_FRUSTUM), ("Raw", RAW)):
        data.views.append(View(DISPLAY, view, space))
    displays = [*dict.fromkeys(m.display for m in MONITORS), DISPLAY]
    data.active_displays = tuple(displays)
    views = [v for d in displays[:-1] for v in data.view_names(d)]
    data.active_views = (*dict.fromkeys(views), VIEW_INNER, VIEW_OUTER, "Raw")


def _origin(solution: Solution) -> str:
    origin = f"stage {solution.stage!r}, environment {solution.environment!r}"
    if solution.measurements_sha256:
        origin += (
            f", from {solution.measurements_file or 'measurements'} "
            f"(sha256 {solution.measurements_sha256[:16]})"
        )
    return origin


def _camera_spaces(camera: str | None) -> list[ColourSpace]:
    gamut_text = f" ({camera} primaries)" if camera else " (as measured; gamut not stated)"
    reference = colour_space(
        REFERENCE,
        f"The camera's native linear RGB{gamut_text}: the space all calibration values were "
        "measured in. Content for the LED wall is expected here.",
        family="Camera",
    )
    raw = colour_space(
        RAW, "Data: no colour conversion.", family="Utility", encoding="data", is_data=True
    )
    return [reference, raw]


def wall_space(
    name: str, description: str, linearity: Linearity | None, chains: Chains
) -> ColourSpace:
    """A wall colour space: reference -> drive (``chains[0]``) and back, both explicit."""
    there, back = chains
    return colour_space(
        name,
        description,
        family="LED Wall",
        encoding=WallEncoding.of(linearity).ocio_encoding,
        from_reference=one(there),
        to_reference=one(back),
    )


def drive_description(
    inside: bool, drive: str, linearity: Linearity | None, origin: str, panel: str = ""
) -> str:
    """The description of a wall colour space (of panel type ``panel``, "" for the wall's):
    content inside or outside the frustum, the ``drive`` in words, the soft clip, ``origin``."""
    of = f" of panel type {panel!r}" if panel else ""
    where = (
        "INSIDE the camera frustum (the in-camera background)"
        if inside
        else "OUTSIDE the camera frustum (lights the actors)"
    )
    return f"Panel drive{of} for content {where}: {drive}{soft_clip_text(linearity)}. {origin}."


def in_frustum_text(
    M: np.ndarray,
    N: np.ndarray | None,
    offset: np.ndarray | None,
    N_reason: str | None,
    *,
    N_text: str | None = None,
) -> str:
    """What an in-frustum drive is (the wall's and every panel type's): ``N_text`` (default
    N = M Q^-1) or, N not solved, M and why; plus the black-level offset."""
    if N is None:
        text = f"N NOT SOLVED ({N_reason}); M is used instead, {format_matrix(M)}"
    else:
        text = N_text or f"N = M Q^-1 {format_matrix(N)}"
    if offset is not None:
        text += f", plus black-level offset {format_matrix(offset[None])}"
    return text


def _in_frustum_text(solution: Solution, model: ModelOutputs | None = None) -> str:
    N_text = None
    if solution.N is not None and model is not None:
        N_text = (
            f"[SL]^-1 Q^-1(c), the baked inverse of the {solution.correction.kind} Q "
            f"({model.q_inverse_file}) then [SL]^-1 {format_matrix(np.linalg.inv(solution.SL))} (N = "
            f"[SL]^-1 Q^-1 for its 3x3 would be {format_matrix(solution.N)})"
        )
    elif solution.N is not None and is_identity(solution.Q):
        N_text = f"N = M (Q is the identity, so no in-frustum change is needed) {format_matrix(solution.N)}"
    text = in_frustum_text(
        solution.M,
        solution.N,
        solution.black_level_offset,
        solution.diagnostics.N_reason or "Q is not invertible",
        N_text=N_text,
    )
    if solution.black_level_offset is not None:
        text += f" ({solution.black_level_method})"
        if offset_is_negligible(solution.black_level_offset, solution.SL):
            text += " - negligible (below 1e-5 of the wall's white), left out of this transform"
    return text


def _add_post_correction(
    data: ConfigData,
    solution: Solution,
    origin: str,
    model: ModelOutputs | None = None,
) -> None:
    """Q twice: the ``Stage Footage`` colour space and the ``Post-Correction Q`` named
    transform (a non-linear Q as its ``model`` sidecars; its matrix then only printed)."""
    q_identity = is_identity(solution.Q) and model is None
    reason = solution.diagnostics.model_reason
    q_text = (
        f"Post-correction Q {format_matrix(solution.Q)} for footage shot on the stage ({solution.method}, "
        f"model {solution.model}{': ' + reason if reason else ''}). {origin}."
    )
    if model is not None:
        q_text = (
            f"The {solution.correction.kind} Q ({solution.correction.describe()}) as a LUT chain "
            f"({model.q_file}; the matrix below is only its 3x3 approximation). {model.note()} "
            + q_text
        )
    if q_identity:
        q_text = "Q is the identity: no post-correction is needed. " + q_text
    forward, inverse, inverse_text = post_correction_transforms(solution, model)
    if inverse_text:
        q_text += " " + inverse_text
    if q_identity:
        forward = inverse = group([])
    data.colour_spaces.append(
        colour_space(
            POST_CORRECTION_COLORSPACE,
            "Camera linear RGB as recorded on the stage; converting to the reference applies Q. "
            + q_text,
            family="Camera",
            to_reference=None if q_identity else forward,
            from_reference=None if q_identity else inverse,
        )
    )
    data.named_transforms.append(
        NamedTransform(POST_CORRECTION, f"{FAMILY}/Post", q_text, forward, inverse)
    )


def _set_roles(data: ConfigData, camera: str | None) -> np.ndarray | None:
    """Every role on the reference; with the camera gamut known, the interchange roles, ACEScct
    as ``compositing_log`` and ``color_timing`` (as the ACES configs) and the camera's log
    spaces (without it, no log role: a linear space there breaks tools that key in log).

    Returns the reference -> ACES2065-1 matrix (None when the camera gamut is unknown)."""
    roles = {
        OCIO.ROLE_SCENE_LINEAR: REFERENCE,
        OCIO.ROLE_REFERENCE: REFERENCE,
        OCIO.ROLE_DEFAULT: REFERENCE,
        OCIO.ROLE_DATA: RAW,
        OCIO.ROLE_COLOR_PICKING: REFERENCE,
        OCIO.ROLE_TEXTURE_PAINT: REFERENCE,
        OCIO.ROLE_MATTE_PAINT: REFERENCE,
    }
    camera_to_aces = None
    if camera:
        working, aces_to_camera = _add_working_spaces(data, camera)
        roles.update(working)
        add_acescct(data, aces_to_camera)
        roles[OCIO.ROLE_COMPOSITING_LOG] = ACESCCT
        roles[OCIO.ROLE_COLOR_TIMING] = ACESCCT
        add_camera_log_spaces(data, camera, reference=REFERENCE, footage=POST_CORRECTION_COLORSPACE)
        camera_to_aces = np.linalg.inv(aces_to_camera)
    data.roles.update(roles)
    return camera_to_aces


def _add_working_spaces(data: ConfigData, camera: str) -> tuple[dict[str, str], np.ndarray]:
    """Add ACES2065-1, ACEScg, linear Rec.709 (CAT02 to the camera gamut) and CIE-XYZ-D65;
    returns their roles and the ACES2065-1 -> camera matrix."""
    import colour

    target = colour.RGB_COLOURSPACES[camera]
    roles = {}
    aces_to_camera = np.eye(3)
    for key, name in WORKING_SPACE_NAMES.items():
        to_camera = rgb_to_rgb_cat02(key, camera)
        if key == "ACES2065-1":
            aces_to_camera = to_camera
            roles[OCIO.ROLE_INTERCHANGE_SCENE] = name
        data.colour_spaces.append(
            colour_space(
                name,
                f"{colour.RGB_COLOURSPACES[key].name} linear; to the reference ({camera}) by colour-science's "
                "matrix_RGB_to_RGB with CAT02 adaptation.",
                family="Working",
                to_reference=matrix_record(to_camera),
            )
        )
    d65 = colour.CCS_ILLUMINANTS[CIE_OBSERVER]["D65"]
    to_xyz = (
        colour.adaptation.matrix_chromatic_adaptation_VonKries(
            colour.xy_to_XYZ(target.whitepoint), colour.xy_to_XYZ(d65), transform="CAT02"
        )
        @ target.matrix_RGB_to_XYZ
    )
    data.colour_spaces.append(
        colour_space(
            "CIE-XYZ-D65",
            f"CIE 1931 XYZ, D65 white; from the reference by {camera}'s RGB-to-XYZ matrix with "
            "CAT02 adaptation to D65 (colour-science).",
            family="Utility",
            from_reference=matrix_record(to_xyz),
        )
    )
    roles[OCIO.ROLE_INTERCHANGE_DISPLAY] = "CIE-XYZ-D65"
    return roles, aces_to_camera


def ocio_names(config_filename: str | None = None) -> OcioNames:
    """The ``ocio`` block of ``solution.json``: which colorspace does what.

    ``config_filename`` (deprecated) names the config other than :data:`CONFIG_FILENAME`."""
    if config_filename is not None:
        warn_deprecated("ocio_names(config_filename=...)", "ocio_names() (a config.ocio)")
    return OcioNames(
        config=CONFIG_FILENAME if config_filename is None else config_filename,
        reference=REFERENCE,
        out_of_frustum=OUT_OF_FRUSTUM,
        in_frustum=IN_FRUSTUM,
        post_correction=POST_CORRECTION,
        post_correction_colorspace=POST_CORRECTION_COLORSPACE,
        display=DISPLAY,
        view_out_of_frustum=VIEW_OUTER,
        view_in_frustum=VIEW_INNER,
    )


def write_config(config: OCIO.Config, directory: str | Path) -> Path:
    """Serialize ``config`` to ``directory/config.ocio``; returns its path."""
    path = Path(directory) / CONFIG_FILENAME
    path.write_text(config.serialize(), encoding="utf-8")
    return path
