"""Validation on the wall: a calibration's chart, played through its config and filmed, judged
against what it should read (``ocio-vp validate``)."""

from ocio_vp.validation.compare import (
    DEFAULT_THRESHOLD,
    GAMUT_TOLERANCE,
    PatchResult,
    ValidationResult,
    compare_take,
    in_frustum_light,
    post_correct,
)
from ocio_vp.validation.write import (
    VALIDATION_FORMAT,
    summary_lines,
    validation_document,
    write_validation,
)

__all__ = [
    "DEFAULT_THRESHOLD",
    "GAMUT_TOLERANCE",
    "VALIDATION_FORMAT",
    "PatchResult",
    "ValidationResult",
    "compare_take",
    "in_frustum_light",
    "post_correct",
    "summary_lines",
    "validation_document",
    "write_validation",
]
