"""OpenColorIO output: the config of one environment (as data, then built), the wall
colorspaces' LUT and encoding tail, and the all-or-nothing writer of ``OUT/<environment>/``.

The names below are imported on first use (PEP 562): a module of this package imported alone
(``ocio_vp.ocio.clf``, ``ocio_vp.ocio.bake``, as the exports do) loads what it needs, not the
config builder and the writer with it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ocio_vp.deprecation import published_on_first_use

#: Working spaces a config gets when the stage names its camera gamut (colour's name: the
#: config's); here, so that exports read them without loading the config builder.
WORKING_SPACE_NAMES = {
    "ACES2065-1": "ACES2065-1",
    "ACEScg": "ACEScg",
    "ITU-R BT.709": "Linear Rec.709 (sRGB)",
}

#: Public name -> the module of this package that defines it.
_EXPORTS = {
    "DISPLAY": "ocio_vp.ocio.config",
    "IN_FRUSTUM": "ocio_vp.ocio.config",
    "OUT_OF_FRUSTUM": "ocio_vp.ocio.config",
    "POST_CORRECTION": "ocio_vp.ocio.config",
    "POST_CORRECTION_COLORSPACE": "ocio_vp.ocio.config",
    "RAW": "ocio_vp.ocio.config",
    "REFERENCE": "ocio_vp.ocio.config",
    "build_config": "ocio_vp.ocio.config",
    "config_data": "ocio_vp.ocio.config",
    "matrix_transform": "ocio_vp.ocio.config",
    "write_config": "ocio_vp.ocio.config",
    "ConfigData": "ocio_vp.ocio.description",
    "build": "ocio_vp.ocio.description",
    "WallOutputs": "ocio_vp.ocio.wall",
    "encoding_transforms": "ocio_vp.ocio.wall",
    "lut_transform": "ocio_vp.ocio.wall",
    "wall_outputs": "ocio_vp.ocio.wall",
    "write_environment": "ocio_vp.ocio.writer",
    "write_solutions": "ocio_vp.ocio.writer",
}

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

if TYPE_CHECKING:  # what type checkers and IDEs see; at run time, __getattr__ below
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


__getattr__, __dir__ = published_on_first_use(__name__, _EXPORTS)
