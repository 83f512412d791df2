"""Per-patch statistics: robust means (:data:`ROBUST_MEAN_METHODS`, after rejecting outliers),
spreads, clip levels and flags, for :mod:`ocio_vp.plates.sampling`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["ROBUST_MEAN_METHODS", "clip_levels", "patch_statistics"]

# --------------------------------------------------------------------------------------------
# Robust means: (k, 3) pixels -> (3,).


def _trimmed_mean(pixels: np.ndarray, *, trim: float) -> np.ndarray:
    from scipy.stats import trim_mean

    return np.asarray(trim_mean(pixels, trim, axis=0), dtype=np.float64)


def _median_of_means(pixels: np.ndarray, *, trim: float) -> np.ndarray:
    # 9 interleaved groups (raster order) so each group spans the whole patch.
    groups = [pixels[i::9] for i in range(min(9, len(pixels)))]
    return np.median(np.stack([g.mean(axis=0) for g in groups]), axis=0)


def _median(pixels: np.ndarray, *, trim: float) -> np.ndarray:
    return np.median(pixels, axis=0)


def _mean(pixels: np.ndarray, *, trim: float) -> np.ndarray:
    return pixels.mean(axis=0)


#: ``method=`` of :func:`ocio_vp.plates.sampling.sample_chart`: how a patch's pixels become one RGB value.
#: ``"trimmed"`` (default) drops the lowest and highest ``trim`` fraction of each channel
#: and averages the rest; ``"median-of-means"`` is the median of 9 interleaved group means.
#: All but ``"mean"`` (plain, for comparison) first drop the patch's outlier pixels.
ROBUST_MEAN_METHODS: dict[str, Callable[..., np.ndarray]] = {
    "trimmed": _trimmed_mean,
    "median-of-means": _median_of_means,
    "median": _median,
    "mean": _mean,
}


def clip_levels(pixels: np.ndarray, clip_level: float | None, is_float: bool) -> np.ndarray:
    """Per-channel clip level: given, 1.0 for integer plates, or a detected plateau for float.

    A float plate has no fixed clip level, but a clipped sensor gives a flat top: the channel's
    maximum shared by at least 0.1 % (and 4) of the sampled pixels. Noise-free synthetic images
    look clipped at their brightest value by this test; pass ``clip_level`` to avoid it.
    """
    if clip_level is not None:
        return np.full(3, float(clip_level))
    if not is_float:
        return np.full(3, 1.0 - 1e-6)
    levels = np.full(3, np.inf)
    if len(pixels) == 0:
        return levels
    top = pixels.max(axis=0)
    for k in range(3):
        at_top = np.count_nonzero(pixels[:, k] >= top[k] - 1e-6 * abs(top[k]))
        if top[k] > 0 and at_top >= max(4, 1e-3 * len(pixels)):
            levels[k] = top[k] * (1 - 1e-6)
    return levels


def patch_statistics(
    groups: Sequence[np.ndarray],
    *,
    method: str,
    trim: float,
    clip_level: float | None,
    is_float: bool,
    outlier_sigma: float,
    max_outlier_fraction: float,
    max_spread: float,
    raw_groups: Sequence[np.ndarray] | None = None,
) -> dict[str, np.ndarray | tuple[float, float, float] | None]:
    """Statistics of each pixel group (one (k, 3) array per patch or region).

    ``raw_groups`` are the same pixels before a flat-field division: clipping is a property of
    the sensor's values, so it is judged on those when given.

    Returns the fields of :class:`ocio_vp.plates.sampling.ChartSamples` as a dict; the options
    are documented on :func:`ocio_vp.plates.sampling.sample_chart`.
    """
    if method not in ROBUST_MEAN_METHODS:
        valid = ", ".join(ROBUST_MEAN_METHODS)
        raise ValueError(f"unknown method {method!r}; expected one of: {valid}")
    if not 0 <= trim < 0.5:
        raise ValueError(f"trim must be in [0, 0.5), got {trim!r}")
    robust_mean = ROBUST_MEAN_METHODS[method]
    raw = groups if raw_groups is None else raw_groups
    levels = clip_levels(np.concatenate(raw), clip_level, is_float)
    n = len(groups)
    means, spreads = np.zeros((n, 3)), np.zeros((n, 3))
    counts = np.zeros(n, dtype=np.int64)
    clipped_fraction, outlier_fraction = np.zeros(n), np.zeros(n)
    for j, pixels in enumerate(groups):
        pixels = np.asarray(pixels, dtype=np.float64)
        clipped_fraction[j] = np.mean(np.any(np.asarray(raw[j]) >= levels, axis=1))
        median = np.median(pixels, axis=0)
        sigma = 1.4826 * np.median(np.abs(pixels - median), axis=0)
        # A floor so noise-free or quantised data (sigma 0) does not call every pixel an outlier.
        sigma = np.maximum(sigma, 1e-3 * max(float(np.max(np.abs(median))), 1e-12))
        far = np.any(np.abs(pixels - median) > outlier_sigma * sigma, axis=1)
        outlier_fraction[j] = np.mean(far)
        # Outliers (a glint, dust) go first, so the trim stays symmetric about the noise.
        # ("mean" is the plain, non-robust mean of all pixels, kept for comparison.)
        enough = np.count_nonzero(~far) >= max(2, len(pixels) // 2)
        kept = pixels[~far] if enough and method != "mean" else pixels
        means[j] = robust_mean(kept, trim=trim)
        counts[j] = len(kept)
        spreads[j] = kept.std(axis=0, ddof=1) if len(kept) > 1 else 0.0
    level = max(float(np.max(means)), 1e-12)
    high_spread = (outlier_fraction > max_outlier_fraction) | (
        np.max(spreads, axis=1) > max_spread * level
    )
    finite = tuple(float(v) for v in levels) if np.all(np.isfinite(levels)) else None
    return {
        "means": means,
        "spreads": spreads,
        "counts": counts,
        "clipped_fraction": clipped_fraction,
        "outlier_fraction": outlier_fraction,
        "clipped": clipped_fraction > 0,
        "high_spread": high_spread,
        "clip_level": finite,
    }
