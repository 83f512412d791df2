"""``auto``: the simplest post-correction model the scene needs, judged on colours it was not
fitted to.

The candidates (:data:`~ocio_vp.correction.linear.AUTO_LADDER`, simplest first) are the linear
family of :mod:`ocio_vp.correction.linear` — identity, white balance, shrunk least squares, the
paper's least squares — and the root-polynomial model of degree 2
(:mod:`ocio_vp.correction.root_polynomial`). Each is judged by its **leave-one-patch-out**
predictions (every patch predicted by the model fitted without it, in closed form), in
**ΔE2000** through a camera RGB -> XYZ matrix
(:func:`ocio_vp.correction.perceptual.patch_delta_e`). The paper's least squares is kept unless
another model is better by more than :data:`~ocio_vp.correction.linear.AUTO_SE_FACTOR`
standard errors of the paired per-patch differences (a one-standard-error rule: the
comparison's own noise decides what "better" means); among equals the simplest wins
Root-polynomial degree 3 is not a candidate:
its 13 terms per channel over-fit a 24-patch chart (on held-out colours it was 34 % worse than
the 3x3 under broadband light, and worse in 29 of 30 environment and noise cells,
docs/accuracy.md). When the target chart has numerical rank below
3 (a monochromatic light such as low-pressure sodium) a reduced-rank Q is fitted instead and N
is not solved. docs/accuracy.md measures the rule on held-out colours; docs/stability.md
explains it.
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.linear import (
    AUTO_LADDER,
    AUTO_LADDER_NARROW,
    AUTO_SE_FACTOR,
    AUTO_TIE,
    NARROW_TARGET,
    RANK_RELATIVE_TOLERANCE,
    ROOT_POLYNOMIAL_DEGREES,
    choose_model,
    colour_spread,
    fit_model,
    ladder_predictions,
    loo_predictions,
    patch_errors,
    problem_arrays,
    target_rank,
)
from ocio_vp.correction.problem import QFit, QProblem
from ocio_vp.correction.root_polynomial import make_q_root_polynomial
from ocio_vp.errors import InputError
from ocio_vp.metrics import error_relative_to_white

__all__ = ["DEGREE_3_EXCLUDED", "q_auto"]

#: Said in every ``auto`` reason: why the richer root-polynomial is not a candidate.
DEGREE_3_EXCLUDED = (
    "root-polynomial degree 3 is not a candidate: its 13 terms per channel over-fit a 24-patch "
    "chart"
)

_NAMES = {"root-polynomial": "root-polynomial (degree 2)"}


def _label(name: str) -> str:
    return _NAMES.get(name, name)


def _auto_reason(chosen: str, table: dict, factor: float, reference: str, unit: str) -> str:
    row = table[chosen]
    rest = ", ".join(
        f"{_label(k)} {v['mean']:.3g} ({v['difference']:+.2g} ± {v['standard_error']:.2g})"
        for k, v in table.items()
        if k not in (chosen, reference)
    )
    if chosen == reference:
        head = (
            f"{reference} (the paper's eq. 5): leave-one-patch-out mean {unit} "
            f"{row['mean']:.3g}; no other model is better by more than {factor:g} standard "
            "error of the paired per-patch differences"
        )
    elif abs(row["difference"]) <= AUTO_TIE:
        head = (
            f"{_label(chosen)}: leave-one-patch-out mean {unit} {row['mean']:.3g}, the same "
            f"as {reference}'s: the simplest model that fits as well"
        )
    else:
        head = (
            f"{_label(chosen)}: leave-one-patch-out mean {unit} {row['mean']:.3g}, better than "
            f"{reference}'s {table[reference]['mean']:.3g} by {-row['difference']:.2g} ± "
            f"{row['standard_error']:.2g} (more than {factor:g} standard error of the paired "
            "per-patch differences)"
        )
    return f"{head}; others (difference from {reference}): {rest}; {DEGREE_3_EXCLUDED}"


def _auto_reduced_rank(X, P, w, white, rank: int, singular: np.ndarray, notes: dict) -> QFit:
    name = f"rank-{rank}"
    held = loo_predictions(name, X, P, w, white)
    active = w > 0
    notes |= {
        "model": name,
        "reason": (
            f"the target chart has rank {rank} (its singular values relative to the largest, "
            "over the lit chart's: "
            f"{', '.join(f'{v:.2g}' for v in singular)}; below {RANK_RELATIVE_TOLERANCE:g} "
            "counts as absent): a near-monochromatic light, so Q is fitted with rank "
            f"{rank} and cannot be inverted; N is not solved"
        ),
        "cv_delta_e": {name: float(np.mean(patch_errors(held, P, w, white)[0][active]))},
        "cross_validated_error": error_relative_to_white(held, P, white, w),
    }
    return QFit(Q=fit_model(name, X, P, w, white), notes=notes)


def _root_polynomial_fit(problem: QProblem, name: str) -> QFit | None:
    """The root-polynomial method's own fit; None when it refuses the chart (too few or
    dependent patches for its terms)."""
    try:
        return make_q_root_polynomial(ROOT_POLYNOMIAL_DEGREES[name])(problem)
    except InputError:
        return None


def _chosen_fit(chosen: str, X, P, w, white, alpha: float, notes: dict, model: QFit | None):
    """The chosen model's QFit: a root-polynomial one as its own method fitted it (``model``:
    the model in ``notes["root_polynomial"]``, Q its 3x3 approximation), auto's notes on top."""
    if model is not None:
        return QFit(Q=model.Q, notes={**model.notes, **notes})
    if chosen == "regularised":
        notes["shrinkage"] = alpha
    return QFit(Q=fit_model(chosen, X, P, w, white, alpha), notes=notes)


def q_auto(problem: QProblem) -> QFit:
    """The simplest model the scene needs, judged in leave-one-out ΔE2000 (module docstring).

    The notes say which model was chosen (``model``), why (``reason``, in ΔE2000), every
    candidate's leave-one-out mean ΔE2000 (``cv_delta_e``) with its difference from least
    squares and that difference's standard error (``cv_comparison``), the rule's factor, the
    target chart's rank, and the chosen model's leave-one-out error per channel relative to
    white (``cross_validated_error``). A root-polynomial choice also carries that method's
    notes (``root_polynomial``: degree and coefficients; ``warnings``).

    Examples
    --------
    A chart lit exactly as the stage lights it needs no correction:

    >>> SL = np.array([[0.9, 0.1, 0.0], [0.2, 0.8, 0.1], [0.0, 0.1, 0.9]])
    >>> rho = np.random.default_rng(0).uniform(0.05, 0.9, (24, 3, 1))
    >>> SRL = 0.25 * rho * SL
    >>> problem = QProblem(SL=SL, SRL=SRL, beta=0.25, M=np.linalg.inv(SL),
    ...                    w_avg=SL.sum(axis=1), target=SRL.sum(axis=2) / 0.25)
    >>> q_auto(problem).notes["model"]
    'identity'
    """
    X, P, w, white = problem_arrays(problem)
    rank, singular = target_rank(P, w, X)
    notes: dict = {
        "target_rank": rank,
        "target_singular_values": singular,
        "rank_relative_tolerance": RANK_RELATIVE_TOLERANCE,
        "se_factor": AUTO_SE_FACTOR,
        "metric": "leave-one-patch-out ΔE2000",
    }
    if rank < 3:
        return _auto_reduced_rank(X, P, w, white, rank, singular, notes)
    active = w > 0
    narrow = colour_spread(P[active]) < NARROW_TARGET * colour_spread(X[active])
    held, alpha = ladder_predictions(AUTO_LADDER_NARROW if narrow else AUTO_LADDER, X, P, w, white)
    stacked, unit = patch_errors(np.stack(list(held.values())), P, w, white)
    scores = {name: e[active] for name, e in zip(held, stacked, strict=True)}
    chosen, table = choose_model(scores, AUTO_SE_FACTOR)
    model = None
    if chosen in ROOT_POLYNOMIAL_DEGREES:
        model = _root_polynomial_fit(problem, chosen)
        if model is None:  # a design the patches do not constrain: not a candidate
            del scores[chosen], held[chosen]
            chosen, table = choose_model(scores, AUTO_SE_FACTOR)
    notes |= {
        "model": chosen,
        "reason": _auto_reason(chosen, table, AUTO_SE_FACTOR, "least-squares", unit),
        "metric": f"leave-one-patch-out {unit}",
        "cv_delta_e": {k: v["mean"] for k, v in table.items()},
        "cv_comparison": table,
        "cv_error": {
            k: float(np.mean(error_relative_to_white(h, P, white, w))) for k, h in held.items()
        },
        "cross_validated_error": error_relative_to_white(held[chosen], P, white, w),
        "narrow_target": narrow,
    }
    return _chosen_fit(chosen, X, P, w, white, alpha, notes, model)
