"""The LED wall's signal: panel-linearity responses from grey ramps, the inverse LUT's table and
the signal encodings (linear, gamma 2.4, PQ), in numpy.
"""

from ocio_vp.wall.encoding import (
    DEFAULT_PEAK_NITS,
    LINEAR_HEADROOM,
    LUT_SIZE,
    WALL_ENCODINGS,
    apply_lut,
    check_encoding,
    encode,
    lut_accuracy,
    lut_domain_max,
    lut_table,
    with_wall_encoding,
)
from ocio_vp.wall.linearity import (
    CHANNELS,
    LINEARITY_TOLERANCE,
    MIN_STEPS,
    Ramp,
    channel_response,
    fit_linearity,
    inverse_response,
    parse_ramps,
    ramps_to_dict,
    response_model,
)

__all__ = [
    "CHANNELS",
    "DEFAULT_PEAK_NITS",
    "LINEARITY_TOLERANCE",
    "LINEAR_HEADROOM",
    "LUT_SIZE",
    "MIN_STEPS",
    "WALL_ENCODINGS",
    "Ramp",
    "apply_lut",
    "channel_response",
    "check_encoding",
    "encode",
    "fit_linearity",
    "inverse_response",
    "lut_accuracy",
    "lut_domain_max",
    "lut_table",
    "parse_ramps",
    "ramps_to_dict",
    "response_model",
    "with_wall_encoding",
]
