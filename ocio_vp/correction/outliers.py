"""Patches inconsistent with the rest of the chart, found before any Q is fitted.

:func:`inconsistent_patches` judges each patch by its held-out **residual** under a
Huber-weighted least-squares 3x3 fitted on the others, its **influence** on the other patches'
colours (:func:`patch_influence`) and how much it **explains** of the chart's inconsistency
(:func:`deletion_gain`), and each reading-order pair by whether it looks **swapped**
(:func:`pair_residuals`); the worst is excluded and the search repeats, up to
:data:`MAX_EXCLUDED_FRACTION` of the chart. docs/stability.md ("A bad patch") explains the tests
and how the thresholds below were set; docs/accuracy.md measures them.
"""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.linear import (
    fit_least_squares,
    is_narrow,
    loo_predictions,
    normal_equations,
    weighted_outer,
)
from ocio_vp.correction.perceptual import (
    normalising_white,
    patch_delta_e,
)
from ocio_vp.errors import InputError
from ocio_vp.formats.diagnostics import Inconsistency
from ocio_vp.metrics import COLORCHECKER_NAMES, sample_camera_to_xyz, white_scale
from ocio_vp.metrics import patch_label as patch_name

__all__ = [
    "COLORCHECKER_NAMES",
    "DELETION_GAIN",
    "EXPLAINS_RELATIVE",
    "FIRST_PASS_SUPPORT",
    "HUBER",
    "INFLUENCE_JUDGES",
    "LATER_INFLUENCE",
    "LATER_RELATIVE",
    "MAX_EXCLUDED",
    "MAX_EXCLUDED_FRACTION",
    "OUTLIER_FLOOR",
    "OUTLIER_INFLUENCE",
    "OUTLIER_RELATIVE",
    "OUTLIER_RELATIVE_NARROW",
    "OUTLIER_Z",
    "SWAP_FLOOR",
    "SWAP_RATIO",
    "SWAP_Z",
    "UNSUPPORTED_SCORE",
    "Inconsistency",
    "deletion_gain",
    "inconsistent_patches",
    "is_narrow",
    "pair_residuals",
    "patch_influence",
    "patch_name",
    "patch_scores",
]

#: A patch is inconsistent when its held-out residual is at least this fraction of the patch
#: itself (``|prediction - target| / max(|prediction|, |target|)``: 1 for a patch read as zero,
#: 0.6 for one read 2.5x too bright) ...
OUTLIER_RELATIVE = 0.3
#: ... at least this many robust standard deviations of all patches' residuals (relative to
#: the target white) ...
OUTLIER_Z = 4.0
#: ... and at least this fraction of the target white (dark patches' noise is not a defect).
OUTLIER_FLOOR = 0.02
#: Under a line-spectrum light the wall cannot reproduce (a *narrow* target,
#: :data:`ocio_vp.correction.linear.NARROW_TARGET`) the 3x3 itself misses single patches by
#: much of their value: only a patch at least this far off (read as zero, its row lost) is.
OUTLIER_RELATIVE_NARROW = 0.9
#: A patch is also inconsistent when leaving it out moves the least-squares fit's colours of the
#: other patches by at least this mean ΔE2000 (:func:`patch_influence`: what an engineer would
#: see), it stands :data:`OUTLIER_Z` robust standard deviations above the chart's influences
#: and it misses its held-out prediction by :data:`OUTLIER_RELATIVE` of itself.
OUTLIER_INFLUENCE = 3.0
#: A patch is also inconsistent when removing it makes the other patches' held-out residuals
#: this many times smaller than a typical patch's removal does (:func:`deletion_gain`) and it
#: misses its held-out prediction by :data:`OUTLIER_RELATIVE` of itself ...
DELETION_GAIN = 1.6
#: ... or, under broadband light (where the 3x3 predicts clean patches well), by this fraction:
#: a white patch read 1.3x too bright (a flare) misses by less than OUTLIER_RELATIVE.
EXPLAINS_RELATIVE = 0.1
#: Fitted patches whose colours judge each patch's influence on a large chart (all of them up
#: to this many); patches judged per block. Both bound the work: linear in the chart's size.
INFLUENCE_JUDGES = 128
_INFLUENCE_BLOCK = 256
#: Residuals beyond this many robust standard deviations weigh less in the fit that judges
#: the patches (Huber).
HUBER = 2.0
#: A patch found after another was excluded needs a score of 1 if it scored at least
#: FIRST_PASS_SUPPORT on the whole chart, else UNSUPPORTED_SCORE.
FIRST_PASS_SUPPORT = 0.5
UNSUPPORTED_SCORE = 2.0
#: After the worst patch is excluded, a further patch scoring below UNSUPPORTED_SCORE must also
#: move the other patches' colours by LATER_INFLUENCE mean ΔE2000 (one just-noticeable
#: difference) or miss its held-out prediction by LATER_RELATIVE times the relative limit
#: (capped at :data:`OUTLIER_RELATIVE_NARROW`: a patch read as zero misses by exactly 100 %):
#: once a bad patch is gone, a clean one of a similar colour is predicted worse without being
#: wrong, and keeping the chart's only red costs less than losing it.
LATER_INFLUENCE = 1.0
LATER_RELATIVE = 1.5
#: More inconsistent patches than this fraction of the chart: refuse rather than guess.
MAX_EXCLUDED_FRACTION = 0.125
#: ... or than this many on a large chart (each exclusion re-judges the whole chart). So many
#: bad patches say the sampling itself went wrong.
MAX_EXCLUDED = 24
#: Two reading-order neighbours look **swapped** (in the target or the lit chart) when, fitted
#: without both, the rest of the chart predicts them at least SWAP_RATIO times better exchanged
#: than as read (the sum of the two held-out residuals' sizes, relative to white:
#: :func:`pair_residuals`) and exchanging them explains at least SWAP_FLOOR of white ...
SWAP_RATIO = 3.0
SWAP_FLOOR = 0.25
#: ... and, as read, the pair misses by at least SWAP_Z times the chart's typical pair (where
#: the model does not fit the chart at all every pair misses alike, some better exchanged by
#: chance).
SWAP_Z = 2.0
#: Patches needed after exclusion (a 9-parameter fit with headroom to judge it).
_MIN_REMAINING = 12


def _robust_sd(values: np.ndarray) -> float:
    """1.4826 x the median: the standard deviation of normal values, not moved by outliers."""
    return 1.4826 * float(np.median(values))


def _robust_weights(X, P, w, scale, steps: int = 8) -> np.ndarray:
    """Weights of a Huber fit (iteratively reweighted least squares, threshold 2 robust
    standard deviations): several bad patches cannot drag the fit that judges them."""
    weights = np.asarray(w, dtype=np.float64).copy()
    active = weights > 0
    for _ in range(steps):
        Q = fit_least_squares(X, P, weights)
        size = np.linalg.norm((X @ Q.T - P) / scale, axis=1)
        spread = _robust_sd(size[active])
        if not spread > 0:
            break
        weights = np.where(
            active, w * np.minimum(1.0, HUBER * spread / np.maximum(size, 1e-300)), 0.0
        )
    return weights


def _spread(indices: np.ndarray) -> np.ndarray:
    """``indices``, or :data:`INFLUENCE_JUDGES` of them spread evenly when there are more."""
    if len(indices) <= INFLUENCE_JUDGES:
        return indices
    return indices[np.linspace(0, len(indices) - 1, INFLUENCE_JUDGES).round().astype(int)]


def _judges(w: np.ndarray, white: int, luminance: np.ndarray) -> tuple[np.ndarray, int]:
    """Indices of the fitted patches whose colours judge a patch's influence (all of them, or
    :data:`INFLUENCE_JUDGES` spread evenly over a larger chart, always with the white) and the
    white's position among them (the patch ΔE is normalised on: :func:`normalising_white`)."""
    white = normalising_white(luminance, white, w)
    judges = np.union1d(_spread(np.flatnonzero(w > 0)), [white])
    return judges, int(np.searchsorted(judges, white))


def patch_influence(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int) -> np.ndarray:
    """(n,) how far each fitted patch drags the fit: the mean ΔE2000, over the other fitted
    patches, between their least-squares predictions with and without it (0 for excluded ones).

    ΔE2000 as :func:`ocio_vp.correction.perceptual.patch_delta_e` gives it, normalised on the
    fitted white patch ``white`` (or the brightest fitted patch); all zeros when no fitted
    colour has luminance. Closed form (rank-one downdates, batched); on a chart of more than
    :data:`INFLUENCE_JUDGES` fitted patches the mean is over that many, spread evenly.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(0.05, 1.0, (24, 3)); X[18] = 1.0
    >>> P = X @ np.array([[1.1, -0.1, 0.0], [0.0, 1.0, 0.05], [0.02, -0.05, 0.9]]).T
    >>> float(patch_influence(X, P, np.ones(24), 18).max()) < 1e-6  # a perfect chart: no drag
    True
    >>> P[3] *= 2.5
    >>> int(np.argmax(patch_influence(X, P, np.ones(24), 18)))
    3
    """
    w = np.asarray(w, dtype=np.float64)
    G, B = normal_equations(X, P, w)
    fitted = X @ (np.linalg.pinv(G, hermitian=True) @ B)
    luminance = fitted @ sample_camera_to_xyz()[1]
    influence = np.zeros(len(w))
    if not np.any((w > 0) & (luminance > 0)):
        return influence
    judges, white_at = _judges(w, white, luminance)
    for start in range(0, len(w), _INFLUENCE_BLOCK):
        i = np.arange(start, min(start + _INFLUENCE_BLOCK, len(w)))
        G_without = G[None] - weighted_outer(w[i], X[i], X[i])
        B_without = B[None] - weighted_outer(w[i], X[i], P[i])
        without = X[judges][None] @ (np.linalg.pinv(G_without, hermitian=True) @ B_without)
        de = patch_delta_e(
            without, fitted[judges], white_patch=white_at, weights=w[judges]
        )  # (block, judges)
        others = (w[judges][None, :] > 0) & (judges[None, :] != i[:, None])
        drag = np.where(others, de, 0.0).sum(axis=1) / np.maximum(others.sum(axis=1), 1)
        influence[i] = np.where(w[i] > 0, drag, 0.0)
    return influence


def pair_residuals(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, scale: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(n - 1,) each reading-order neighbour pair's held-out residuals as read and exchanged.

    For the pair (j, j + 1) of fitted patches, least squares is fitted without both (a rank-two
    downdate of the 3x3 normal equations, batched) and predicts both from the rest. ``as_read``
    is ``|pred_j - P_j| + |pred_k - P_k|``, ``exchanged`` is ``|pred_j - P_k| + |pred_k - P_j|``
    (Euclidean norms of the white-relative residuals, ``scale``: :func:`ocio_vp.metrics.
    white_scale`); both NaN for a pair with an unfitted patch. A swapped lit-chart row gives the
    same pair (exchanging the rows exchanges the predictions).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(0.05, 1.0, (24, 3)); X[18] = 1.0
    >>> P = X @ np.array([[1.1, -0.1, 0.0], [0.0, 1.0, 0.05], [0.02, -0.05, 0.9]]).T
    >>> P[[7, 8]] = P[[8, 7]]
    >>> as_read, exchanged = pair_residuals(X, P, np.ones(24), np.ones(3))
    >>> int(np.argmax(as_read - exchanged)), float(exchanged[7]) < 1e-9
    (7, True)
    """
    w = np.asarray(w, dtype=np.float64)
    j = np.arange(len(w) - 1)
    k = j + 1
    G, B = normal_equations(X, P, w)
    G_without = G[None] - weighted_outer(w[j], X[j], X[j]) - weighted_outer(w[k], X[k], X[k])
    B_without = B[None] - weighted_outer(w[j], X[j], P[j]) - weighted_outer(w[k], X[k], P[k])
    Qt = np.linalg.pinv(G_without, hermitian=True) @ B_without  # (n - 1, 3, 3)
    pred_j = np.einsum("pc,pcd->pd", X[j], Qt) / scale
    pred_k = np.einsum("pc,pcd->pd", X[k], Qt) / scale
    Pj, Pk = P[j] / scale, P[k] / scale

    def norm(a):
        return np.linalg.norm(a, axis=1)

    as_read = norm(pred_j - Pj) + norm(pred_k - Pk)
    exchanged = norm(pred_j - Pk) + norm(pred_k - Pj)
    both = (w[j] > 0) & (w[k] > 0)
    return np.where(both, as_read, np.nan), np.where(both, exchanged, np.nan)


def deletion_gain(X: np.ndarray, P: np.ndarray, w: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """(n,) how much more consistent the rest of the chart is without each fitted patch.

    ``cost[j]`` is the root mean square, over the other fitted patches k (weighted by ``w``),
    of k's held-out least-squares residual (relative to white, ``scale``) with j removed too.
    The gain is the median of ``cost`` divided by ``cost[j]``: about 1 for every patch of a
    consistent chart, well above 1 for the patch whose removal leaves the rest consistent (0
    for unfitted patches). Closed form (rank-one downdates); on a chart of more than
    :data:`INFLUENCE_JUDGES` fitted patches the mean is over that many, spread evenly.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.uniform(0.05, 1.0, (24, 3))
    >>> P = X @ np.array([[1.1, -0.1, 0.0], [0.0, 1.0, 0.05], [0.02, -0.05, 0.9]]).T
    >>> P *= 1 + 0.01 * rng.standard_normal(P.shape)
    >>> P[5] *= 2.5
    >>> gain = deletion_gain(X, P, np.ones(24), np.ones(3))
    >>> int(np.argmax(gain)), bool(gain[5] > 3), bool(np.all(np.delete(gain, 5) < 1.5))
    (5, True, True)
    """
    w = np.asarray(w, dtype=np.float64)
    G, B = normal_equations(X, P, w)
    active = np.flatnonzero(w > 0)
    judges = _spread(active)
    Xk, Pk, wk = X[judges], P[judges] / scale, w[judges]
    cost = np.zeros(len(w))
    for start in range(0, len(active), _INFLUENCE_BLOCK):
        j = active[start : start + _INFLUENCE_BLOCK]
        inverse = np.linalg.pinv(G[None] - weighted_outer(w[j], X[j], X[j]), hermitian=True)
        Qt = inverse @ (B[None] - weighted_outer(w[j], X[j], P[j]))  # (block, 3, 3)
        residual = Pk[None] - (Xk[None] @ Qt) / scale  # (block, judges, 3)
        leverage = wk[None] * np.einsum("kc,bcd,kd->bk", Xk, inverse, Xk)
        held = residual / np.maximum(1.0 - leverage, 1e-12)[..., None]
        others = np.where(judges[None, :] != j[:, None], wk[None, :], 0.0)
        mean = (others * np.sum(held**2, axis=2)).sum(axis=1) / np.maximum(
            others.sum(axis=1), 1e-300
        )
        cost[j] = np.sqrt(mean)
    typical = float(np.median(cost[active])) if len(active) else 0.0
    gain = np.divide(typical, cost, out=np.ones(len(w)), where=cost > 0)
    return np.where(w > 0, gain, 0.0)


def patch_scores(
    X: np.ndarray,
    P: np.ndarray,
    w: np.ndarray,
    white: int,
    narrow: bool | None = None,
    pair_scale: np.ndarray | None = None,
) -> dict:
    """Per patch: ``relative`` and white-relative ``residual`` of the held-out least-squares
    prediction (``relative``: under broadband light the smaller of its miss and the held-out
    root-polynomial's), its robust ``z`` score, its ``influence`` (:func:`patch_influence`), its
    ``deletion`` gain (:func:`deletion_gain`) and
    ``score`` (> 1: inconsistent; 0 for excluded). Per reading-order neighbour pair (j, j + 1):
    ``as_read`` and ``exchanged`` (:func:`pair_residuals`, on the robust weights) and ``swap``
    (> 1: swapped; 0 for a pair with an excluded patch), relative to ``pair_scale`` (default:
    this chart's white, :func:`ocio_vp.metrics.white_scale`). ``narrow``: the light's kind
    (:func:`is_narrow`), computed from the chart when not given."""
    scale = white_scale(P, white, w)
    robust = _robust_weights(X, P, w, scale)
    held = loo_predictions("least-squares", X, P, robust, white)
    residual = (held - P) / scale
    active = w > 0
    # A held-out residual's spread grows as 1 / sqrt(1 - leverage): a patch of a colour few
    # others share is predicted less surely, so its residual is scaled back before comparing.
    G = np.einsum("j,jc,jd->cd", robust, X, X)
    leverage = robust * np.einsum("jc,cd,jd->j", X, np.linalg.pinv(G, hermitian=True), X)
    size = np.linalg.norm(residual, axis=1) * np.sqrt(np.clip(1.0 - leverage, 0.0, 1.0))
    spread = max(_robust_sd(size[active]), 1e-12)
    z = size / spread
    relative = _relative_miss(held, P)
    narrow = is_narrow(X, P, w) if narrow is None else narrow
    if not narrow and np.count_nonzero(active) > _MIN_REMAINING:
        # A colour the 3x3 cannot model (a saturated red under a narrow red LED) is not a
        # defect: the default's root-polynomial predicts it, while a defect is missed by both.
        rich = loo_predictions("root-polynomial", X, P, robust, white)
        relative = np.minimum(relative, _relative_miss(rich, P))
    limit = OUTLIER_RELATIVE_NARROW if narrow else OUTLIER_RELATIVE
    influence = patch_influence(X, P, w, white)
    as_read, exchanged = pair_residuals(X, P, robust, scale if pair_scale is None else pair_scale)
    # A patch drags the fit when its influence is large in ΔE2000, stands out from the chart's
    # others (on a chart the model does not fit at all every patch is influential) and the
    # others do not predict it (a clean white can drag an ill-determined sodium fit).
    typical = max(_robust_sd(influence[active]), 1e-12)
    drag = np.minimum(influence / OUTLIER_INFLUENCE, influence / typical / OUTLIER_Z)
    drag = np.minimum(drag, relative / OUTLIER_RELATIVE)
    # A patch explains the chart's inconsistency when the rest is far more consistent without
    # it, and it is itself clearly off (a bright clean patch can carry much of the chart's
    # noise in units of white, while predicted within a few percent of itself).
    deletion = deletion_gain(X, P, w, scale)
    explains = np.minimum(
        deletion / DELETION_GAIN, relative / (OUTLIER_RELATIVE if narrow else EXPLAINS_RELATIVE)
    )
    off = active & (np.max(np.abs(residual), axis=1) > OUTLIER_FLOOR)
    misses = np.where(off, np.minimum(relative / limit, z / OUTLIER_Z), 0.0)
    suspect = np.maximum(misses, np.where(off, drag, 0.0))
    explains = np.where(off, explains, 0.0)
    score = np.maximum(suspect, explains)
    return {
        "score": score,
        "misses": misses,
        "suspect": suspect,
        "explains": explains,
        "relative": relative,
        "z": z,
        "influence": influence,
        "deletion": deletion,
        "residual": residual,
        "limit": limit,
        "as_read": as_read,
        "exchanged": exchanged,
        "swap": _swap_scores(as_read, exchanged),
    }


def _relative_miss(held: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``|held - P| / max(|held|, |P|)`` per patch (0 for black predicted as black)."""
    magnitude = np.maximum(np.linalg.norm(held, axis=1), np.linalg.norm(P, axis=1))
    return np.linalg.norm(held - P, axis=1) / np.where(magnitude > 0, magnitude, 1.0)


def _swap_scores(as_read: np.ndarray, exchanged: np.ndarray) -> np.ndarray:
    """(n - 1,) > 1 for a pair that looks swapped (0 for a pair with an unfitted patch)."""
    fitted = np.isfinite(as_read)
    typical = _robust_sd(as_read[fitted]) if fitted.any() else 0.0
    score = np.minimum(
        np.minimum(
            as_read / np.maximum(exchanged, 1e-12) / SWAP_RATIO, (as_read - exchanged) / SWAP_FLOOR
        ),
        as_read / max(SWAP_Z * typical, 1e-12),
    )
    return np.where(fitted, score, 0.0)


def _next_patch(scores: dict, first: np.ndarray, after_exclusion: bool) -> int | None:
    """The patch to exclude next, or None."""
    score = scores["score"]
    if after_exclusion:  # stronger evidence needed (LATER_INFLUENCE, LATER_RELATIVE)
        visible = scores["influence"] >= LATER_INFLUENCE
        wrong = scores["relative"] >= min(LATER_RELATIVE * scores["limit"], OUTLIER_RELATIVE_NARROW)
        supported = (first >= FIRST_PASS_SUPPORT) & (visible | wrong)
        score = score / np.where(supported, 1.0, UNSUPPORTED_SCORE)
    j = int(np.argmax(score))
    return j if score[j] > 1.0 else None


def _rival(scores: dict, j: int) -> int | None:
    """A patch the data cannot tell from ``j`` as the bad one, or None.

    When ``j`` is excluded on soft evidence only (it drags the fit or its removal explains the
    chart, while its own prediction does not mark it as wrong), another patch that looked
    suspect too (:data:`FIRST_PASS_SUPPORT`) and whose removal leaves the rest at least as
    consistent (:func:`deletion_gain`) is as likely the bad one.
    """
    if scores["misses"][j] > 1.0:
        return None
    score, deletion = scores["score"], scores["deletion"]
    rivals = (score >= FIRST_PASS_SUPPORT) & (score <= 1.0) & (deletion >= deletion[j])
    rivals[j] = False
    return int(np.argmax(np.where(rivals, deletion, 0.0))) if rivals.any() else None


def _ambiguous(scores: dict, j: int, k: int, n: int) -> list[Inconsistency]:
    """Both patches of an ambiguous pair, each naming the other."""
    return [
        _inconsistency(
            scores,
            a,
            n,
            ambiguous_with=b,
            ambiguous_name=patch_name(b, n),
            ambiguous_deletion=float(scores["deletion"][b]),
        )
        for a, b in ((j, k), (k, j))
    ]


def _rgb(values: np.ndarray) -> tuple[float, float, float]:
    r, g, b = (float(v) for v in values)
    return r, g, b


def _inconsistency(scores: dict, j: int, n: int, **swap) -> Inconsistency:
    return Inconsistency(
        j,
        patch_name(j, n),
        float(scores["relative"][j]),
        float(scores["z"][j]),
        float(scores["influence"][j]),
        _rgb(scores["residual"][j]),
        **swap,
        deletion=float(scores["deletion"][j]),
    )


def _swapped(scores: dict, j: int, n: int) -> list[Inconsistency]:
    """Both patches of the swapped pair (j, j + 1), each naming the other."""
    residuals = (float(scores["as_read"][j]), float(scores["exchanged"][j]))
    return [
        _inconsistency(
            scores, a, n, swapped_with=b, swapped_name=patch_name(b, n), swap_residuals=residuals
        )
        for a, b in ((j, j + 1), (j + 1, j))
    ]


def inconsistent_patches(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int
) -> list[Inconsistency]:
    """Patches of the chart (lit ``X``, target ``P``, weights ``w``) inconsistent with the rest.

    See the module docstring. Returns them worst first, or ``[]``.

    Raises
    ------
    InputError
        When more than :data:`MAX_EXCLUDED_FRACTION` of the chart, or more than
        :data:`MAX_EXCLUDED` patches, are inconsistent (the chart cannot be trusted; nothing is
        guessed).
    """
    w = np.asarray(w, dtype=np.float64).copy()
    n = len(P)
    limit = max(1, min(int(MAX_EXCLUDED_FRACTION * np.count_nonzero(w > 0)), MAX_EXCLUDED))
    narrow = is_narrow(X, P, w)  # the light's kind does not change when a patch is excluded
    # Nor does the white pairs are judged against: once the white patch itself is excluded the
    # fallback scale (the chart's mean) would make every pair's residuals look several-fold.
    pair_scale = white_scale(P, white, w)
    found: list[Inconsistency] = []
    first = None
    while np.count_nonzero(w > 0) > _MIN_REMAINING:
        scores = patch_scores(X, P, w, white, narrow, pair_scale)
        first = scores["score"] if first is None else first
        pair = int(np.argmax(scores["swap"])) if n > 1 else 0
        if n > 1 and scores["swap"][pair] > 1.0:
            found += _swapped(scores, pair, n)
        else:
            j = _next_patch(scores, first, bool(found))
            if j is None:
                break
            k = _rival(scores, j)
            found += [_inconsistency(scores, j, n)] if k is None else _ambiguous(scores, j, k, n)
        w[[f.index for f in found]] = 0.0
        if len(found) > limit:
            names = ", ".join(f.name for f in found[:6]) + (", ..." if len(found) > 6 else "")
            raise InputError(
                f"{len(found)} or more chart patches are inconsistent with the rest, too many "
                "to exclude safely (check the sampling boxes, flare and the patch order, or "
                f"solve with --keep-all-patches): {names}",
                key="target_chart",
            )
    return found
