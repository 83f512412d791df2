"""The paper's solves: M, Q, N and the in-frustum black-level offset.

Notation follows LeGendre, Lepicovsky & Debevec (2022), Section 3.3: ``SL`` is [SL] (camera
channels along rows, LED channels along columns), ``SRL`` stacks the [SRL]_j, ``beta`` is the
panel's form factor and ``w_avg`` the environment's diffuse integral. Content is camera-native
linear RGB; "drive" is the linear signal sent to the LED channels (1.0 = the primaries' level).

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import BLACK_LEVEL_METHODS
from ocio_vp.errors import InputError
from ocio_vp.model.correction import MAX_CONDITION_INVERSE, condition_number

__all__ = [
    "BLACK_LEVEL_METHODS",
    "MAX_CONDITION_Q_FOR_N",
    "MAX_CONDITION_SL",
    "SINGULAR_CONDITION",
    "black_level_offset",
    "condition_number",
    "condition_text",
    "in_frustum_drive",
    "predict_displayed_chart",
    "predict_lit_chart",
    "solve_M",
    "solve_N",
]

#: [SL] above this condition number is refused: inverting it would turn float64 rounding
#: (and any real measurement noise) into visible errors in M (relative error ~ cond * 1e-16
#: from arithmetic alone, ~ cond * noise from the plates).
MAX_CONDITION_SL = 1e10

#: N = M Q^-1 is not solved when cond(Q) is above this: the post-correction's own invertibility
#: limit (:data:`ocio_vp.model.MAX_CONDITION_INVERSE`, defined there once).
MAX_CONDITION_Q_FOR_N = MAX_CONDITION_INVERSE


def solve_M(
    SL: ArrayLike, *, max_condition: float = MAX_CONDITION_SL, source: object = None
) -> np.ndarray:
    """The out-of-frustum pre-correction ``M = [SL]^-1`` (paper, eqs. 1-2).

    Parameters
    ----------
    SL
        (3, 3) camera RGB of the three LED primaries, as columns.
    max_condition
        Refuse an [SL] whose condition number is above this.

    Raises
    ------
    InputError
        When [SL] is singular or worse conditioned than ``max_condition`` (e.g. two primaries
        that look alike to the camera, or a dark LED channel).

    Examples
    --------
    >>> SL = np.array([[0.8, 0.1, 0.0], [0.2, 0.7, 0.1], [0.0, 0.1, 0.9]])
    >>> bool(np.allclose(SL @ solve_M(SL), np.eye(3)))
    True
    """
    SL = np.asarray(SL, dtype=np.float64)
    if SL.shape != (3, 3):
        raise InputError(f"[SL] must be 3x3, got shape {SL.shape}", source=source, key="primaries")
    cond = condition_number(SL)
    if not cond <= max_condition:
        raise InputError(
            f"[SL] is singular or badly conditioned (cond {cond:.3g} > {max_condition:.0e}): two "
            "primaries look alike to the camera or an LED channel is dark; re-shoot the primaries",
            source=source,
            key="primaries",
        )
    return np.linalg.inv(SL)


def predict_lit_chart(SRL: ArrayLike, beta: float, M: ArrayLike, w_avg: ArrayLike) -> np.ndarray:
    """The chart lit by the stage showing an environment through M (paper, eq. 3).

    ``(1/beta) [SRL]_j M w_avg`` for every patch j.

    Parameters
    ----------
    SRL
        (n, 3, 3) the [SRL]_j as photographed from the calibration panel.
    beta
        The calibration panel's form factor.
    M
        (3, 3) the out-of-frustum pre-correction.
    w_avg
        (3,) the environment's diffuse integral (camera RGB).

    Returns
    -------
    ndarray
        (n, 3) predicted camera RGB of every patch.
    """
    SRL = np.asarray(SRL, dtype=np.float64)
    drive = np.asarray(M, dtype=np.float64) @ np.asarray(w_avg, dtype=np.float64)
    return SRL @ drive / float(beta)


#: cond() above this is a singular matrix: the figure itself is rounding (1e16 on one machine,
#: 4e18 on another), so texts print it as a bound.
SINGULAR_CONDITION = 1e12


def condition_text(cond: float) -> str:
    """A condition number as texts print it: 3 digits, or ``> 1e+12`` for a singular matrix.

    >>> condition_text(12.345), condition_text(4.1e18), condition_text(float("inf"))
    ('12.3', '> 1e+12', '> 1e+12')
    """
    return f"{cond:.3g}" if cond <= SINGULAR_CONDITION else f"> {SINGULAR_CONDITION:.0e}"


def solve_N(
    M: ArrayLike,
    Q: ArrayLike,
    *,
    max_condition: float = MAX_CONDITION_Q_FOR_N,
    SL: ArrayLike | None = None,
) -> tuple[np.ndarray | None, str | None]:
    """The in-frustum pre-correction ``N = M Q^-1`` (paper, eqs. 6-8).

    With ``SL`` given, N is solved from eq. 7 itself, ``(Q [SL]) N = I``: then
    ``||Q [SL] N - I|| <= c eps cond(Q) cond([SL])`` (backward-stable LU, docs/stability.md),
    where going through ``M = [SL]^-1`` first can lose another factor cond(Q). For ``Q = I``
    both give ``N = M`` bit for bit.

    Returns
    -------
    (N, reason)
        ``N`` and ``None``; or ``None`` and the reason N was not solved (Q singular or worse
        conditioned than ``max_condition``).
    """
    M = np.asarray(M, dtype=np.float64)
    Q = np.asarray(Q, dtype=np.float64)
    cond = condition_number(Q)
    if not cond <= max_condition:
        rank = int(np.linalg.matrix_rank(Q)) if np.all(np.isfinite(Q)) else 0
        return None, (
            f"Q is rank {rank} / cond {condition_text(cond)} > {max_condition:.0e}: its inverse would "
            "amplify measurement noise into the in-frustum drive; in-frustum content uses M, "
            "so do not apply Q to shots with the wall in frame"
        )
    if SL is not None:
        return np.linalg.solve(Q @ np.asarray(SL, dtype=np.float64), np.eye(3)), None
    # N = M Q^-1 computed as a solve of N Q = M (more accurate than forming Q^-1).
    N = np.linalg.solve(Q.T, M.T).T
    return N, None


def black_level_offset(
    b_camera: ArrayLike,
    *,
    M: ArrayLike,
    SL: ArrayLike | None = None,
    method: Literal["exact", "paper"] = "exact",
) -> np.ndarray:
    """Offset added to the in-frustum drive to cancel light bounced off the panels (Sec. 3.4).

    The camera sees ``[SL] d + b_camera`` for a drive ``d``. For the background to come back as
    it would without the bounce, ``d = N c - M b_camera``: the **exact** offset is
    ``-M b_camera`` in panel-drive space (equivalently ``Q b_camera`` subtracted from the content
    before N). The **paper** subtracts ``b_camera / w_camera`` from the displayed values, with
    ``w_camera = [SL] [1, 1, 1]`` the camera's view of a full-white panel: a per-channel
    approximation of ``M b_camera`` that is exact only when [SL] is diagonal. Both are returned
    in drive space: ``drive = N c + offset``.

    Parameters
    ----------
    b_camera
        (3,) camera RGB of the dark in-frustum panels with the environment lighting the stage.
    M
        (3, 3) the out-of-frustum pre-correction [SL]^-1.
    SL
        (3, 3) [SL] (``paper`` method only).
    method
        ``"exact"`` (default) or ``"paper"``.

    Examples
    --------
    >>> SL = np.diag([0.8, 0.9, 0.7])
    >>> b = np.array([0.02, 0.03, 0.01])
    >>> bool(np.allclose(black_level_offset(b, M=np.linalg.inv(SL)),
    ...                  black_level_offset(b, M=np.linalg.inv(SL), SL=SL, method="paper")))
    True
    """
    b_camera = np.asarray(b_camera, dtype=np.float64)
    if method == "exact":
        return -np.asarray(M, dtype=np.float64) @ b_camera
    if method == "paper":
        if SL is None:
            raise ValueError("the paper's black level needs [SL]")
        w_camera = np.asarray(SL, dtype=np.float64).sum(axis=1)
        return -b_camera / w_camera
    raise ValueError(
        f"unknown black-level method {method!r}; expected one of {BLACK_LEVEL_METHODS}"
    )


def in_frustum_drive(
    content: ArrayLike, *, matrix: ArrayLike, offset: ArrayLike | None = None
) -> np.ndarray:
    """The LED drive ``matrix c + offset`` the in-frustum wall is asked for (before clipping).

    Examples
    --------
    >>> in_frustum_drive([[0.5, 0.2, 0.1]], matrix=np.eye(3), offset=[-0.3, 0.0, 0.0]).tolist()
    [[0.2, 0.2, 0.1]]
    """
    content = np.asarray(content, dtype=np.float64)
    drive = content @ np.asarray(matrix, dtype=np.float64).T
    if offset is not None:
        drive = drive + np.asarray(offset, dtype=np.float64)
    return drive


def predict_displayed_chart(
    content: ArrayLike,
    *,
    SL: ArrayLike,
    matrix: ArrayLike,
    offset: ArrayLike | None = None,
    black_level: ArrayLike | None = None,
    max_drive: float | None = None,
) -> np.ndarray:
    """Camera RGB of ``content`` shown on the in-frustum wall (before any post-correction).

    ``[SL] clip(matrix c + offset) + b_camera``: the wall cannot emit a negative drive (nor
    more than ``max_drive``, when given), and the camera also sees the light bounced off the
    panels, ``b_camera``.
    """
    drive = in_frustum_drive(content, matrix=matrix, offset=offset)
    drive = np.clip(drive, 0.0, np.inf if max_drive is None else max_drive)
    seen = drive @ np.asarray(SL, dtype=np.float64).T
    if black_level is not None:
        seen = seen + np.asarray(black_level, dtype=np.float64)
    return seen
