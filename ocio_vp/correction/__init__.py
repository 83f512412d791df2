"""Post-correction Q: the problem dataclass, the registry of methods (``Q_SOLVE_METHODS``) and
the methods themselves (the linear family and ``auto``, ``perceptual``, ``joint``), plus their
leave-one-patch-out validation.
"""

from ocio_vp.correction.joint import (
    DEFAULT_MAX_CONDITION,
    DEFAULT_MAX_DELTA_E,
    joint_matrix,
    make_q_joint,
    q_joint,
    white_point_delta_e,
)
from ocio_vp.correction.linear import (
    AUTO_LADDER,
    AUTO_TOLERANCE_ABSOLUTE,
    AUTO_TOLERANCE_RELATIVE,
    BLEND_BAND,
    MODEL_KERNELS,
    RANK_RELATIVE_TOLERANCE,
    REGULARISATION_GRID,
    fit_least_squares,
    loo_cv_error,
    q_auto,
    q_diagonal,
    q_identity,
    q_regularised,
    q_white_preserving,
    soft_choice,
    target_rank,
)
from ocio_vp.correction.perceptual import (
    PERCEPTUAL_METRICS,
    default_camera_to_xyz,
    make_q_perceptual,
    mean_delta_e,
    q_perceptual,
)
from ocio_vp.correction.problem import (
    QFit,
    QProblem,
)
from ocio_vp.correction.registry import (
    Q_SOLVE_METHODS,
    q_least_squares,
    solve_post_correction,
)
from ocio_vp.correction.root_polynomial import (
    ROOT_POLYNOMIAL_TERMS,
    apply_root_polynomial,
    fit_root_polynomial,
    invert_root_polynomial,
    make_q_root_polynomial,
    post_correction,
    q_root_polynomial,
    root_polynomial_expansion,
)
from ocio_vp.correction.validation import (
    CLOSED_FORM_METHODS,
    cross_validated_error,
)

__all__ = [
    "AUTO_LADDER",
    "AUTO_TOLERANCE_ABSOLUTE",
    "AUTO_TOLERANCE_RELATIVE",
    "BLEND_BAND",
    "CLOSED_FORM_METHODS",
    "DEFAULT_MAX_CONDITION",
    "DEFAULT_MAX_DELTA_E",
    "MODEL_KERNELS",
    "PERCEPTUAL_METRICS",
    "Q_SOLVE_METHODS",
    "RANK_RELATIVE_TOLERANCE",
    "REGULARISATION_GRID",
    "ROOT_POLYNOMIAL_TERMS",
    "QFit",
    "QProblem",
    "apply_root_polynomial",
    "cross_validated_error",
    "default_camera_to_xyz",
    "fit_least_squares",
    "fit_root_polynomial",
    "invert_root_polynomial",
    "joint_matrix",
    "loo_cv_error",
    "make_q_joint",
    "make_q_perceptual",
    "make_q_root_polynomial",
    "mean_delta_e",
    "post_correction",
    "q_auto",
    "q_diagonal",
    "q_identity",
    "q_joint",
    "q_least_squares",
    "q_perceptual",
    "q_regularised",
    "q_root_polynomial",
    "q_white_preserving",
    "root_polynomial_expansion",
    "soft_choice",
    "solve_post_correction",
    "target_rank",
    "white_point_delta_e",
]
