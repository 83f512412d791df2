"""ocio_vp: colour calibration of RGB LED virtual-production stages as OpenColorIO configs.

Implements LeGendre, Lepicovsky & Debevec, "Jointly Optimizing Color Rendition and In-Camera
Backgrounds in an RGB Virtual Production Stage", DigiPro 2022,
https://doi.org/10.1145/3543664.3543699.
"""

from ocio_vp.calibrate import solve_environment, solve_measurements
from ocio_vp.errors import InputError
from ocio_vp.geometry import form_factor_parallel_rectangle, w_avg_from_white_patch
from ocio_vp.measurements import Measurements, load_measurements, save_measurements
from ocio_vp.qsolve import Q_SOLVE_METHODS, QProblem, solve_post_correction
from ocio_vp.solution import Solution, load_solution
from ocio_vp.solve import black_level_offset, predict_lit_chart, solve_M, solve_N

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
    "save_measurements",
    "solve_M",
    "solve_N",
    "solve_environment",
    "solve_measurements",
    "solve_post_correction",
    "w_avg_from_white_patch",
]
