"""``--priority skin``: the post-correction fitted with faces first.

The default (``auto``) already fits its root-polynomial candidate to the problem's skin samples
(:mod:`ocio_vp.correction.skin`) with a small weight and never takes a model that renders them
worse than least squares. With skin first the weight is :data:`PRIORITY_SKIN_WEIGHT`: the
bounded root-polynomial of degree 2 fitted to the chart and the skin samples, each skin sample
scaled by its luminance to the power -2/3 (CIE L* is about ``Y^(1/3)``: skin of every
lightness counts alike). Its fallback outside the chart's domain stays the chart's least
squares, so emitters, highlights and saturated colours are corrected as by the default. Where
the root-polynomial is not safe (it folds, flips or collapses a bright saturated input, or the
chart does not constrain its terms) a 3x3 is fitted to the same rows instead. The chart's
error is bounded (:data:`CHART_BUDGET` times least squares'); a target chart of rank below 3
(monochromatic light) has no colour to put first and is solved as the default solves it.

Faces first must not cost the rest of the frame: the in-frustum background's expected error
(:func:`~ocio_vp.correction.skin_figures.background_error`) and the wall's LEDs in frame
(:func:`~ocio_vp.correction.extrapolation.in_frame_led_damage`) through the skin fit may be no
worse than through the default's post-correction on the same problem. Where either is, the fit
is drawn towards the default (``(1 - a) default + a skin`` for a in :data:`BLEND_STEPS`; the
outputs mix, so the blend stays a model of the same kind) until both hold; at ``a = 0`` it is
the default itself.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ocio_vp.correction.auto import bounded_candidate, q_auto
from ocio_vp.correction.extrapolation import in_frame_led_damage
from ocio_vp.correction.linear import patch_errors, problem_arrays, target_rank
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.correction.skin import sample_camera_to_xyz, with_rows
from ocio_vp.correction.skin_figures import background_error
from ocio_vp.errors import InputError
from ocio_vp.model.correction import (
    FitDomain,
    MatrixCorrection,
    PostCorrection,
    RootPolynomialCorrection,
)

__all__ = ["BLEND_STEPS", "CHART_BUDGET", "PRIORITY_SKIN_WEIGHT", "q_skin_priority"]

#: Weight of the skin samples with skin first (relative to the chart's energy). Chosen on the
#: training skin (half fitted, half judged) and the tuning cameras at 0.2 % and 1 % noise:
#: 0.5 rendered that skin 0.65-0.77x least squares with general reflectances ~0.94x; 1.0 gained
#: at 0.2 % noise and lost it at 1 % (docs/skin.md).
PRIORITY_SKIN_WEIGHT = 0.5
#: The chart's mean ΔE2000 after the fit may be at most this times least squares'.
CHART_BUDGET = 1.15
#: Least squares' chart ΔE2000 below this is rounding: the stage reproduces the light exactly.
EXACT = 1e-6
#: Shares of the skin fit tried, largest first, where it is worse than the default on the
#: background or the LEDs in frame (0 is the default itself).
BLEND_STEPS = (0.75, 0.5, 0.25, 0.0)
#: "No worse" up to rounding: a figure may exceed the default's by this fraction of itself.
_ROUNDING = 1e-9


def _blend(skin: PostCorrection, default: PostCorrection, a: float) -> PostCorrection | None:
    """``(1 - a) default + a skin`` as one model of their kind: two matrices, two
    root-polynomials of one degree, fallback, domain and fade, or a root-polynomial and the
    matrix that is its fallback (its linear terms); None for any other pair."""
    if a == 1.0:
        return skin
    if a == 0.0:
        return default
    if isinstance(skin, MatrixCorrection) and isinstance(default, MatrixCorrection):
        return MatrixCorrection((1 - a) * default.Q + a * skin.Q)
    if not isinstance(skin, RootPolynomialCorrection):
        return None
    C = skin.coefficients
    if isinstance(default, MatrixCorrection):
        if not np.array_equal(default.Q, skin.fallback):
            return None
        D = np.zeros_like(C)
        D[:, :3] = default.Q  # the first three terms are r, g, b
    elif (
        isinstance(default, RootPolynomialCorrection)
        and default.coefficients.shape == C.shape
        and np.array_equal(default.fallback, skin.fallback)
        and default.fade == skin.fade
        and _same_domain(default.domain, skin.domain)
    ):
        D = default.coefficients
    else:
        return None
    return dataclasses.replace(skin, coefficients=(1 - a) * D + a * C)


def _same_domain(a: FitDomain | None, b: FitDomain | None) -> bool:
    return a is b or (a is not None and b is not None and a.to_dict() == b.to_dict())


def _figures(problem: QProblem, correction: PostCorrection) -> tuple[float, float]:
    """(background error, in-frame LED damage) of ``correction`` on ``problem``."""
    white = np.asarray(problem.target, dtype=np.float64)[problem.white_patch]
    damage = in_frame_led_damage(correction, problem.SL, white, sample_camera_to_xyz())
    return background_error(problem, correction), damage


def _no_worse(value: float, bound: float) -> bool:
    return not np.isfinite(bound) or value <= bound + _ROUNDING * abs(bound)


def within_default(problem: QProblem, fit: QFit) -> tuple[QFit, str, float]:
    """``fit`` drawn towards the default until its background and LED figures are no worse
    than the default's (module docstring): the fit, what was done in words, and the skin
    fit's share of it (1: the skin fit unchanged, 0: the default)."""
    default = q_auto(problem)
    bg_default, leds_default = _figures(problem, default.correction)
    bg, leds = bg_default, leds_default
    blended: PostCorrection = default.correction
    a = 0.0
    for a in (1.0, *BLEND_STEPS):
        mixed = _blend(fit.correction, default.correction, a)
        if mixed is None:
            continue
        blended = mixed
        bg, leds = _figures(problem, blended)
        if _no_worse(bg, bg_default) and _no_worse(leds, leds_default):
            break
    figures = (
        f"background {100 * bg:.3g} % of white (default {100 * bg_default:.3g} %), LEDs in "
        f"frame p95 ΔE2000 {leds:.3g} (default {leds_default:.3g})"
    )
    if a == 1.0:
        return fit, f"no worse than the default ({default.model}) elsewhere: {figures}", a
    if a == 0.0:
        note = f"the default ({default.model}) kept: the skin fit was worse than it elsewhere"
        reason = f"faces first, but {note}: {figures}; {default.reason}"
        return dataclasses.replace(default, reason=reason), note, a
    note = (
        f"{a:g} of the skin fit and {1 - a:g} of the default ({default.model}): the skin fit "
        f"alone was worse than the default elsewhere; so mixed, {figures}"
    )
    details = {**fit.details, "default_share": 1 - a}
    return dataclasses.replace(fit, correction=blended, details=details), note, a


def q_skin_priority(problem: QProblem) -> QFit:
    """The skin-first post-correction (module docstring); an InputError without skin samples.

    Examples
    --------
    Without skin samples there is nothing to put first:

    >>> SL = np.eye(3)
    >>> problem = QProblem(SL=SL, SRL=np.ones((24, 3, 3)), beta=1.0, M=SL,
    ...                    w_avg=np.ones(3), target=np.ones((24, 3)))
    >>> q_skin_priority(problem)
    Traceback (most recent call last):
    ...
    ocio_vp.errors.InputError: --priority: skin: the chart gives no skin samples ...
    """
    if problem.skin is None or problem.skin.count == 0:
        raise InputError(
            "skin: the chart gives no skin samples (a ColorChecker 24, skin_patches named in "
            "the measurements file, or patches of skin colour are needed)",
            key="--priority",
        )
    X, P, w, white = problem_arrays(problem)
    rank, _ = target_rank(P, w, X)
    if rank < 3:
        fit = q_auto(problem)
        reason = f"skin priority not applied: the target chart has rank {rank}; {fit.reason}"
        return QFit(
            fit.correction, fit.model, fit.description, reason=reason, target_rank=rank,
            cross_validated_error=fit.cross_validated_error, details=fit.details,
        )  # fmt: skip
    active = w > 0
    Q_ls = fit_least_squares(X, P, w)
    chart_ls = float(np.mean(patch_errors(X @ Q_ls.T, P, w, white)[0][active]))
    if chart_ls < EXACT:
        fit = q_auto(problem)  # the stage reproduces the light: no colour, skin or other, to fix
        return QFit(
            fit.correction, fit.model, fit.description, reason=f"faces first: {fit.reason}",
            cross_validated_error=fit.cross_validated_error, target_rank=rank,
            details=fit.details,
        )  # fmt: skip
    candidate, why = bounded_candidate(problem, "root-polynomial", PRIORITY_SKIN_WEIGHT)
    if candidate is not None:
        fit = candidate
    else:
        rows = problem.skin_rows(PRIORITY_SKIN_WEIGHT)
        fit = QFit(
            MatrixCorrection(fit_least_squares(*with_rows(X, P, w, rows))),
            "skin-weighted",
            "3x3 least squares over the chart and the skin samples",
        )
    chart = float(np.mean(patch_errors(fit.correction.apply(X), P, w, white)[0][active]))
    if not chart <= CHART_BUDGET * chart_ls:
        default = q_auto(problem)
        reason = (
            f"faces first, but the skin fit's chart error {chart:.3g} is above "
            f"{CHART_BUDGET:g}x least squares' {chart_ls:.3g}: the default kept; {default.reason}"
        )
        return dataclasses.replace(default, reason=reason)
    fit, elsewhere, share = within_default(problem, fit)
    if share == 0.0:  # the default itself, its reason saying why
        return fit
    chart = float(np.mean(patch_errors(fit.correction.apply(X), P, w, white)[0][active]))
    notes = [elsewhere] if why is None else [elsewhere, why]
    reason = (
        f"faces first: {fit.description} (skin weight {PRIORITY_SKIN_WEIGHT:g}); chart mean "
        f"ΔE2000 {chart:.3g} against least squares' {chart_ls:.3g} (at most {CHART_BUDGET:g}x)"
    )
    return QFit(
        fit.correction,
        fit.model,
        fit.description,
        reason="; ".join([reason, *notes]),
        cross_validated_error=fit.cross_validated_error,
        target_rank=rank,
        details={**fit.details, "skin_weight": PRIORITY_SKIN_WEIGHT, "chart_budget": CHART_BUDGET},
    )
