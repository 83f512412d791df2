"""ocio_vp: colour calibration of RGB LED virtual-production stages as OpenColorIO configs.

Implements LeGendre, Lepicovsky & Debevec, "Jointly Optimizing Color Rendition and In-Camera
Backgrounds in an RGB Virtual Production Stage", DigiPro 2022,
https://doi.org/10.1145/3543664.3543699.
"""

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

__version__ = "0.1.0"

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


def __getattr__(name: str):
    # ``sample_chart`` needs OpenImageIO, which ``import ocio_vp`` (and ``ocio-vp --help``)
    # should not pay for: it is imported on first use (PEP 562).
    if name == "sample_chart":
        from ocio_vp.plates.sampling import sample_chart

        return sample_chart
    raise AttributeError(f"module 'ocio_vp' has no attribute {name!r}")
