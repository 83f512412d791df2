"""OpenColorIO output: the config of one environment (as data, then built), the wall
colorspaces' LUT and encoding tail, and the all-or-nothing writer of ``OUT/<environment>/``.
"""

from ocio_vp.ocio.config import (
    DISPLAY,
    IN_FRUSTUM,
    OUT_OF_FRUSTUM,
    POST_CORRECTION,
    POST_CORRECTION_COLORSPACE,
    RAW,
    REFERENCE,
    build_config,
    config_data,
    matrix_transform,
    write_config,
)
from ocio_vp.ocio.description import ConfigData, build
from ocio_vp.ocio.wall import (
    WallOutputs,
    encoding_transforms,
    lut_transform,
    wall_outputs,
)
from ocio_vp.ocio.writer import (
    write_environment,
    write_solutions,
)

__all__ = [
    "DISPLAY",
    "IN_FRUSTUM",
    "OUT_OF_FRUSTUM",
    "POST_CORRECTION",
    "POST_CORRECTION_COLORSPACE",
    "RAW",
    "REFERENCE",
    "ConfigData",
    "WallOutputs",
    "build",
    "build_config",
    "config_data",
    "encoding_transforms",
    "lut_transform",
    "matrix_transform",
    "wall_outputs",
    "write_config",
    "write_environment",
    "write_solutions",
]
