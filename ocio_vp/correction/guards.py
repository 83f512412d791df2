"""Checks every Q method relies on, made before any method runs, and the cause of a singular Q.

A chart that cannot determine a 3x3 Q (fewer than 3 usable patches, a lit chart that is dark in
one camera channel, patches whose lit colours span fewer than three directions, an all-black
target, a value no camera produces) is refused with an :class:`~ocio_vp.errors.InputError`
naming the key, instead of a rank-deficient or absurd Q that ``N_reason`` later blames on the
light. :func:`singular_q_cause` names the real cause when N cannot be solved.
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.problem import QProblem
from ocio_vp.errors import InputError
from ocio_vp.metrics import patch_label
from ocio_vp.wall.linearity import CHANNELS

__all__ = [
    "MAX_DYNAMIC_RANGE",
    "MIN_LIT_DIRECTION",
    "check_problem",
    "relative_figure",
    "singular_q_cause",
]

#: A chart value more than this many times the chart's median magnitude is not a camera value
#: (a typo, an unscaled integer, 1e300): no camera's linear signal spans 1e9 within one chart.
MAX_DYNAMIC_RANGE = 1e9
#: The lit chart's fitted patches must span three colour directions: the smallest singular
#: value of their (unit-length) colours at least this fraction of the largest.
MIN_LIT_DIRECTION = 1e-6

#: A relative singular value below this is rounding, not colour: printed as "< 1e-6" so that
#: texts do not depend on the machine's arithmetic (it varies by 10x there).
NOISE_FLOOR = 1e-6


def relative_figure(value: float) -> str:
    """A relative singular value as the terminal and configs print it (2 digits; rounding-level
    values as ``< 1e-6``).

    >>> relative_figure(0.37), relative_figure(3.7e-17)
    ('0.37', '< 1e-06')
    """
    return f"{value:.2g}" if value >= NOISE_FLOOR else f"< {NOISE_FLOOR:.0e}"


def _check_range(values: np.ndarray, active: np.ndarray, key: str, what: str) -> None:
    """Refuse a value more than MAX_DYNAMIC_RANGE times its column's median magnitude (each
    column is one camera channel, lit by one LED channel: a dark LED is not an outlier)."""
    magnitude = np.abs(values[active])
    for column in magnitude.T:
        lit = column[column > 0]
        if lit.size == 0:
            continue
        median = float(np.median(lit))
        if np.max(column) > MAX_DYNAMIC_RANGE * median:
            j = int(np.flatnonzero(active)[np.argmax(column)])
            raise InputError(
                f"{patch_label(j, len(values))} of the {what} reads {float(np.max(column)):.3g}, more than "
                f"{MAX_DYNAMIC_RANGE:.0e} times the median of its channel ({median:.3g}): not "
                "a camera value",
                key=key,
            )


def check_problem(problem: QProblem) -> None:
    """Refuse a Q problem no method can solve sensibly (see the module docstring).

    Raises
    ------
    InputError
        With key ``target_chart`` (or ``lit_chart`` for the lit chart's own defects).
    """
    w = problem.fit_weights
    active = w > 0
    count = int(np.count_nonzero(active))
    if count < 3:
        raise InputError(
            f"only {count} chart patches are usable (not clipped or excluded): need at least 3 "
            "to fit Q",
            key="target_chart",
        )
    P = np.asarray(problem.target, dtype=np.float64)
    SRL = np.asarray(problem.SRL, dtype=np.float64)
    _check_range(P, active, "target_chart", "target chart")
    _check_range(SRL.reshape(len(SRL), -1), active, "lit_chart", "lit chart")
    if not np.any(P[active] != 0):
        raise InputError("the target chart is black on every fitted patch", key="target_chart")
    dark = [c for c in range(3) if not np.any(SRL[active][:, c, :] != 0)]
    if dark:
        names = ", ".join(CHANNELS[c] for c in dark)
        raise InputError(
            f"the lit chart reads 0 in the camera's {names} channel on every patch: that "
            "channel carries no signal, so Q cannot be fitted (check the plates' channels)",
            key="lit_chart",
        )
    _check_directions(problem.predicted[active])


def _check_directions(X: np.ndarray) -> None:
    size = np.linalg.norm(X, axis=1, keepdims=True)
    if not np.all(np.isfinite(X)) or not np.any(size > 0):
        raise InputError(
            "the lit chart predicted through M is not finite or is black", key="lit_chart"
        )
    s = np.linalg.svd(X / np.where(size > 0, size, 1.0), compute_uv=False)
    rank = int(np.sum(s >= MIN_LIT_DIRECTION * s[0]))
    if rank < 3:
        raise InputError(
            f"the usable chart patches span only {rank} colour direction(s) under the stage's "
            "LEDs: a 3x3 Q needs patches of at least three different colours",
            key="target_chart",
        )


def singular_q_cause(problem: QProblem, model: str) -> str:
    """Why a fitted Q is singular, in the terms of the measurements (for ``N_reason``);
    ``model`` is the fitted model's name (``rank-1`` for a reduced-rank fit)."""
    if model.startswith("rank-"):
        return (
            f"the target chart has rank {model.removeprefix('rank-')}: a near-monochromatic "
            "light (such as sodium vapour) that the stage's LEDs cannot reproduce"
        )
    w = problem.fit_weights
    P = np.asarray(problem.target, dtype=np.float64)[w > 0]
    s = np.linalg.svd(P, compute_uv=False)
    if s[0] > 0 and s[-1] < 1e-2 * s[0]:
        return (
            f"the target chart has almost no colour in one direction (singular values "
            f"{', '.join(relative_figure(v / s[0]) for v in s)} of the largest): a near-monochromatic "
            "light such as sodium vapour, or a dark channel in the target plate"
        )
    return (
        f"the {model or 'fitted'} model gave a singular Q on this chart (its "
        "patches do not constrain every colour direction)"
    )
