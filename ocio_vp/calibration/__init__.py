"""The paper's equations: eq. 3's lit chart, M = [SL]^-1, N from eq. 7, the black-level
offset, the geometry of beta and w_avg, and the diagnostics of a solved environment.
"""

from ocio_vp.calibration.diagnostics import (
    black_level_bounce,
    clipped_drive_lit,
    clipped_patches,
    identity_check,
    in_frustum_drive_range,
    is_identity,
    offset_is_negligible,
    out_of_frustum_drive,
    residuals_per_patch,
    stability_diagnostics,
    summary_errors,
)
from ocio_vp.calibration.equations import (
    BLACK_LEVEL_METHODS,
    MAX_CONDITION_Q_FOR_N,
    MAX_CONDITION_SL,
    black_level_offset,
    condition_number,
    in_frustum_drive,
    predict_displayed_chart,
    predict_lit_chart,
    solve_M,
    solve_N,
)
from ocio_vp.calibration.geometry import (
    environment_w_avg,
    form_factor_numerical,
    form_factor_parallel_rectangle,
    panel_beta,
    stage_beta,
    w_avg_from_white_patch,
)

__all__ = [
    "BLACK_LEVEL_METHODS",
    "MAX_CONDITION_Q_FOR_N",
    "MAX_CONDITION_SL",
    "black_level_bounce",
    "black_level_offset",
    "clipped_drive_lit",
    "clipped_patches",
    "condition_number",
    "environment_w_avg",
    "form_factor_numerical",
    "form_factor_parallel_rectangle",
    "identity_check",
    "in_frustum_drive",
    "in_frustum_drive_range",
    "is_identity",
    "offset_is_negligible",
    "out_of_frustum_drive",
    "panel_beta",
    "predict_displayed_chart",
    "predict_lit_chart",
    "residuals_per_patch",
    "solve_M",
    "solve_N",
    "stability_diagnostics",
    "stage_beta",
    "summary_errors",
    "w_avg_from_white_patch",
]
