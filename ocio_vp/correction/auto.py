"""``auto``: the simplest post-correction model the scene needs, judged on colours it was not
fitted to.

The candidates (:data:`~ocio_vp.correction.linear.AUTO_LADDER`) are judged by their
leave-one-patch-out ΔE2000 (:func:`~ocio_vp.correction.linear.choose_model`); none that renders
the skin samples worse than least squares is taken, and a target chart of rank below 3 gets a
reduced-rank Q. docs/stability.md ("What auto does") explains the rule; docs/accuracy.md
measures it on held-out colours.
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.extrapolation import (
    MIN_NEGATIVE,
    MIN_RETAINED,
    lowest_channel_words,
    saturation_probe,
)
from ocio_vp.correction.guards import relative_figure
from ocio_vp.correction.linear import (
    AUTO_LADDER,
    AUTO_LADDER_NARROW,
    AUTO_SE_FACTOR,
    AUTO_TIE,
    LINE_SPECTRUM_TOLERANCE,
    RANK_RELATIVE_TOLERANCE,
    ROOT_POLYNOMIAL_DEGREES,
    choose_model,
    fit_model,
    is_narrow,
    ladder_predictions,
    loo_predictions,
    patch_errors,
    problem_arrays,
    target_rank,
)
from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.correction.root_polynomial import make_q_root_polynomial
from ocio_vp.correction.skin_figures import skin_errors
from ocio_vp.errors import InputError
from ocio_vp.metrics import error_relative_to_white, zero_below_rounding
from ocio_vp.model.correction import MatrixCorrection, PostCorrection
from ocio_vp.model.expansion import ROOT_POLYNOMIAL_TERMS

__all__ = [
    "AUTO_SKIN_WEIGHT",
    "DEGREE_3_EXCLUDED",
    "SHRUNK_SE_FACTOR",
    "bounded_candidate",
    "candidate_skin_errors",
    "q_auto",
]

#: Said in every ``auto`` reason: why the richer root-polynomial is not a candidate.
DEGREE_3_EXCLUDED = (
    "root-polynomial degree 3 is not a candidate: its 13 terms per channel over-fit a 24-patch "
    "chart"
)

#: ``regularised`` (least squares shrunk toward white balance) replaces least squares only when
#: better by this many standard errors of the paired per-patch differences: its gains on the
#: chart carry to held-out reflectances less often than the others' (docs/accuracy.md).
SHRUNK_SE_FACTOR = 2.0

#: Weight of the skin samples in ``auto``'s root-polynomial candidate (relative to the chart's
#: energy; :func:`ocio_vp.correction.skin.skin_rows`), chosen on the training skin and the
#: tuning cameras (docs/skin.md).
AUTO_SKIN_WEIGHT = 0.25

#: A candidate is not taken when its mean ΔE2000 on the skin samples is above least squares' by
#: more than this many standard errors of the paired per-sample differences (worse beyond the
#: comparison's own noise).
SKIN_SE_FACTOR = 1.0


_NAMES = {"root-polynomial": "root-polynomial (degree 2, bounded)"}


def _label(name: str) -> str:
    return _NAMES.get(name, name)


def _g(value: float, digits: int = 3, sign: str = "") -> str:
    """A ΔE figure as the reason prints it; below 1e-9 it is rounding, printed as 0."""
    return f"{value:{sign}.{digits}g}" if abs(value) >= 1e-9 else "0"


def _auto_reason(chosen: str, table: dict, factor: float, reference: str, unit: str) -> str:
    row = table[chosen]
    rest = ", ".join(
        f"{_label(k)} {_g(v['mean'])} ({_g(v['difference'], 2, '+')} ± "
        f"{_g(v['standard_error'], 2)})"
        for k, v in table.items()
        if k not in (chosen, reference)
    )
    if chosen == reference:
        head = (
            f"{reference} (the paper's eq. 5): leave-one-patch-out mean {unit} "
            f"{_g(row['mean'])}; no other model is better by more than {factor:g} standard "
            "error of the paired per-patch differences"
        )
    elif abs(row["difference"]) <= AUTO_TIE:
        head = (
            f"{_label(chosen)}: leave-one-patch-out mean {unit} {_g(row['mean'])}, the same "
            f"as {reference}'s: the simplest model that fits as well"
        )
    else:
        head = (
            f"{_label(chosen)}: leave-one-patch-out mean {unit} {_g(row['mean'])}, better than "
            f"{reference}'s {_g(table[reference]['mean'])} by {_g(-row['difference'], 2)} ± "
            f"{_g(row['standard_error'], 2)} (more than {factor:g} standard error of the paired "
            "per-patch differences)"
        )
    return f"{head}; others (difference from {reference}): {rest}; {DEGREE_3_EXCLUDED}"


def _auto_reduced_rank(X, P, w, white, rank: int, singular: np.ndarray, details: dict) -> QFit:
    name = f"rank-{rank}"
    held = loo_predictions(name, X, P, w, white)
    active = w > 0
    figures = ", ".join(relative_figure(v) for v in singular)
    reason = (
        f"the target chart has rank {rank} (its singular values relative to the largest, over "
        f"the lit chart's: {figures}; a second one below "
        f"{LINE_SPECTRUM_TOLERANCE:g} is measurement noise, a third below "
        f"{RANK_RELATIVE_TOLERANCE:g} counts as absent): a near-monochromatic light, so Q is "
        f"fitted with rank {rank} and cannot be inverted; N is not solved"
    )
    details["cv_delta_e"] = {name: float(np.mean(patch_errors(held, P, w, white)[0][active]))}
    return QFit(
        MatrixCorrection(fit_model(name, X, P, w, white)),
        name,
        f"reduced-rank least squares (rank {rank})",
        reason=reason,
        cross_validated_error=error_relative_to_white(held, P, white, w),
        target_rank=rank,
        details=details,
    )


def bounded_candidate(
    problem: QProblem, name: str, skin_weight: float = 0.0
) -> tuple[QFit | None, str | None]:
    """The bounded root-polynomial fit and its held-out predictions' source; (None, why) when it
    is not a candidate: the chart does not constrain its terms, it folds among reflective
    colours whatever its fade, or it flips or collapses a bright saturated input that least
    squares does not."""
    try:
        fit = make_q_root_polynomial(ROOT_POLYNOMIAL_DEGREES[name], skin_weight)(problem)
    except InputError as error:
        return None, f"{_label(name)} refused: {error.problem}"
    if fit.warnings:
        return None, f"{_label(name)} is not a candidate: {fit.warnings[0]}"
    white = problem.predicted[problem.white_patch]
    kept, negative = saturation_probe(fit.correction, white)
    # Judged against its own fallback, the least-squares 3x3 that is also a candidate: a flip or
    # collapse that least squares has too is the light's or the camera's, not the polynomial's.
    fallback_kept, fallback_negative = saturation_probe(
        MatrixCorrection(fit.correction.matrix), white
    )
    if kept < min(MIN_RETAINED, fallback_kept) or negative < min(MIN_NEGATIVE, fallback_negative):
        return None, (
            f"{_label(name)} is not a candidate: a bright saturated input keeps {kept:.0%} of "
            f"its channel, {lowest_channel_words(negative)} (least squares: "
            f"{fallback_kept:.0%}, {lowest_channel_words(fallback_negative)})"
        )
    return fit, None


def _chosen_fit(chosen: str, X, P, w, white, alpha: float, model: QFit | None, **typed) -> QFit:
    """The chosen model's QFit: a root-polynomial one as its own method fitted it (``model``),
    auto's reason and figures on top."""
    if model is not None:
        details = {**typed.pop("details"), **model.details}
        return QFit(
            model.correction, chosen, model.description, details=details, folds=model.folds,
            **typed,
        )  # fmt: skip
    if chosen == "regularised":
        typed["details"]["shrinkage"] = alpha
    description = {"identity": "Q = I, no post-correction", "diagonal": "white balance"}
    return QFit(
        MatrixCorrection(fit_model(chosen, X, P, w, white, alpha)),
        chosen,
        description.get(chosen, f"{chosen} (chosen by auto)"),
        **typed,
    )


def _choose(scores: dict[str, np.ndarray]) -> tuple[str, dict, list[str]]:
    """:func:`~ocio_vp.correction.linear.choose_model`, with ``regularised`` held to
    :data:`SHRUNK_SE_FACTOR`: (chosen, the table of every candidate, why regularised was
    passed over, if it was)."""
    chosen, table = choose_model(scores, AUTO_SE_FACTOR)
    row = table.get("regularised")
    if (
        chosen != "regularised"
        or abs(row["difference"]) <= AUTO_TIE  # shrunk by nothing: least squares itself
        or row["difference"] < -SHRUNK_SE_FACTOR * row["standard_error"]
    ):
        return chosen, table, []
    chosen, _ = choose_model(
        {k: v for k, v in scores.items() if k != "regularised"}, AUTO_SE_FACTOR
    )
    return (
        chosen,
        table,
        [
            f"regularised is not taken: better than least-squares by {-row['difference']:.2g} ± "
            f"{row['standard_error']:.2g}, less than the {SHRUNK_SE_FACTOR:g} standard errors a "
            "shrunk 3x3 needs"
        ],
    )


def candidate_skin_errors(
    problem: QProblem, corrections: dict[str, PostCorrection]
) -> dict[str, np.ndarray]:
    """Each candidate's ΔE2000 on the problem's skin samples (:mod:`ocio_vp.correction.skin`),
    through the sample camera's matrix; empty where the problem has no skin."""
    if problem.skin is None or problem.skin.count == 0:
        return {}
    errors = skin_errors(problem, list(corrections.values()))
    return dict(zip(corrections, errors, strict=True))


def _skin_veto(skin: dict[str, np.ndarray]) -> tuple[set[str], list[str]]:
    """The candidates whose mean skin ΔE2000 is above least squares' by more than
    :data:`SKIN_SE_FACTOR` standard errors of the paired differences (and more than
    :data:`~ocio_vp.correction.linear.AUTO_TIE`), and why, in words."""
    if not skin:
        return set(), []
    base = skin["least-squares"]
    reference = float(np.mean(base))
    vetoed, words = set(), []
    for name, errors in skin.items():
        difference = errors - base
        se = float(np.std(difference, ddof=1) / np.sqrt(len(difference))) if len(base) > 1 else 0.0
        if float(np.mean(difference)) > max(AUTO_TIE, SKIN_SE_FACTOR * se):
            vetoed.add(name)
            words.append(
                f"{_label(name)} is not taken: it renders skin worse than least squares (mean "
                f"ΔE2000 {_g(float(np.mean(errors)))} against {_g(reference)} on the skin "
                f"samples, by more than {SKIN_SE_FACTOR:g} standard error)"
            )
    return vetoed, words


def _corrections(held, models, X, P, w, white, alpha) -> dict[str, PostCorrection]:
    """Every candidate's post-correction fitted to all its patches, by name."""
    return {
        name: models[name].correction
        if name in models
        else MatrixCorrection(fit_model(name, X, P, w, white, alpha))
        for name in held
    }


def _root_polynomial_candidates(
    problem: QProblem, ladder: tuple[str, ...], held: dict[str, np.ndarray]
) -> tuple[dict[str, QFit], list[str]]:
    """The ladder's root-polynomial candidates (fitted to the skin samples too, with
    :data:`AUTO_SKIN_WEIGHT`), their leave-one-out predictions added to ``held``, and why any
    is not a candidate."""
    models, excluded = {}, []
    active = int(np.count_nonzero(problem.fit_weights > 0))
    for name in (m for m in ladder if m in ROOT_POLYNOMIAL_DEGREES):
        if active <= ROOT_POLYNOMIAL_TERMS[ROOT_POLYNOMIAL_DEGREES[name]]:
            continue
        fit, why = bounded_candidate(problem, name, AUTO_SKIN_WEIGHT)
        if fit is None:
            excluded.append(why or "")
            continue
        models[name] = fit
        assert fit.loo_predictions is not None  # enough patches, checked above
        held[name] = fit.loo_predictions
    return models, excluded


def q_auto(problem: QProblem) -> QFit:
    """The simplest model the scene needs, judged in leave-one-out ΔE2000 (module docstring).

    ``model`` names the choice and ``reason`` why (every candidate left out, and why);
    ``details`` hold every candidate's leave-one-out mean ΔE2000 (``cv_delta_e``), its
    difference from least squares and that difference's standard error (``cv_comparison``).

    Examples
    --------
    A chart lit exactly as the stage lights it needs no correction:

    >>> SL = np.array([[0.9, 0.1, 0.0], [0.2, 0.8, 0.1], [0.0, 0.1, 0.9]])
    >>> rho = np.random.default_rng(0).uniform(0.05, 0.9, (24, 3, 1))
    >>> SRL = 0.25 * rho * SL
    >>> problem = QProblem(SL=SL, SRL=SRL, beta=0.25, M=np.linalg.inv(SL),
    ...                    w_avg=SL.sum(axis=1), target=SRL.sum(axis=2) / 0.25)
    >>> q_auto(problem).model
    'identity'
    """
    X, P, w, white = problem_arrays(problem)
    rank, singular = target_rank(P, w, X)
    details: dict = {
        "target_singular_values": singular,
        "rank_relative_tolerance": RANK_RELATIVE_TOLERANCE,
        "se_factor": AUTO_SE_FACTOR,
        "metric": "leave-one-patch-out ΔE2000",
    }
    if rank < 3:
        return _auto_reduced_rank(X, P, w, white, rank, singular, details)
    active = w > 0
    narrow = is_narrow(X, P, w)
    ladder = AUTO_LADDER_NARROW if narrow else AUTO_LADDER
    held, alpha = ladder_predictions(
        [m for m in ladder if m not in ROOT_POLYNOMIAL_DEGREES], X, P, w, white
    )
    models, excluded = _root_polynomial_candidates(problem, ladder, held)
    stacked, unit = patch_errors(np.stack(list(held.values())), P, w, white)
    scores = {name: e[active] for name, e in zip(held, stacked, strict=True)}
    skin = candidate_skin_errors(problem, _corrections(held, models, X, P, w, white, alpha))
    vetoed, veto_words = _skin_veto(skin)
    chosen, _, shrunk = _choose({k: v for k, v in scores.items() if k not in vetoed})
    table = choose_model(scores, AUTO_SE_FACTOR)[1]  # every candidate, for the reason
    excluded += veto_words + shrunk
    reason = _auto_reason(chosen, table, AUTO_SE_FACTOR, "least-squares", unit)
    details |= {
        "metric": f"leave-one-patch-out {unit}",
        "cv_delta_e": {k: v["mean"] for k, v in table.items()},
        "cv_comparison": table,
        "cv_error": {
            k: float(np.mean(error_relative_to_white(h, P, white, w))) for k, h in held.items()
        },
        "narrow_target": narrow,
        "excluded_candidates": excluded,
    }
    if skin:
        details["skin_delta_e"] = {k: zero_below_rounding(np.mean(v)) for k, v in skin.items()}
    return _chosen_fit(
        chosen,
        X,
        P,
        w,
        white,
        alpha,
        models.get(chosen),
        reason="; ".join([reason, *excluded]),
        cross_validated_error=error_relative_to_white(held[chosen], P, white, w),
        target_rank=rank,
        details=details,
    )
