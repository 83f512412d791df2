"""Synthesized target charts for CG environments: the chart a camera would record under an
HDRI's light, computed from spectra instead of photographed (``ocio-vp target-chart``).

- :mod:`~ocio_vp.synthesis.camera`: the camera as spectral sensitivities or a colour space;
- :mod:`~ocio_vp.synthesis.illuminant`: a plausible light spectrum from one RGB colour;
- :mod:`~ocio_vp.synthesis.chart`: the chart's reflectances, scaled to the file's white;
- :mod:`~ocio_vp.synthesis.target`: the chart, the environment and its ``synthesized`` record;
- :mod:`~ocio_vp.synthesis.evaluate`: how good the synthesized chart and its Q are, measured on
  the spectral simulator (held-out reflectances, measurement noise).
"""

from ocio_vp.synthesis.camera import (
    CameraModel,
    camera_from_colourspace,
    camera_from_csv,
    camera_from_dataset,
    camera_from_matrix,
    cie_cmfs,
)
from ocio_vp.synthesis.chart import DEFAULT_CHART, ScaledChart, chart_spectra, scaled_to_white
from ocio_vp.synthesis.illuminant import (
    ILLUMINANT_METHODS,
    NATURAL_CCT,
    NATURAL_DUV,
    IlluminantEstimate,
    cct_duv,
    estimate_illuminant,
    given_illuminant,
    match_colour,
)
from ocio_vp.synthesis.target import (
    CAMERA_SPACE,
    LightSource,
    SynthesizedTarget,
    rgb_to_camera,
    synthesize_environment,
    synthesize_target,
    with_environment,
)

__all__ = [
    "CAMERA_SPACE",
    "DEFAULT_CHART",
    "ILLUMINANT_METHODS",
    "NATURAL_CCT",
    "NATURAL_DUV",
    "CameraModel",
    "IlluminantEstimate",
    "LightSource",
    "ScaledChart",
    "SynthesizedTarget",
    "camera_from_colourspace",
    "camera_from_csv",
    "camera_from_dataset",
    "camera_from_matrix",
    "cct_duv",
    "chart_spectra",
    "cie_cmfs",
    "estimate_illuminant",
    "given_illuminant",
    "match_colour",
    "rgb_to_camera",
    "scaled_to_white",
    "synthesize_environment",
    "synthesize_target",
    "with_environment",
]
