"""The patterns a wall plays for calibration and validation: the sequence, its ``sequence.yaml``
and the frames (EXR, TIFF, DPX) written for a media server or Unreal."""

from ocio_vp.patterns.design import (
    DEFAULT_FPS,
    DEFAULT_HOLD,
    DEFAULT_SIZE,
    DEFAULT_STEPS,
    PatternOptions,
    calibration_sequence,
    flash_frames,
    quantise,
    ramp_drives,
)
from ocio_vp.patterns.sequence import (
    FILE_FORMATS,
    FORMAT,
    MEASURED_KINDS,
    PATCH_KINDS,
    VERSION,
    Patch,
    PatternSequence,
    Validation,
    load_sequence,
    sequence_from_dict,
    sequence_to_dict,
)

__all__ = [
    "DEFAULT_FPS",
    "DEFAULT_HOLD",
    "DEFAULT_SIZE",
    "DEFAULT_STEPS",
    "FILE_FORMATS",
    "FORMAT",
    "MEASURED_KINDS",
    "PATCH_KINDS",
    "VERSION",
    "Patch",
    "PatternOptions",
    "PatternSequence",
    "Validation",
    "calibration_sequence",
    "flash_frames",
    "load_sequence",
    "quantise",
    "ramp_drives",
    "sequence_from_dict",
    "sequence_to_dict",
]
