"""Panel linearity: the ``ramps`` section, the per-channel response fit and its inverse 1D LUT.

The paper assumes a linear LED volume (LeGendre et al. 2022, Section 3.2, "Panel and Camera
Linearity") and suggests verifying it with displayed ramps. Per LED channel, each step's
camera RGB is projected onto the primary's column of [SL], black-subtracted and normalised at
the top step; the noise is estimated from the ramp; a monotone (isotonic, then PCHIP) response
is fitted and inverted exactly. Each step, and when a channel counts as linear, is in
docs/linearity.md; :mod:`ocio_vp.wall.encoding` turns the inverse into the CLF sidecar.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ocio_vp.errors import InputError, format_key_path
from ocio_vp.formats.checker import CHANNELS, Key, Validator
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.linearity import (
    MEASURED_KEYS,
    ChannelBlack,
    ChannelNoise,
    Linearity,
    LinearityChannel,
    ShadowDeviation,
)
from ocio_vp.formats.records import floats

__all__ = [
    "CHANNELS",
    "DETECTION_SIGMAS",
    "LINEARITY_TOLERANCE",
    "MIN_STEPS",
    "QUANTIFICATION_SIGMAS",
    "REFUSAL_SIGMAS",
    "RELATIVE_TOLERANCE",
    "TOP_STEP_REFUSAL",
    "ChannelResponse",
    "Ramp",
    "channel_response",
    "estimate_noise",
    "fit_linearity",
    "inverse_response",
    "parse_ramps",
    "ramps_to_dict",
    "response_model",
]

#: A channel whose normalised response is within this of the identity (fraction of the top
#: step) at every knot, and within :data:`RELATIVE_TOLERANCE` of each level, is linear.
LINEARITY_TOLERANCE = 0.002
#: Relative deviation (of the level itself) that makes a channel corrected, where it exceeds
#: the noise: a wall 50% dark at 0.3% of peak is far from linear although only 0.15% of peak off.
RELATIVE_TOLERANCE = 0.01
#: Fewer steps cannot show the shape of a response curve.
MIN_STEPS = 4
#: A step whose black-subtracted level is below this many noise floors cannot be told from
#: black (the usual "limit of detection", 3 sigma of the blank): it is dropped from the knots.
DETECTION_SIGMAS = 3.0
#: Levels above this many noise floors can be quantified (the "limit of quantification"):
#: the worst relative deviation is reported among them.
QUANTIFICATION_SIGMAS = 10.0
#: A step lower than an earlier one by more than this many combined noise sigmas is not noise:
#: the ramp is refused.
REFUSAL_SIGMAS = 5.0
#: The top step and ``primaries`` are the same level; further apart than this (relative) they
#: are not the same capture and the ramp is refused. Beyond the noise, a warning.
TOP_STEP_REFUSAL = 0.5
#: Camera exposure repeatability between two captures: the smallest top-step mismatch warned of.
TOP_STEP_WARNING = 0.01
_NOISE_MIN = 1e-9  # a noiseless (simulated) ramp still gets a positive floor
_TRIM = 0.8  # the noise is refitted on this fraction of the residuals, the best-fitting ones
#: sigma of a standard normal kept within its central 80% (|z| < 1.2816): sqrt(1 - 2 z phi(z) / 0.8)
_TRIMMED_NORMAL = math.sqrt(
    1 - 2 * 1.2815516 * math.exp(-(1.2815516**2) / 2) / math.sqrt(2 * math.pi) / 0.8
)


@dataclass(frozen=True)
class Ramp:
    """One LED channel's ramp: ``drive`` (m,) values sent to the wall, ``camera`` (m, 3) RGB;
    the section's optional ``black`` frame (3,) and ``noise_floor`` (fraction of the top step)."""

    drive: np.ndarray
    camera: np.ndarray
    black: np.ndarray | None = None
    noise_floor: float | None = None


# --------------------------------------------------------------------------------------------
# The ``ramps`` section of the measurements file.


def _error(source: str | None, key: Key, problem: str) -> InputError:
    """A ramp that cannot be fitted (found after parsing), named under ``ramps``."""
    return InputError(problem, source=source, key=format_key_path("ramps", *key))


def _parse_ramp(
    ctx: Validator, raw: JsonValue, key: Key, black: np.ndarray | None, noise: float | None
) -> Ramp:
    ramp = ctx.mapping(raw, key, required=("drive", "camera"))
    drive_raw, camera_raw = ramp["drive"], ramp["camera"]
    if not isinstance(drive_raw, (list, tuple)):
        raise ctx.error((*key, "drive"), "expected a list of drive values")
    if not isinstance(camera_raw, (list, tuple)):
        raise ctx.error((*key, "camera"), "expected a list of [r, g, b]")
    if len(drive_raw) < MIN_STEPS:
        raise ctx.error(
            (*key, "drive"),
            f"has {len(drive_raw)} steps; at least {MIN_STEPS} are needed to fit a response",
        )
    if len(camera_raw) != len(drive_raw):
        raise ctx.error(
            (*key, "camera"),
            f"has {len(camera_raw)} entries but drive has {len(drive_raw)}; give one camera "
            "RGB per drive step",
        )
    drive = np.array([ctx.number(v, (*key, "drive", i)) for i, v in enumerate(drive_raw)])
    camera = np.stack([_rgb(ctx, rgb, (*key, "camera", i)) for i, rgb in enumerate(camera_raw)])
    for i in range(1, len(drive)):
        if drive[i] <= drive[i - 1]:
            raise ctx.error(
                (*key, "drive", i),
                f"drive values must increase strictly: {drive[i]:g} follows {drive[i - 1]:g}",
            )
    if drive[-1] != 1.0:
        raise ctx.error(
            (*key, "drive", len(drive) - 1),
            f"the top step must be drive 1.0 (the level of `primaries`), got {drive[-1]:g}",
        )
    if not np.any(camera[-1] > 0):
        raise ctx.error((*key, "camera", len(drive) - 1), "the top step is black (zero)")
    return Ramp(drive=drive, camera=camera, black=black, noise_floor=noise)


def _rgb(ctx: Validator, value: JsonValue, key: Key) -> np.ndarray:
    """Camera RGB: finite, may be negative (after the camera's black subtraction)."""
    return ctx.rgb(value, key, minimum=-math.inf, maximum=math.inf)


def parse_ramps(
    raw: JsonValue, *, source: str | None = None, key: Key = ("ramps",)
) -> dict[str, Ramp]:
    """Validate the ``ramps`` section of a measurements file (see ``docs/measurements.md``);
    ``key`` is where it is in the file.

    Camera values may be negative (a camera's black subtraction leaves the zero step slightly
    below 0); what is done with noise and dips is decided when the response is fitted.

    Raises
    ------
    InputError
        Naming ``ramps.<channel>.<key>[i]`` for unknown keys, fewer than :data:`MIN_STEPS`
        steps, lengths that disagree, non-finite values, negative drive, drive values that do
        not increase, a top step that is not drive 1.0 or is black, a bad ``black`` or
        ``noise_floor``.
    """
    ctx = Validator(source or "")
    section = ctx.mapping(raw, key, required=CHANNELS, optional=("black", "noise_floor"))
    black = section.get("black")
    black = None if black is None else _rgb(ctx, black, (*key, "black"))
    noise = section.get("noise_floor")
    if noise is not None:
        noise = ctx.number(noise, (*key, "noise_floor"))
        if not 0 < noise < 0.5:
            raise ctx.error(
                (*key, "noise_floor"),
                f"expected a fraction of the top step in (0, 0.5), got {noise:g}",
            )
    return {c: _parse_ramp(ctx, section[c], (*key, c), black, noise) for c in CHANNELS}


def ramps_to_dict(ramps: Mapping[str, Ramp]) -> JsonObject:
    """The inverse of :func:`parse_ramps` (plain Python types)."""
    data: JsonObject = {
        c: {
            "drive": floats(ramps[c].drive),
            "camera": floats(ramps[c].camera),
        }
        for c in CHANNELS
        if c in ramps
    }
    first = next(iter(ramps.values()), None)
    if first is not None and first.black is not None:
        data["black"] = floats(first.black)
    if first is not None and first.noise_floor is not None:
        data["noise_floor"] = float(first.noise_floor)
    return data


# --------------------------------------------------------------------------------------------
# Noise and the monotone fit.


def _pseudo_residuals(drive: np.ndarray, response: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each interior step against the quadratic through three neighbours (Gasser, Sroka &
    Jennen-Steinmetz 1986, one order up so a curved response adds little), scaled to the noise
    of one step: ``(r_i - sum w_j r_j) / sqrt(1 + sum w_j^2)``. Returns (levels, residuals)."""
    i = np.arange(1, len(drive) - 1)
    third = np.where(i + 2 < len(drive), i + 2, i - 2)
    others = np.stack([i - 1, i + 1, third], axis=1)  # (n, 3) neighbours of each step i
    d, x = drive[others], drive[i]
    w = np.stack(
        [
            np.prod([(x - d[:, k]) / (d[:, j] - d[:, k]) for k in range(3) if k != j], axis=0)
            for j in range(3)
        ],
        axis=1,
    )
    predicted = np.sum(w * response[others], axis=1)
    return response[i], (response[i] - predicted) / np.sqrt(1.0 + np.sum(w * w, axis=1))


def estimate_noise(drive: np.ndarray, response: np.ndarray) -> tuple[float, float]:
    """The ramp's noise, ``sigma(r) = sqrt(floor^2 + (relative * r)^2)`` in fractions of the
    top step, estimated from the step-to-step scatter (see :func:`_pseudo_residuals`).

    Maximum likelihood of the two parameters for Gaussian residuals, refitted twice on the
    80% of residuals that fit best and scaled by the trimmed normal's consistency factor, so
    that one bad step (which spoils up to four residuals) does not widen the noise that judges
    it.

    Examples
    --------
    >>> d = np.linspace(0, 1, 65)
    >>> noise = np.random.default_rng(0).normal(0, 0.001, 65)
    >>> floor, relative = estimate_noise(d, d + noise)
    >>> 0.0005 < floor < 0.002
    True
    """
    levels, residuals = _pseudo_residuals(
        np.asarray(drive, dtype=np.float64), np.asarray(response, dtype=np.float64)
    )
    levels = np.maximum(levels, 0.0)
    spread = 1.4826 * float(np.median(np.abs(residuals))) + _NOISE_MIN
    start = np.log([spread, spread / max(float(np.median(levels)), 1e-3)])
    bounds = [(math.log(_NOISE_MIN), math.log(0.5))] * 2
    keep = np.ones(len(residuals), dtype=bool)
    scale = 0.0
    from scipy.optimize import minimize  # deferred: see response_model

    for _ in range(3):
        start = minimize(
            _noise_nll,
            start,
            args=(levels[keep], residuals[keep]),
            jac=True,
            bounds=bounds,
            method="TNC",  # bounded, and an order faster here than L-BFGS-B
        ).x
        scale = 0.0 if keep.all() else math.log(_TRIMMED_NORMAL)
        z = np.abs(residuals) / np.sqrt(np.exp(2 * start[0]) + np.exp(2 * start[1]) * levels**2)
        keep = z <= np.quantile(z, _TRIM)
    return float(np.exp(start[0] - scale)), float(np.exp(start[1] - scale))


def _noise_nll(
    log_sigma: np.ndarray, levels: np.ndarray, residuals: np.ndarray
) -> tuple[float, np.ndarray]:
    """Twice the negative log-likelihood of the residuals, and its gradient."""
    floor2, relative2 = np.exp(2 * log_sigma[0]), np.exp(2 * log_sigma[1]) * levels**2
    variance = floor2 + relative2
    slope = 1 / variance - residuals**2 / variance**2
    gradient = np.array([np.sum(slope * 2 * floor2), np.sum(slope * 2 * relative2)])
    return float(np.sum(np.log(variance) + residuals**2 / variance)), gradient


def _check_falls(
    drive: np.ndarray, r: np.ndarray, sigma: np.ndarray, steps: np.ndarray, where: tuple
) -> None:
    """Refuse a ramp with a step lower than an earlier one by more than the noise:
    ``r_i - r_j > REFUSAL_SIGMAS (sigma_i + sigma_j)`` for some ``i < j``."""
    high = np.maximum.accumulate(r - REFUSAL_SIGMAS * sigma)
    falls = np.nonzero(r[1:] + REFUSAL_SIGMAS * sigma[1:] < high[:-1])[0]
    if len(falls) == 0:
        return
    j = int(falls[0]) + 1
    i = int(np.argmax(r[:j] - REFUSAL_SIGMAS * sigma[:j]))
    source, name = where
    raise _error(
        source,
        (name, "camera", int(steps[j])),
        f"response not monotone: step {steps[j]} (drive {drive[j]:g}) reads "
        f"{100 * r[j]:.4g}% of the top step, {100 * (r[i] - r[j]):.3g}% below "
        f"{_step_name(steps[i])} (drive {drive[i]:g}, {100 * r[i]:.4g}%): more than "
        f"{REFUSAL_SIGMAS:g} noise sigmas ({100 * sigma[j]:.2g}% there), so not noise; "
        "check that step's capture",
    )


def _step_name(step: int) -> str:
    return "the assumed black" if step < 0 else f"step {step}"


def _monotone_knots(
    drive: np.ndarray, r: np.ndarray, sigma: np.ndarray, limit: float
) -> tuple[np.ndarray, np.ndarray, dict[str, list]]:
    """Weighted isotonic regression of the interior steps (black fixed at 0, top at 1).

    Each block the regression pools becomes one knot at its weighted mean drive, so the knots
    increase strictly; blocks below ``limit`` (the detection limit) or reaching the top are
    dropped. Returns knot drive, knot response and the indices (into ``r``) of the ``merged``
    blocks (more than one step), the steps ``below`` the limit and those ``at_top``.
    """
    from scipy.optimize import isotonic_regression  # deferred: see response_model

    weights = 1.0 / sigma[1:-1] ** 2
    fit = isotonic_regression(r[1:-1], weights=weights, increasing=True)
    knots_d, knots_r = [0.0], [0.0]
    groups: dict[str, list] = {"merged": [], "below": [], "at_top": []}
    for start, stop in zip(fit.blocks[:-1], fit.blocks[1:], strict=True):
        idx = np.arange(start, stop) + 1
        value = float(fit.x[start])
        if len(idx) > 1:
            groups["merged"].append(idx.tolist())
        if value < limit:
            groups["below"].extend(idx.tolist())
        elif value >= 1.0:
            groups["at_top"].extend(idx.tolist())
        else:
            knots_d.append(float(np.average(drive[idx], weights=weights[idx - 1])))
            knots_r.append(value)
    knots_d.append(1.0)
    knots_r.append(1.0)
    return np.array(knots_d), np.array(knots_r), groups


# --------------------------------------------------------------------------------------------
# The response and its inverse.


@dataclass(frozen=True)
class ChannelResponse:
    """One LED channel's fitted response (see :func:`channel_response`).

    ``drive``/``response`` are the knots of the monotone model (from (0, 0) to (1, 1));
    ``measured`` the black-subtracted, normalised response at every ramp step; ``black`` and
    ``noise`` what was subtracted and estimated; ``below_floor``, ``merged`` and ``at_top`` the
    ramp steps (their index in ``ramps.<channel>``) the knots leave out or pool.
    """

    drive: np.ndarray
    response: np.ndarray
    measured: np.ndarray
    black: ChannelBlack
    noise: ChannelNoise
    projection_residual: float
    below_floor: list[int] = field(default_factory=list)
    merged: list[list[int]] = field(default_factory=list)
    at_top: list[int] = field(default_factory=list)


def _black(ramp: Ramp, camera_y: np.ndarray, s: np.ndarray) -> tuple[float, np.ndarray, str]:
    if ramp.drive[0] == 0.0:
        return float(camera_y[0]), ramp.camera[0], "zero step"
    if ramp.black is not None:
        return float(ramp.black @ s / (s @ s)), ramp.black, "black frame"
    return 0.0, np.zeros(3), "assumed 0 (no zero step, no black frame)"


def channel_response(
    ramp: Ramp,
    SL: np.ndarray,
    channel: int,
    *,
    source: str | None = None,
) -> ChannelResponse:
    """Normalised panel response of one LED channel from its ramp, as a camera delivers it:
    projected onto column ``channel`` of [SL], black-subtracted, normalised at the top step,
    its noise estimated (:func:`estimate_noise`) unless ``noise_floor`` is given, dips within
    the noise pooled and steps below :data:`DETECTION_SIGMAS` noise floors dropped from the
    knots (docs/linearity.md, "From ramp to response").

    ``projection_residual`` is the largest part of a step's (black-subtracted) camera RGB that
    is *not* along the primary's column, relative to the top step.

    Raises
    ------
    InputError
        When the top step is not brighter than the black, or the response falls by more than
        :data:`REFUSAL_SIGMAS` noise sigmas (naming the step).
    """
    s = np.asarray(SL, dtype=np.float64)[:, channel]
    name = CHANNELS[channel]
    y = ramp.camera @ s / (s @ s)
    y0, black, black_source = _black(ramp, y, s)
    drive, camera, steps = ramp.drive, ramp.camera, np.arange(len(ramp.drive))
    if drive[0] != 0.0:
        drive, y, steps = np.r_[0.0, drive], np.r_[y0, y], np.r_[-1, steps]
        camera = np.vstack([black, camera])
    top = y[-1] - y0
    if not top > 0:
        raise _error(
            source,
            (name, "camera", len(ramp.drive) - 1),
            f"zero top step: its projection on primaries.{name} ({y[-1]:.6g}) is not above "
            f"the black's ({y0:.6g}, {black_source})",
        )
    r = (y - y0) / top
    floor, relative = estimate_noise(drive, r)
    if ramp.noise_floor is not None:
        floor = ramp.noise_floor
    sigma = np.hypot(floor, relative * np.maximum(r, 0.0))
    _check_falls(drive, r, sigma, steps, (source, name))
    knot_d, knot_r, groups = _monotone_knots(drive, r, sigma, DETECTION_SIGMAS * floor)
    excess = (camera - black) - np.outer(y - y0, s)
    return ChannelResponse(
        drive=knot_d,
        response=knot_r,
        measured=r[steps >= 0],
        black=ChannelBlack(
            source=black_source,
            camera=np.asarray(black, dtype=np.float64).copy(),
            level=float(y0 / top),
        ),
        noise=ChannelNoise(
            floor=float(floor),
            relative=float(relative),
            source="given" if ramp.noise_floor is not None else "estimated from the ramp",
            detection_limit=float(DETECTION_SIGMAS * floor),
        ),
        projection_residual=float(np.max(np.linalg.norm(excess, axis=1)) / np.linalg.norm(top * s)),
        below_floor=[int(steps[i]) for i in groups["below"]],
        merged=[[int(steps[i]) for i in block] for block in groups["merged"]],
        at_top=[int(steps[i]) for i in groups["at_top"]],
    )


def response_model(drive: np.ndarray, response: np.ndarray):
    """The monotone interpolant ``r(d)`` of the response knots (``scipy`` PCHIP).

    PCHIP (Fritsch & Carlson 1980) preserves the monotonicity of the data, so its inverse
    exists; a fitted polynomial could wiggle and fold back.
    """
    # scipy is imported here: every `ocio-vp` command imports this module (through the
    # measurements reader) while few of them fit a response.
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


# --------------------------------------------------------------------------------------------
# The ``linearity`` block of solution.json.


def _deviations(
    fit: ChannelResponse, tolerance: float
) -> tuple[float, ShadowDeviation | None, bool]:
    """Absolute and relative deviation from linear at the knots, and whether to correct."""
    d, r = fit.drive[1:-1], fit.response[1:-1]
    absolute = float(np.max(np.abs(fit.response - fit.drive)))
    if len(d) == 0:
        return absolute, None, absolute > tolerance
    relative = r / d - 1.0
    sigma = np.hypot(fit.noise.floor, fit.noise.relative * r)
    # deviations within the noise say nothing about the wall; the worst is reported where a
    # level can be quantified, chosen by its lower bound (docs/linearity.md)
    significant = np.abs(r - d) > DETECTION_SIGMAS * sigma
    quantified = significant & (r >= QUANTIFICATION_SIGMAS * fit.noise.floor)
    uncertainty = np.hypot(sigma, fit.noise.floor) / d
    shadow = None
    if np.any(quantified):
        bound = np.abs(relative) - 2 * uncertainty
        i = int(np.argmax(np.where(quantified, bound, -np.inf)))
        shadow = ShadowDeviation(
            relative=float(relative[i]), uncertainty=float(uncertainty[i]), drive=float(d[i])
        )
    corrected = bool(
        absolute > tolerance or np.any(significant & (np.abs(relative) > RELATIVE_TOLERANCE))
    )
    return absolute, shadow, corrected


def _top_step(
    ramp: Ramp, fit: ChannelResponse, SL: np.ndarray, k: int, source: str | None
) -> tuple[float, str | None]:
    """How far the ramp's top step is from ``primaries``: refused beyond
    :data:`TOP_STEP_REFUSAL`, a warning beyond the noise (and camera repeatability)."""
    black = fit.black.camera
    primary = SL[:, k]
    mismatch = float(np.linalg.norm(ramp.camera[-1] - black - primary) / np.linalg.norm(primary))
    name = CHANNELS[k]
    if mismatch > TOP_STEP_REFUSAL:
        raise _error(
            source,
            (name, "camera", len(ramp.drive) - 1),
            f"the top step (black subtracted) differs from primaries.{name} by "
            f"{100 * mismatch:.3g}% (more than {100 * TOP_STEP_REFUSAL:g}%): the ramp and the "
            "primaries must be shot at the same level and exposure",
        )
    noise = 3.0 * math.hypot(fit.noise.floor, fit.noise.relative)
    if mismatch <= max(noise, TOP_STEP_WARNING):
        return mismatch, None
    return mismatch, (
        f"ramps.{name}: the top step differs from primaries.{name} by {100 * mismatch:.3g}% "
        f"(noise {100 * noise:.2g}%, repeatability {100 * TOP_STEP_WARNING:g}%): ramps and "
        "primaries were not shot at the same level; the response is normalised at the top step"
    )


def _steps_text(steps: list[int], drive: np.ndarray) -> str:
    listed = ", ".join(map(str, steps[:8])) + (", ..." if len(steps) > 8 else "")
    return f"step{'s' if len(steps) > 1 else ''} {listed} (drive <= {drive[max(steps)]:.3g})"


def _channel_notes(name: str, ramp: Ramp, fit: ChannelResponse) -> list[str]:
    """What was done to the ramp, in words (terminal and ``solution.json``)."""
    black, noise = fit.black, fit.noise
    rgb = ", ".join(f"{v + 0.0:.4g}" for v in black.camera)  # + 0.0: no "-0"
    notes = [
        f"{name}: black ({black.source}) camera [{rgb}] = {100 * black.level:.3g}% of "
        f"the top step, subtracted; noise {100 * noise.floor:.2g}% of the top step + "
        f"{100 * noise.relative:.2g}% of the level ({noise.source})"
    ]
    if fit.below_floor:
        notes.append(
            f"{name}: {_steps_text(fit.below_floor, ramp.drive)} below the detection limit "
            f"({100 * noise.detection_limit:.2g}% of the top step): dropped from the fit"
        )
    for block in fit.merged:
        if not set(block) & set(fit.below_floor + fit.at_top):
            notes.append(
                f"{name}: steps {block[0]}-{block[-1]} dip within the noise: merged into one "
                "knot by the monotone (isotonic) fit"
            )
    if fit.at_top:
        notes.append(
            f"{name}: {_steps_text(fit.at_top, ramp.drive)} read at the top step's level "
            "within the noise: merged with it"
        )
    return notes


def _summary(channels: Mapping[str, LinearityChannel], tolerance: float) -> str:
    corrected = [c for c in CHANNELS if channels[c].corrected]
    worst = max(channels[c].max_deviation for c in CHANNELS)

    def shadow(c: str) -> str:
        dev = channels[c].shadow_deviation
        if dev is None:
            return f"{c} within the noise"
        word = "dark" if dev.relative < 0 else "bright"
        return (
            f"{c} {100 * abs(dev.relative):.3g}% (+-{100 * dev.uncertainty:.2g}%) {word} "
            f"at {100 * dev.drive:.3g}% of peak"
        )

    if corrected:
        verb = "deviates" if len(corrected) == 1 else "deviate"
        return (
            f"{', '.join(corrected)} {verb} from linear; worst relative to the level: "
            f"{'; '.join(shadow(c) for c in corrected)} (largest absolute deviation "
            f"{100 * worst:.3g}% of the top step): corrected by a per-channel 1D LUT"
        )
    return (
        f"every channel is linear within {100 * tolerance:.3g}% of the top step and "
        f"{100 * RELATIVE_TOLERANCE:.3g}% of the level above the noise (largest deviation "
        f"{100 * worst:.3g}%; {'; '.join(shadow(c) for c in CHANNELS)}): no LUT"
    )


def fit_linearity(
    ramps: Mapping[str, Ramp],
    SL: np.ndarray,
    *,
    tolerance: float = LINEARITY_TOLERANCE,
    source: str | None = None,
) -> Linearity:
    """The ``linearity`` block of ``solution.json`` from the measured ramps (its fields:
    docs/linearity.md); ``notes`` and ``warnings`` say it in words, for the terminal.

    The pre-correction LUT is built from the knots when the config is written
    (:func:`ocio_vp.ocio.wall.wall_outputs`); ``corrected`` false everywhere means no LUT.
    """
    SL = np.asarray(SL, dtype=np.float64)
    channels: dict[str, LinearityChannel] = {}
    notes: list[str] = []
    warnings: list[str] = []
    for k, name in enumerate(CHANNELS):
        ramp = ramps[name]
        fit = channel_response(ramp, SL, k, source=source)
        top_vs_primary, warning = _top_step(ramp, fit, SL, k, source)
        warnings += [warning] if warning else []
        notes += _channel_notes(name, ramp, fit)
        max_deviation, shadow, corrected = _deviations(fit, tolerance)
        channels[name] = LinearityChannel(
            drive=fit.drive,
            response=fit.response,
            measured_response=fit.measured,
            max_deviation=max_deviation,
            shadow_deviation=shadow,
            corrected=corrected,
            black=fit.black,
            noise=fit.noise,
            below_floor=fit.below_floor,
            merged=fit.merged,
            at_top=fit.at_top,
            projection_residual=fit.projection_residual,
            top_step_vs_primary=top_vs_primary,
        )
    return Linearity(
        measured=True,
        model="isotonic-pchip-inverse-1d-lut"
        if any(c.corrected for c in channels.values())
        else "linear",
        summary=_summary(channels, tolerance),
        notes=notes,
        warnings=warnings,
        tolerance=tolerance,
        relative_tolerance=RELATIVE_TOLERANCE,
        max_deviation=max(channels[c].max_deviation for c in CHANNELS),
        projection="least squares of each step's camera RGB onto the primary's column of [SL]",
        channels=channels,
        lut=None,
        present=MEASURED_KEYS,
    )
