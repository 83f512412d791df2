"""``--priority skin``: the post-correction fitted with faces first.

The bounded root-polynomial of degree 2 (a 3x3 where it is not safe) fitted to the chart and
the skin samples with weight :data:`PRIORITY_SKIN_WEIGHT`, the chart's error bounded by
:data:`CHART_BUDGET` times least squares'; where it is worse than the default (``auto``) on the
in-frustum background, the LEDs in frame or the skin, it is drawn towards the default (projected,
then straight, at :data:`BLEND_STEPS`). docs/skin.md ("--priority skin") explains the rule.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ocio_vp.calibration.equations import condition_number
from ocio_vp.correction.auto import bounded_candidate, q_auto
from ocio_vp.correction.linear import problem_arrays, target_rank
from ocio_vp.correction.problem import QFit, QProblem, fit_least_squares
from ocio_vp.correction.skin import with_rows
from ocio_vp.correction.skin_figures import (
    chart_error,
    clipped_background,
    judged,
    shown_error,
)
from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.model.correction import (
    FitDomain,
    MatrixCorrection,
    PostCorrection,
    RootPolynomialCorrection,
)
from ocio_vp.model.expansion import ROOT_POLYNOMIAL_TERMS, root_polynomial_expansion

__all__ = ["BLEND_STEPS", "CHART_BUDGET", "PRIORITY_SKIN_WEIGHT", "q_skin_priority"]

#: Weight of the skin samples with skin first (relative to the chart's energy), chosen on the
#: training skin and the tuning cameras (docs/skin.md).
PRIORITY_SKIN_WEIGHT = 0.5
#: The chart's mean ΔE2000 after the fit may be at most this times least squares'.
CHART_BUDGET = 1.15
#: Least squares' chart ΔE2000 below this is rounding: the stage reproduces the light exactly.
EXACT = 1e-6
#: Shares of the way from the default to the skin fit tried, largest first, where the skin fit
#: is worse than the default on the background or the LEDs in frame (0 is the default itself).
BLEND_STEPS = (0.75, 0.5, 0.25, 0.0)
#: Along the projected way the background's first-order rise is turned into a fall of this
#: fraction of it, so that its second-order change does not make it a rise.
PROJECTION_MARGIN = 0.25
#: What the solve wraps the post-correction in (the emitter guard), applied before judging it.
Guard = Callable[[PostCorrection], PostCorrection]
#: Forward-difference step of the background's gradient, relative to the largest parameter.
_STEP = 1e-6


def _parameters(
    skin: PostCorrection, default: PostCorrection
) -> tuple[np.ndarray, np.ndarray] | None:
    """The skin fit's and the default's parameters in one space, where the two are models of
    one kind whose outputs mix linearly in them: two matrices, two root-polynomials of one
    degree, fallback, domain and fade, or a root-polynomial and the matrix that is its fallback
    (its linear terms); None for any other pair."""
    if isinstance(skin, MatrixCorrection) and isinstance(default, MatrixCorrection):
        return skin.Q, default.Q
    if not isinstance(skin, RootPolynomialCorrection):
        return None
    C = skin.coefficients
    if isinstance(default, MatrixCorrection):
        if not np.array_equal(default.Q, skin.fallback):
            return None
        D = np.zeros_like(C)
        D[:, :3] = default.Q  # the first three terms are r, g, b
        return C, D
    if (
        isinstance(default, RootPolynomialCorrection)
        and default.coefficients.shape == C.shape
        and np.array_equal(default.fallback, skin.fallback)
        and default.fade == skin.fade
        and _same_domain(default.domain, skin.domain)
    ):
        return C, default.coefficients
    return None


def _model(skin: PostCorrection, parameters: np.ndarray) -> PostCorrection:
    """``skin``'s kind of model with other parameters."""
    if isinstance(skin, MatrixCorrection):
        return MatrixCorrection(parameters)
    if not isinstance(skin, RootPolynomialCorrection):
        raise TypeError(f"no parameters for a {skin.kind} model")
    return dataclasses.replace(skin, coefficients=parameters)


def _gradient(problem: QProblem, skin: PostCorrection, at: np.ndarray) -> np.ndarray:
    """The background error's gradient in the parameters at ``at`` (forward differences) over
    the chart colours that clip there (the others are shown exactly); each moved model's
    inverse is one Newton step from the unmoved one's (exact to the step's square)."""
    model = _model(skin, at)
    clipped = clipped_background(problem, model)
    gradient = np.zeros_like(at)
    if not np.any(clipped):
        return gradient
    P = np.asarray(problem.target, dtype=np.float64)[clipped]
    u = model.inverse(P)
    h = _STEP * np.maximum(np.max(np.abs(u), axis=1), 1e-12)
    J = np.stack(
        [(model.apply(u + h[:, None] * e) - model.apply(u - h[:, None] * e)) / (2 * h[:, None])
         for e in np.eye(3)],
        axis=-1,
    )  # fmt: skip

    def error(moved: PostCorrection) -> float:
        content = u - np.linalg.solve(J, (moved.apply(u) - P)[..., None])[..., 0]
        return shown_error(problem, moved, content, P)

    base = error(model)
    step = _STEP * max(float(np.max(np.abs(at))), 1.0)
    for index in np.ndindex(at.shape):
        moved = at.copy()
        moved[index] += step
        gradient[index] = (error(_model(skin, moved)) - base) / step
    return gradient


def _directions(problem: QProblem, skin: PostCorrection, C: np.ndarray, D: np.ndarray):
    """From the default's parameters ``D`` towards the skin fit's ``C``: the straight way and,
    where the background error rises along it, the way with that rise taken out (to first
    order, plus :data:`PROJECTION_MARGIN` of it turned into a fall), that one first."""
    step = C - D
    g = _gradient(problem, skin, D)
    rise = float(np.sum(g * step))
    metric = _fit_metric(problem, C)
    if rise > 0 and metric is not None:
        h = np.linalg.solve(metric, g.T).T  # the way the fit's rows resist least
        norm = float(np.sum(g * h))
        if norm > 0:
            yield "projected", step - (1 + PROJECTION_MARGIN) * rise / norm * h
    yield "straight", step


def _fit_metric(problem: QProblem, C: np.ndarray) -> np.ndarray | None:
    """``E^T W E`` of the skin fit's rows (the chart and the skin samples, the expansion ``E``
    of their lit colours, weights ``W``): how much its objective grows per parameter change;
    None where it is singular or the parameters are not a root-polynomial's or a matrix's."""
    X, P, w, _ = problem_arrays(problem)
    X, _, w = with_rows(X, P, w, problem.skin_rows(PRIORITY_SKIN_WEIGHT))
    terms = C.shape[1]
    degree = next((d for d, n in ROOT_POLYNOMIAL_TERMS.items() if n == terms), None)
    if terms == 3:
        E = X
    elif degree is not None:
        E = root_polynomial_expansion(X, degree)
    else:
        return None
    H = E.T @ (w[:, None] * E)
    return H if condition_number(H) < 1e12 else None


def _same_domain(a: FitDomain | None, b: FitDomain | None) -> bool:
    return a is b or (a is not None and b is not None and a.to_dict() == b.to_dict())


def within_default(
    problem: QProblem, fit: QFit, default: QFit, guard: Guard | None = None
) -> tuple[QFit, str, float]:
    """``fit`` drawn towards the default until its background and LED figures are no worse
    than the default's, nor its skin (module docstring), each judged through ``guard`` (the
    emitter guard the solve wraps the model in; none by default): the fit, what was done in
    words, and the share of the way from the default to the skin fit taken (1: the skin fit
    unchanged, 0: the default); ``default`` is ``auto``'s fit of ``problem``."""
    guarded = guard or (lambda correction: correction)
    reference = judged(problem, guarded(default.correction))
    figures = judged(problem, guarded(fit.correction))
    chart = max(figures.chart, reference.chart)  # both the default's and the skin fit's are fine
    chosen, share, way = fit.correction, 1.0, "straight"
    if not figures.no_worse(reference, chart):
        chosen, share, figures = default.correction, 0.0, reference
        pair = _parameters(fit.correction, default.correction)
        C, D = pair if pair is not None else (np.zeros(0), np.zeros(0))
        for way, step in () if pair is None else _directions(problem, fit.correction, C, D):
            for a in (1.0, *BLEND_STEPS[:-1]):
                if way == "straight" and a == 1.0:
                    continue  # the skin fit itself, judged above
                candidate = _model(fit.correction, D + a * step)
                candidate_figures = judged(problem, guarded(candidate))
                if candidate_figures.no_worse(reference, chart):
                    chosen, share, figures = candidate, a, candidate_figures
                    break
            if share > 0:
                break
    words = figures.words(reference)
    if share == 1.0 and way == "straight":
        return fit, f"no worse than the default ({default.model}) elsewhere: {words}", share
    if share == 0.0:
        note = f"the default ({default.model}) kept: the skin fit was worse than it elsewhere"
        reason = f"faces first, but {note}: {words}; {default.reason}"
        return dataclasses.replace(default, reason=reason), note, share
    note = (
        f"{share:g} of the way from the default ({default.model}) to the skin fit"
        f"{', the background rise taken out' if way == 'projected' else ''}: the skin fit "
        f"alone was worse than the default elsewhere; so, {words}"
    )
    details = {**fit.details, "share": share, "way": way}
    return dataclasses.replace(fit, correction=chosen, details=details), note, share


def q_skin_priority(problem: QProblem, guard: Guard | None = None) -> QFit:
    """The skin-first post-correction (module docstring); an InputError without skin samples.
    ``guard``: the emitter guard the solve will wrap it in (judged through it).

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
    default = q_auto(problem)
    fit = _q_skin_priority(problem, default, guard)
    return dataclasses.replace(fit, default=default)


def _q_skin_priority(problem: QProblem, default: QFit, guard: Guard | None) -> QFit:
    X, P, w, _ = problem_arrays(problem)
    rank, _ = target_rank(P, w, X)
    if rank < 3:
        fit = default
        reason = f"skin priority not applied: the target chart has rank {rank}; {fit.reason}"
        return QFit(
            fit.correction, fit.model, fit.description, reason=reason, target_rank=rank,
            cross_validated_error=fit.cross_validated_error, details=fit.details,
        )  # fmt: skip
    chart_ls = chart_error(problem, X @ fit_least_squares(X, P, w).T)
    if chart_ls < EXACT:
        fit = default  # the stage reproduces the light: no colour, skin or other, to fix
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
    chart = chart_error(problem, fit.correction.apply(X))
    if not chart <= CHART_BUDGET * chart_ls:
        reason = (
            f"faces first, but the skin fit's chart error {chart:.3g} is above "
            f"{CHART_BUDGET:g}x least squares' {chart_ls:.3g}: the default kept; {default.reason}"
        )
        return dataclasses.replace(default, reason=reason)
    fit, elsewhere, share = within_default(problem, fit, default, guard)
    if share == 0.0:  # the default itself, its reason saying why
        return fit
    chart = chart_error(problem, fit.correction.apply(X))
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


#: Names served for one more release (ocio_vp.deprecation): ``default_fit(problem)`` was
#: ``q_auto(problem)`` kept in a module-level cache of the last problem.
DEPRECATED = {
    "default_fit": (
        "ocio_vp.correction.auto.q_auto (the skin-first fit's default field holds the fit it "
        "was compared with)",
        "ocio_vp.correction.auto:q_auto",
    )
}
__getattr__ = deprecated_names(__name__, DEPRECATED)
