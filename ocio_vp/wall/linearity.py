"""Panel linearity: the ``ramps`` section, the per-channel response fit and its inverse 1D LUT.

The paper assumes a linear LED volume (LeGendre et al. 2022, Section 3.2, "Panel and Camera
Linearity") and suggests verifying it with displayed ramps and correcting it when needed. Here,
per LED channel k:

1. every ramp step's camera RGB ``C_i`` is projected onto that primary's column ``s_k`` of [SL]
   by least squares, ``y_i = s_k . C_i / (s_k . s_k)``, so the response is one scalar per step;
2. the zero-drive step (flare, wall black) is subtracted and the response normalised at the top
   step (drive 1.0, the level of ``primaries``): ``r_i = (y_i - y_0) / (y_top - y_0)``;
3. ``r(d)`` is interpolated monotonically (PCHIP, never a polynomial) and inverted exactly
   (bisection on the interpolant), giving the pre-correction ``d = r^-1(x)`` that makes the
   panel linear. :mod:`ocio_vp.wall.encoding` turns it into the CLF sidecar.

Only what a scene requires is modelled: a channel within :data:`LINEARITY_TOLERANCE` of linear
is left alone, and when every channel is, no LUT is written (``solution.json`` says so).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ocio_vp.errors import InputError, format_key_path

__all__ = [
    "CHANNELS",
    "LINEARITY_TOLERANCE",
    "MIN_STEPS",
    "Ramp",
    "channel_response",
    "fit_linearity",
    "inverse_response",
    "parse_ramps",
    "ramps_to_dict",
    "response_model",
]

CHANNELS = ("red", "green", "blue")
#: A channel whose normalised response is within this of the identity (fraction of the top
#: step, at every ramp step) is treated as linear: 0.2% is below what a camera ramp resolves
#: reliably and below what the 3x3 solve itself can reach.
LINEARITY_TOLERANCE = 0.002
#: Fewer steps cannot show the shape of a response curve.
MIN_STEPS = 4
_RAMP_KEYS = ("drive", "camera")


@dataclass(frozen=True)
class Ramp:
    """One LED channel's ramp: ``drive`` (m,) values sent to the wall, ``camera`` (m, 3) RGB."""

    drive: np.ndarray
    camera: np.ndarray


# --------------------------------------------------------------------------------------------
# The ``ramps`` section of the measurements file.


def _error(source: str | None, key: tuple[str | int, ...], problem: str) -> InputError:
    return InputError(problem, source=source, key=format_key_path("ramps", *key))


def _number(value: Any, source: str | None, key: tuple[str | int, ...]) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _error(source, key, f"expected a number, got {type(value).__name__} {value!r}"[:80])
    number = float(value)
    if not math.isfinite(number):
        raise _error(source, key, f"expected a finite number, got {value!r}")
    if number < 0:
        raise _error(source, key, f"expected a number >= 0, got {value!r}")
    return number


def _parse_ramp(raw: Any, source: str | None, channel: str) -> Ramp:
    if not isinstance(raw, Mapping):
        raise _error(source, (channel,), "expected a mapping with 'drive' and 'camera'")
    for name in raw:
        if name not in _RAMP_KEYS:
            raise _error(source, (channel, str(name)), "unknown key; expected drive, camera")
    for name in _RAMP_KEYS:
        if name not in raw:
            raise _error(source, (channel,), f"missing required key {name!r}")
    drive_raw, camera_raw = raw["drive"], raw["camera"]
    if not isinstance(drive_raw, (list, tuple)):
        raise _error(source, (channel, "drive"), "expected a list of drive values")
    if not isinstance(camera_raw, (list, tuple)):
        raise _error(source, (channel, "camera"), "expected a list of [r, g, b]")
    if len(drive_raw) < MIN_STEPS:
        raise _error(
            source,
            (channel, "drive"),
            f"has {len(drive_raw)} steps; at least {MIN_STEPS} are needed to fit a response",
        )
    if len(camera_raw) != len(drive_raw):
        raise _error(
            source,
            (channel, "camera"),
            f"has {len(camera_raw)} entries but drive has {len(drive_raw)}; give one camera "
            "RGB per drive step",
        )
    drive = np.array([_number(v, source, (channel, "drive", i)) for i, v in enumerate(drive_raw)])
    rows = []
    for i, rgb in enumerate(camera_raw):
        if not isinstance(rgb, (list, tuple)) or len(rgb) != 3:
            raise _error(source, (channel, "camera", i), "expected [r, g, b]")
        rows.append([_number(v, source, (channel, "camera", i, j)) for j, v in enumerate(rgb)])
    camera = np.array(rows, dtype=np.float64)
    for i in range(1, len(drive)):
        if drive[i] <= drive[i - 1]:
            raise _error(
                source,
                (channel, "drive", i),
                f"drive values must increase strictly: {drive[i]:g} follows {drive[i - 1]:g}",
            )
    if drive[-1] != 1.0:
        raise _error(
            source,
            (channel, "drive", len(drive) - 1),
            f"the top step must be drive 1.0 (the level of `primaries`), got {drive[-1]:g}",
        )
    if not np.any(camera[-1] > 0):
        raise _error(source, (channel, "camera", len(drive) - 1), "the top step is black (zero)")
    return Ramp(drive=drive, camera=camera)


def parse_ramps(raw: Any, *, source: str | None = None) -> dict[str, Ramp]:
    """Validate the ``ramps`` section of a measurements file (see ``docs/measurements.md``).

    Raises
    ------
    InputError
        Naming ``ramps.<channel>.<key>[i]`` for unknown keys, fewer than :data:`MIN_STEPS`
        steps, lengths that disagree, non-finite or negative values, drive values that do not
        increase, a top step that is not drive 1.0 or is black.
    """
    if not isinstance(raw, Mapping):
        raise _error(source, (), "expected a mapping with red, green and blue ramps")
    for name in raw:
        if name not in CHANNELS:
            raise _error(source, (str(name),), "unknown key; expected red, green, blue")
    for name in CHANNELS:
        if name not in raw:
            raise _error(source, (), f"missing the {name!r} ramp (all three channels are needed)")
    return {c: _parse_ramp(raw[c], source, c) for c in CHANNELS}


def ramps_to_dict(ramps: Mapping[str, Ramp]) -> dict[str, Any]:
    """The inverse of :func:`parse_ramps` (plain Python types)."""
    return {
        c: {
            "drive": [float(v) for v in ramps[c].drive],
            "camera": [[float(v) for v in row] for row in ramps[c].camera],
        }
        for c in CHANNELS
        if c in ramps
    }


# --------------------------------------------------------------------------------------------
# The response and its inverse.


def channel_response(
    ramp: Ramp,
    SL: np.ndarray,
    channel: int,
    *,
    source: str | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Normalised panel response of one LED channel from its ramp.

    Each step's camera RGB is projected onto column ``channel`` of [SL] (paper eq. 1: the
    camera sees ``[SL] d`` for drive ``d``) by least squares; the zero-drive step is subtracted
    (or ``r(0) = 0`` is assumed when the ramp has none) and the result divided by the top step.

    Returns
    -------
    drive, response : ndarray (m,)
        Knots of the response, starting at drive 0 with response 0, ending at (1, 1).
    projection_residual : float
        Largest part of a step's (black-subtracted) camera RGB that is *not* along the
        primary's column, relative to the top step: a 1D LUT cannot fix a channel whose colour
        shifts along the ramp, and this says how much it does.

    Raises
    ------
    InputError
        When the projected response is not strictly increasing or the top step is not brighter
        than the zero step.
    """
    s = np.asarray(SL, dtype=np.float64)[:, channel]
    name = CHANNELS[channel]
    y = ramp.camera @ s / (s @ s)
    drive, camera = ramp.drive, ramp.camera
    if drive[0] == 0.0:
        y0, black = y[0], camera[0]
    else:
        y0, black = 0.0, np.zeros(3)
        drive, y, camera = np.r_[0.0, drive], np.r_[0.0, y], np.vstack([black, camera])
    top = y[-1] - y0
    offset = len(drive) - len(ramp.drive)
    if not top > 0:
        raise _error(
            source,
            (name, "camera", len(ramp.drive) - 1),
            f"zero top step: its projection on primaries.{name} ({y[-1]:.6g}) is not above "
            f"the zero step's ({y0:.6g})",
        )
    response = (y - y0) / top
    for i in range(1, len(response)):
        if response[i] <= response[i - 1]:
            raise _error(
                source,
                (name, "camera", i - offset),
                f"response not monotone: step {i - offset} (drive {drive[i]:g}) is "
                f"{response[i]:.6g} of the top step, not above the step before "
                f"({response[i - 1]:.6g})",
            )
    excess = (camera - black) - np.outer(y - y0, s)
    residual = float(np.max(np.linalg.norm(excess, axis=1)) / np.linalg.norm(top * s))
    return drive, response, residual


def response_model(drive: np.ndarray, response: np.ndarray):
    """The monotone interpolant ``r(d)`` of the response knots (``scipy`` PCHIP).

    PCHIP (Fritsch & Carlson 1980) preserves the monotonicity of the data, so its inverse
    exists; a fitted polynomial could wiggle and fold back.
    """
    from scipy.interpolate import PchipInterpolator

    return PchipInterpolator(
        np.asarray(drive, float), np.asarray(response, float), extrapolate=False
    )


def inverse_response(drive: np.ndarray, response: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The drive ``d`` with ``r(d) = x`` for the PCHIP response, for ``x`` in [0, 1].

    Exact inverse of :func:`response_model` (bisection to float64 resolution, not a second
    interpolation). Values outside [0, 1] are returned unchanged: above the top step the
    response is taken as linear (continuous at 1, since r(1) = 1), below zero the wall is black.

    Examples
    --------
    >>> d = np.linspace(0, 1, 5)
    >>> x = inverse_response(d, d**2, np.array([0.25, 1.0, 3.0]))
    >>> [round(float(v), 6) for v in x]
    [0.5, 1.0, 3.0]
    """
    model = response_model(drive, response)
    x = np.asarray(x, dtype=np.float64)
    inside = (x >= 0.0) & (x <= 1.0)
    target = np.clip(x, 0.0, 1.0)
    lo, hi = np.zeros_like(target), np.ones_like(target)
    for _ in range(60):  # 2^-60 < float64 resolution of [0, 1]
        mid = 0.5 * (lo + hi)
        below = model(mid) < target
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return np.where(inside, 0.5 * (lo + hi), x)


def fit_linearity(
    ramps: Mapping[str, Ramp],
    SL: np.ndarray,
    *,
    tolerance: float = LINEARITY_TOLERANCE,
    source: str | None = None,
) -> dict[str, Any]:
    """The ``linearity`` block of ``solution.json`` from the measured ramps.

    Per channel: the response knots, the largest deviation from linear over the ramp steps
    (``max |r_i - d_i|``, a fraction of the top step), whether it is corrected (deviation above
    ``tolerance``), the projection residual (see :func:`channel_response`) and how far the top
    step is from ``primaries`` (they should be the same capture level).

    The pre-correction LUT is built from the knots when the config is written
    (:func:`ocio_vp.ocio.wall.wall_outputs`); ``corrected`` false everywhere means no LUT.
    """
    SL = np.asarray(SL, dtype=np.float64)
    channels: dict[str, Any] = {}
    for k, name in enumerate(CHANNELS):
        ramp = ramps[name]
        drive, response, residual = channel_response(ramp, SL, k, source=source)
        deviation = float(np.max(np.abs(response - drive)))
        black = ramp.camera[0] if ramp.drive[0] == 0.0 else np.zeros(3)
        top_vs_primary = float(
            np.linalg.norm(ramp.camera[-1] - black - SL[:, k]) / np.linalg.norm(SL[:, k])
        )
        channels[name] = {
            "drive": drive.tolist(),
            "response": response.tolist(),
            "max_deviation": deviation,
            "corrected": deviation > tolerance,
            "projection_residual": residual,
            "top_step_vs_primary": top_vs_primary,
        }
    corrected = [c for c in CHANNELS if channels[c]["corrected"]]
    worst = max(channels[c]["max_deviation"] for c in CHANNELS)
    if corrected:
        verb = "deviates" if len(corrected) == 1 else "deviate"
        summary = (
            f"{', '.join(corrected)} {verb} from linear by up to {100 * worst:.3g}% of the "
            f"top step (tolerance {100 * tolerance:.3g}%): corrected by a per-channel 1D LUT"
        )
    else:
        summary = (
            f"every channel is linear within {100 * tolerance:.3g}% (largest deviation "
            f"{100 * worst:.3g}%): no LUT"
        )
    return {
        "measured": True,
        "model": "pchip-inverse-1d-lut" if corrected else "linear",
        "summary": summary,
        "tolerance": tolerance,
        "max_deviation": worst,
        "projection": "least squares of each step's camera RGB onto the primary's column of [SL]",
        "channels": channels,
        "lut": None,
    }
