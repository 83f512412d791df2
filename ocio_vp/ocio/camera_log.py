"""Cameras' log encodings as OCIO ``LogCameraTransform`` s (``Stage Footage (LogC4)`` and alike).

Each curve is the vendor's published one in OCIO's camera-log terms, named by colour-science's
decoding names (``colour.LOG_DECODINGS``) with its default arguments.

References
----------
ARRI (2022). ARRI LogC4 Specification. ARRI (2017). ALEXA Log C Curve (EI 800, SUP 3.x).
Sony (2014). Technical Summary for S-Gamut3.Cine/S-Log3 and S-Gamut3/S-Log3.
RED (2021). White paper on REDWideGamutRGB and Log3G10 (v3: offset 0.01).
Panasonic (2014). V-Log/V-Gamut Reference manual.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import PyOpenColorIO as OCIO

__all__ = [
    "CAMERA_LOG_CURVES",
    "LOG_FOR_GAMUT",
    "LogCurve",
    "camera_log_for",
    "log_transform",
]


@dataclass(frozen=True)
class LogCurve:
    """One camera log curve in OCIO ``LogCameraTransform`` terms (linear -> log forward)."""

    name: str  # colour-science's decoding name
    short: str  # as the colour space names show it: "Stage Footage (LogC4)"
    base: float
    log_side_slope: float
    log_side_offset: float
    lin_side_slope: float
    lin_side_offset: float
    lin_side_break: float
    linear_slope: float


def _logc4() -> LogCurve:
    a = (2.0**18 - 16.0) / 117.45
    b = (1023.0 - 95.0) / 1023.0
    c = 95.0 / 1023.0
    s = (7.0 * math.log(2.0) * 2.0 ** (7.0 - 14.0 * c / b)) / (a * b)
    t = (2.0 ** (14.0 * (-c / b) + 6.0) - 64.0) / a
    return LogCurve("ARRI LogC4", "LogC4", 2.0, b / 14.0, c - 6.0 * b / 14.0, a, 64.0, t, 1.0 / s)


def _logc3() -> LogCurve:
    # EI 800, SUP 3.x, linear scene exposure factor: colour-science's defaults.
    cut, a, b, c, d, e = 0.010591, 5.555556, 0.052272, 0.247190, 0.385537, 5.367655
    return LogCurve("ARRI LogC3", "LogC3", 10.0, c, d, a, b, cut, e)


def _slog3() -> LogCurve:
    # (420 + 261.5 log10((x + 0.01) / 0.19)) / 1023 above 0.01125; its straight line below.
    slope = (171.2102946929 - 95.0) / 0.01125 / 1023.0
    offset = (420.0 - 261.5 * math.log10(0.19)) / 1023.0
    return LogCurve("S-Log3", "S-Log3", 10.0, 261.5 / 1023.0, offset, 1.0, 0.01, 0.01125, slope)


def _log3g10() -> LogCurve:
    # v3: 0.224282 log10(155.975327 (x + 0.01) + 1) above -0.01; slope 15.1927 below.
    b = 155.975327
    return LogCurve("Log3G10", "Log3G10", 10.0, 0.224282, 0.0, b, 0.01 * b + 1.0, -0.01, 15.1927)


def _vlog() -> LogCurve:
    return LogCurve("V-Log", "V-Log", 10.0, 0.241514, 0.598206, 1.0, 0.00873, 0.01, 5.6)


#: The camera log curves the configs carry, by colour-science's decoding name.
CAMERA_LOG_CURVES: dict[str, LogCurve] = {
    curve.name: curve for curve in (_logc4(), _logc3(), _slog3(), _log3g10(), _vlog())
}

#: The log encoding a camera records in each camera gamut (colour.RGB_COLOURSPACES names).
LOG_FOR_GAMUT: dict[str, str] = {
    "ARRI Wide Gamut 4": "ARRI LogC4",
    "ARRI Wide Gamut 3": "ARRI LogC3",
    "S-Gamut3": "S-Log3",
    "S-Gamut3.Cine": "S-Log3",
    "Venice S-Gamut3": "S-Log3",
    "Venice S-Gamut3.Cine": "S-Log3",
    "REDWideGamutRGB": "Log3G10",
    "V-Gamut": "V-Log",
}


def camera_log_for(camera_colorspace: str | None) -> LogCurve | None:
    """The log curve footage in ``camera_colorspace`` is recorded in (None when unknown)."""
    name = LOG_FOR_GAMUT.get(camera_colorspace or "")
    return None if name is None else CAMERA_LOG_CURVES[name]


def log_transform(
    curve: LogCurve, direction: OCIO.TransformDirection = OCIO.TRANSFORM_DIR_FORWARD
) -> OCIO.LogCameraTransform:
    """``curve`` as OCIO's LogCameraTransform: forward encodes (linear -> log)."""
    transform = OCIO.LogCameraTransform(
        linSideBreak=[curve.lin_side_break] * 3,
        base=curve.base,
        logSideSlope=[curve.log_side_slope] * 3,
        logSideOffset=[curve.log_side_offset] * 3,
        linSideSlope=[curve.lin_side_slope] * 3,
        linSideOffset=[curve.lin_side_offset] * 3,
        direction=direction,
    )
    transform.setLinearSlopeValue([curve.linear_slope] * 3)
    return transform
