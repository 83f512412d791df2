"""ocio_vp: colour calibration of RGB LED virtual-production stages as OpenColorIO configs.

Implements LeGendre, Lepicovsky & Debevec, "Jointly Optimizing Color Rendition and In-Camera
Backgrounds in an RGB Virtual Production Stage", DigiPro 2022,
https://doi.org/10.1145/3543664.3543681.

The public names below are imported on first use (PEP 562), so ``import ocio_vp`` and every
``ocio-vp`` command load only what they use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_EXPORTS = {
    "black_level_offset": "ocio_vp.calibration",
    "form_factor_parallel_rectangle": "ocio_vp.calibration",
    "predict_lit_chart": "ocio_vp.calibration",
    "solve_M": "ocio_vp.calibration",
    "solve_N": "ocio_vp.calibration",
    "w_avg_from_white_patch": "ocio_vp.calibration",
    "Q_SOLVE_METHODS": "ocio_vp.correction",
    "QProblem": "ocio_vp.correction",
    "solve_post_correction": "ocio_vp.correction",
    "InputError": "ocio_vp.errors",
    "Measurements": "ocio_vp.formats",
    "Solution": "ocio_vp.formats",
    "load_measurements": "ocio_vp.formats",
    "load_solution": "ocio_vp.formats",
    "save_measurements": "ocio_vp.formats",
    "sample_chart": "ocio_vp.plates.sampling",
    "solve_environment": "ocio_vp.pipeline",
    "solve_measurements": "ocio_vp.pipeline",
}

__all__ = [
    "Q_SOLVE_METHODS",
    "InputError",
    "Measurements",
    "QProblem",
    "Solution",
    "black_level_offset",
    "form_factor_parallel_rectangle",
    "load_measurements",
    "load_solution",
    "predict_lit_chart",
    "sample_chart",
    "save_measurements",
    "solve_M",
    "solve_N",
    "solve_environment",
    "solve_measurements",
    "solve_post_correction",
    "w_avg_from_white_patch",
]

if TYPE_CHECKING:  # what type checkers and IDEs see; at run time, __getattr__ below
    from ocio_vp.calibration import (
        black_level_offset,
        form_factor_parallel_rectangle,
        predict_lit_chart,
        solve_M,
        solve_N,
        w_avg_from_white_patch,
    )
    from ocio_vp.correction import Q_SOLVE_METHODS, QProblem, solve_post_correction
    from ocio_vp.errors import InputError
    from ocio_vp.formats import (
        Measurements,
        Solution,
        load_measurements,
        load_solution,
        save_measurements,
    )
    from ocio_vp.pipeline import solve_environment, solve_measurements
    from ocio_vp.plates.sampling import sample_chart


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ocio_vp' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
