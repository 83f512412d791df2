"""The post-correction model every host carries: a typed, serialisable object with ``apply`` and
``inverse`` (:mod:`ocio_vp.model.correction`), and the root-polynomial expansion it builds on
(:mod:`ocio_vp.model.expansion`). numpy only: the solution file, ``ocio-vp apply`` and every
export read it without the solvers (which live in :mod:`ocio_vp.correction`)."""

from ocio_vp.model.correction import (
    DEFAULT_BRIGHT,
    DEFAULT_DARK,
    DEFAULT_FADE,
    DEFAULT_NEGATIVE,
    DRIVE_FLOOR,
    HULL_MIN_RADIUS,
    MAX_CONDITION_INVERSE,
    PROTECTION,
    FitDomain,
    MatrixCorrection,
    PostCorrection,
    ProtectedCorrection,
    ProtectionPoint,
    RootPolynomialCorrection,
    correction_from_dict,
    correction_to_dict,
    fit_domain,
    matrix_invertible,
    newton_inverse,
    smoothstep,
    truncated_pseudo_inverse,
)
from ocio_vp.model.expansion import (
    ROOT_POLYNOMIAL_TERMS,
    apply_root_polynomial,
    root_polynomial_expansion,
    root_polynomial_jacobian,
    root_polynomial_term_powers,
    root_polynomial_terms,
)
from ocio_vp.model.pixels import PixelFunction, pixel_function

__all__ = [
    "DEFAULT_BRIGHT",
    "DEFAULT_DARK",
    "DEFAULT_FADE",
    "DEFAULT_NEGATIVE",
    "DRIVE_FLOOR",
    "HULL_MIN_RADIUS",
    "MAX_CONDITION_INVERSE",
    "PROTECTION",
    "ROOT_POLYNOMIAL_TERMS",
    "FitDomain",
    "MatrixCorrection",
    "PixelFunction",
    "PostCorrection",
    "ProtectedCorrection",
    "ProtectionPoint",
    "RootPolynomialCorrection",
    "apply_root_polynomial",
    "correction_from_dict",
    "correction_to_dict",
    "fit_domain",
    "matrix_invertible",
    "newton_inverse",
    "pixel_function",
    "root_polynomial_expansion",
    "root_polynomial_jacobian",
    "root_polynomial_term_powers",
    "root_polynomial_terms",
    "smoothstep",
    "truncated_pseudo_inverse",
]
