"""A target chart for a CG environment: the chart a camera would record under the HDRI's light.

For a rendered environment there is no location to photograph the chart in (p_j, eq. 5); as
the paper's future work proposes, the chart is rendered spectrally from the environment's w_avg
(Section 3.3): a light spectrum whose camera RGB is exactly w_avg
(:mod:`ocio_vp.synthesis.illuminant`), then ``p_j = sum S R_j E`` (:mod:`.camera`, :mod:`.chart`).
docs/target_chart.md says what it assumes; the environment written carries them in a
``synthesized`` record, which ``solve`` repeats as a warning.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, Sections 3.3 and 6
("Extending our Approach to CG Scenes"). https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import Environment, Measurements
from ocio_vp.formats.synthesis import SynthesisRecord
from ocio_vp.metrics import rgb_to_rgb_cat02
from ocio_vp.spectra import unknown_name
from ocio_vp.synthesis.camera import CameraModel
from ocio_vp.synthesis.chart import DEFAULT_CHART, chart_spectra, scaled_to_white
from ocio_vp.synthesis.illuminant import IlluminantEstimate, estimate_illuminant, given_illuminant

__all__ = [
    "CAMERA_SPACE",
    "LightSource",
    "SynthesizedTarget",
    "rgb_to_camera",
    "synthesize_environment",
    "synthesize_target",
    "with_environment",
]

#: ``--hdri-colorspace`` value meaning the camera's native linear RGB (the measurements' space).
CAMERA_SPACE = "camera"
_ALIASES = {"Linear Rec.709": "Linear Rec.709 (sRGB)"}


def rgb_to_camera(rgb: ArrayLike, colorspace: str, camera_colorspace: str | None) -> np.ndarray:
    """(3,) an HDRI's RGB in ``colorspace`` as camera linear RGB.

    ``"camera"`` is returned as is. Another ``colour.RGB_COLOURSPACES`` name (or ``Linear
    Rec.709``) goes to ``camera_colorspace`` by :func:`ocio_vp.metrics.rgb_to_rgb_cat02`, as the
    OCIO config converts that working space for the wall.

    Examples
    --------
    >>> np.round(rgb_to_camera([1.0, 1.0, 1.0], "ACEScg", "ACES2065-1"), 6).tolist()
    [1.0, 1.0, 1.0]
    """
    import colour

    rgb = np.asarray(rgb, dtype=np.float64)
    if colorspace == CAMERA_SPACE:
        return rgb
    name = _ALIASES.get(colorspace, colorspace)
    if name not in colour.RGB_COLOURSPACES:
        valid = [
            CAMERA_SPACE,
            "ACES2065-1",
            "ACEScg",
            "Linear Rec.709",
            "(colour.RGB_COLOURSPACES)",
        ]
        raise InputError(unknown_name("colour space", colorspace, valid), key="--hdri-colorspace")
    if camera_colorspace is None:
        raise InputError(
            f"RGB in {colorspace} cannot be put into the camera's RGB: the stage has no "
            "camera_colorspace (the gamut the wall's content is converted to); set "
            "stage.camera_colorspace or give the RGB in the camera's space ('camera')",
            key="--hdri-colorspace",
        )
    return rgb_to_rgb_cat02(name, camera_colorspace) @ rgb


@dataclass(frozen=True)
class SynthesizedTarget:
    """The chart (n, 3) camera RGB, the light behind it and the chart's white scale.

    ``negative_patches``: patches whose rendered RGB had a channel below 0 (possible only
    through a colour-space camera model), clipped to 0 in ``target_chart``.
    """

    target_chart: np.ndarray
    w_avg: np.ndarray
    illuminant: IlluminantEstimate
    chart_scale: float
    negative_patches: tuple[int, ...] = ()


def synthesize_target(
    w_avg: ArrayLike,
    camera: CameraModel,
    reflectances: ArrayLike,
    *,
    white_patch: int = DEFAULT_WHITE_PATCH,
    white_reflectance: float = 0.9,
    method: str = "auto",
    spectrum: ArrayLike | None = None,
) -> SynthesizedTarget:
    """The chart the camera records under a light of camera RGB ``w_avg`` (module docstring).

    Parameters
    ----------
    w_avg
        (3,) the environment's diffuse integral in camera linear RGB.
    camera
        The camera model (its observer renders the chart).
    reflectances
        (n, W) the chart, scaled here so patch ``white_patch`` reads ``white_reflectance``.
    method
        An :data:`~ocio_vp.synthesis.illuminant.ILLUMINANT_METHODS` name or ``"auto"``.
    spectrum
        (W,) the light's known spectrum instead of an estimate (kept in shape).

    Examples
    --------
    The white patch reads about the white reflectance (0.9 by default) times w_avg:

    >>> from ocio_vp.synthesis.camera import camera_from_dataset
    >>> from ocio_vp.synthesis.chart import chart_spectra
    >>> t = synthesize_target([1.0, 1.0, 1.0], camera_from_dataset("Nikon 5100 (NPL)"),
    ...                       chart_spectra())
    >>> np.round(t.target_chart[18] / t.w_avg, 2).tolist()
    [0.9, 0.9, 0.89]
    """
    w_avg = np.asarray(w_avg, dtype=np.float64)
    if w_avg.shape != (3,) or not np.all(np.isfinite(w_avg)) or np.any(w_avg < 0):
        raise InputError(f"w_avg must be three finite values >= 0, got {w_avg.tolist()}")
    if not np.any(w_avg > 0):
        raise InputError("w_avg is black: the environment gives no light")
    if spectrum is None:
        estimate = estimate_illuminant(w_avg, camera, method=method)
    else:
        estimate = given_illuminant(spectrum, w_avg, camera)
    chart = scaled_to_white(reflectances, white_patch, white_reflectance, camera.observer[:, 1])
    target = camera.render(chart.reflectances * estimate.spectrum)
    negative = tuple(int(j) for j in np.flatnonzero(np.any(target < 0, axis=1)))
    return SynthesizedTarget(
        target_chart=np.maximum(target, 0.0),
        w_avg=camera.render(estimate.spectrum),
        illuminant=estimate,
        chart_scale=chart.scale,
        negative_patches=negative,
    )


@dataclass(frozen=True)
class LightSource:
    """Where an environment's light comes from: an HDRI file or an average RGB, and its space."""

    rgb: np.ndarray
    colorspace: str
    kind: str  # "hdri" or "average-rgb"
    hdri: str | None = None


def _assumptions(synth: SynthesizedTarget, light: LightSource, camera, chart: str, stage) -> list:
    e = synth.illuminant
    lines = [
        "the chart is lit by the environment's diffuse integral w_avg (a Lambertian chart "
        "facing the HDRI's centre), as the out-of-frustum wall will light the actors",
        f"the light's spectrum is {e.label} (CCT {e.cct:.0f} K, Duv {e.duv:+.4f}), matched "
        "exactly to w_avg's colour; a spiky light (LED, fluorescent, discharge) of the same "
        "colour would render the chart differently",
        f"camera: {camera.description}",
        f"chart: {chart} spectral data scaled by {synth.chart_scale:.4f} so the white patch "
        f"reads the file's white_reflectance {stage.white_reflectance:g}",
    ]
    if light.colorspace != CAMERA_SPACE:
        lines.append(
            f"the {light.colorspace} RGB was converted to {stage.camera_colorspace} with CAT02, "
            "as the OCIO config converts that space for the wall"
        )
    return lines


def _warnings(synth: SynthesizedTarget) -> list:
    warnings = list(synth.illuminant.warnings)
    if synth.negative_patches:
        warnings.append(
            f"patches {list(synth.negative_patches)} came out with a negative channel through "
            "the colour-space camera model and were clipped to 0"
        )
    return warnings


def synthesize_environment(
    measurements: Measurements,
    name: str,
    light: LightSource,
    camera: CameraModel,
    *,
    chart: str = DEFAULT_CHART,
    method: str = "auto",
    spectrum: ArrayLike | None = None,
) -> tuple[Environment, SynthesizedTarget]:
    """An environment with a synthesized target chart, w_avg and the ``synthesized`` record.

    A ``black_level`` of an environment of that name already in ``measurements`` is kept (it is
    measured on the stage, not in the location). On a stage of several panel types the
    environment gets no w_avg: each type's part of it comes from ``solve --hdri`` and the types'
    regions (docs/panels.md).
    """
    stage = measurements.stage
    reflectances = chart_spectra(chart)
    if len(reflectances) != measurements.n_patches:
        raise InputError(
            f"the chart {chart!r} has {len(reflectances)} patches, the measurements' lit_chart "
            f"{measurements.n_patches}",
            key="--chart",
        )
    w_avg = rgb_to_camera(light.rgb, light.colorspace, stage.camera_colorspace)
    if np.any(w_avg < 0):
        raise InputError(
            f"the light's {light.colorspace} RGB {np.round(light.rgb, 6).tolist()} is outside "
            f"the camera gamut {stage.camera_colorspace} (camera RGB "
            f"{np.round(w_avg, 6).tolist()}): no light the camera can see",
            key="--hdri-colorspace",
        )
    synth = synthesize_target(
        w_avg,
        camera,
        reflectances,
        white_patch=stage.white_patch,
        white_reflectance=stage.white_reflectance,
        method=method,
        spectrum=spectrum,
    )
    record = SynthesisRecord(
        source=light.kind,
        hdri=light.hdri,
        colorspace=light.colorspace,
        illuminant=synth.illuminant.label,
        cct=round(synth.illuminant.cct, 1),
        duv=round(synth.illuminant.duv, 5),
        camera=camera.description,
        chart=chart,
        assumptions=tuple(_assumptions(synth, light, camera, chart, stage)),
        warnings=tuple(_warnings(synth)),
    )
    previous = {e.name: e for e in measurements.environments}.get(name)
    panels = bool(measurements.panels)  # each type's share of w_avg comes from `solve --hdri`
    environment = Environment(
        name=name,
        target_chart=synth.target_chart,
        w_avg=None if panels else w_avg,
        black_level=None if previous is None else previous.black_level,
        panel_black_level=previous.panel_black_level if panels and previous else None,
        synthesized=record,
    )
    return environment, synth


def with_environment(measurements: Measurements, environment: Environment) -> Measurements:
    """``measurements`` with ``environment`` replacing the one of its name, or appended."""
    by_name = {e.name: e for e in measurements.environments}  # a replaced one keeps its place
    by_name[environment.name] = environment
    return dataclasses.replace(measurements, environments=tuple(by_name.values()))
