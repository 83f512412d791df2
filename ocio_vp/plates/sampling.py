"""Sample a colour chart (and plain regions) from a plate: perspective-correct patch grid, robust
statistics (:mod:`ocio_vp.plates.statistics`), flags; docs/capture.md, *Coordinates*.

A homography maps grid coordinates ``(u, v)`` in ``[0, columns] x [0, rows]`` onto the corners;
a pixel belongs to patch ``(r, c)`` when its centre's grid coordinates fall in
``[c + inset, c + 1 - inset] x [r + inset, r + 1 - inset]``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.frames import data_window, flat_field_gain, frames_pixels
from ocio_vp.plates.statistics import ROBUST_MEAN_METHODS, patch_statistics

__all__ = [
    "ROBUST_MEAN_METHODS",
    "ChartSamples",
    "apply_homography",
    "chart_box",
    "grid_homography",
    "patch_labels",
    "sample_chart",
    "sample_region",
]

Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class ChartSamples:
    """Per-patch statistics of a sampled chart (or of regions, one row each).

    Attributes
    ----------
    means : (n, 3) robust mean linear RGB per patch (``method``).
    spreads : (n, 3) standard deviation of the pixels the mean used (outliers rejected), so
        ``spreads / sqrt(counts)`` estimates the standard error of a mean from noise.
    counts : (n,) number of pixels the mean used per patch (sampled minus outliers).
    clipped_fraction : (n,) fraction of pixels with a channel at or above the clip level.
    outlier_fraction : (n,) fraction of pixels farther than ``outlier_sigma`` robust sigmas
        from the patch median.
    clipped, high_spread : (n,) flags. ``high_spread`` means too many outliers or a spread
        above ``max_spread`` of the chart's brightest patch.
    box : the (x0, y0, x1, y1) image region that was read.
    frames : how many frames were averaged (pixel by pixel, before the statistics).
    """

    means: np.ndarray
    spreads: np.ndarray
    counts: np.ndarray
    clipped_fraction: np.ndarray
    outlier_fraction: np.ndarray
    clipped: np.ndarray
    high_spread: np.ndarray
    box: Box
    method: str
    frames: int = 1
    clip_level: tuple[float, float, float] | None = None

    @property
    def flagged(self) -> np.ndarray:
        """(n,) patches with any flag."""
        return self.clipped | self.high_spread

    def flag_names(self, index: int) -> list[str]:
        """The flags of patch ``index`` as words (for messages)."""
        names = []
        if self.clipped[index]:
            names.append(f"clipped ({100 * self.clipped_fraction[index]:.1f}% of pixels)")
        if self.high_spread[index]:
            names.append(f"high spread ({100 * self.outlier_fraction[index]:.1f}% outliers)")
        return names


# --------------------------------------------------------------------------------------------
# Geometry.


def _check_corners(corners: object, source: object) -> np.ndarray:
    c = np.asarray(corners, dtype=np.float64)
    if c.shape != (4, 2) or not np.all(np.isfinite(c)):
        raise InputError(
            f"expected 4 corners [[x, y], ...] (TL, TR, BR, BL), got shape {c.shape}",
            source=source,
            key="corners",
        )
    # Cross products of consecutive edges: all the same sign for a convex quadrilateral.
    edges = np.roll(c, -1, axis=0) - c
    following = np.roll(edges, -1, axis=0)
    cross = edges[:, 0] * following[:, 1] - edges[:, 1] * following[:, 0]
    if not (np.all(cross > 0) or np.all(cross < 0)):
        raise InputError(
            "corners do not form a convex quadrilateral in the order TL, TR, BR, BL",
            source=source,
            key="corners",
        )
    return c


def grid_homography(corners: np.ndarray, rows: int, columns: int) -> np.ndarray:
    """The 3x3 homography ``H`` with ``H (u, v, 1)`` ~ ``(x, y, 1)``.

    Maps grid coordinates (``u`` across ``columns``, ``v`` down ``rows``) to pixel coordinates,
    from the four correspondences (0,0)->TL, (C,0)->TR, (C,R)->BR, (0,R)->BL (direct linear
    transform with h33 = 1, exact for four points).
    """
    src = np.array([[0, 0], [columns, 0], [columns, rows], [0, rows]], dtype=np.float64)
    dst = np.asarray(corners, dtype=np.float64)
    A = np.zeros((8, 8))
    b = np.zeros(8)
    for i, ((u, v), (x, y)) in enumerate(zip(src, dst, strict=True)):
        A[2 * i] = [u, v, 1, 0, 0, 0, -u * x, -v * x]
        A[2 * i + 1] = [0, 0, 0, u, v, 1, -u * y, -v * y]
        b[2 * i], b[2 * i + 1] = x, y
    h = np.linalg.solve(A, b)
    return np.append(h, 1.0).reshape(3, 3)


def apply_homography(H: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points (..., 2) mapped by the 3x3 homography ``H`` (column vectors, divided by w)."""
    p = points @ H[:, :2].T + H[:, 2]
    return p[..., :2] / p[..., 2:3]


def chart_box(corners: np.ndarray, *, margin: int = 0) -> Box:
    """Integer pixel box (x0, y0, x1, y1) covering the corners, grown by ``margin``."""
    c = np.asarray(corners, dtype=np.float64)
    x0, y0 = np.floor(c.min(axis=0)).astype(int) - margin
    x1, y1 = np.ceil(c.max(axis=0)).astype(int) + margin
    return (int(x0), int(y0), int(x1), int(y1))


def patch_labels(
    corners: np.ndarray, rows: int, columns: int, *, inset: float, box: Box
) -> np.ndarray:
    """(h, w) int32 map over ``box``: the patch index of each sampled pixel, -1 elsewhere.

    This is *the* definition of which pixels are sampled; overlays draw this very map.
    """
    H = grid_homography(corners, rows, columns)
    Hinv = np.linalg.inv(H)
    x0, y0, x1, y1 = box
    labels = np.full((y1 - y0, x1 - x0), -1, dtype=np.int32)
    cell = np.array(
        [[inset, inset], [1 - inset, inset], [1 - inset, 1 - inset], [inset, 1 - inset]]
    )
    for r in range(rows):
        for c in range(columns):
            quad = apply_homography(H, cell + np.array([c, r], dtype=np.float64))
            qx0, qy0, qx1, qy1 = chart_box(quad, margin=1)
            qx0, qy0 = max(qx0, x0), max(qy0, y0)
            qx1, qy1 = min(qx1, x1), min(qy1, y1)
            if qx1 <= qx0 or qy1 <= qy0:
                continue
            ys, xs = np.mgrid[qy0:qy1, qx0:qx1]
            centres = np.stack([xs + 0.5, ys + 0.5], axis=-1).astype(np.float64)
            uv = apply_homography(Hinv, centres) - [c, r]
            inside = np.all((uv >= inset) & (uv <= 1 - inset), axis=-1)
            view = labels[qy0 - y0 : qy1 - y0, qx0 - x0 : qx1 - x0]
            view[inside] = r * columns + c
    return labels


def sample_chart(
    image: object,
    corners: object,
    rows: int = 4,
    columns: int = 6,
    *,
    inset: float = 0.25,
    method: str = "trimmed",
    trim: float = 0.1,
    clip_level: float | None = None,
    encoding: str | None = None,
    outlier_sigma: float = 6.0,
    max_outlier_fraction: float = 0.005,
    max_spread: float = 0.05,
    min_pixels: int = 16,
    flat_field: object = None,
    source: object = None,
) -> ChartSamples:
    """Sample every patch of a chart photographed in perspective, in reading order.

    The camera RGB the paper samples from its calibration photographs (the lit-chart columns of
    [SRL]_j, eq. 3; the target chart p_j, eq. 5), with :mod:`ocio_vp.plates.statistics`.

    Parameters
    ----------
    image, encoding
        A plate path, a :class:`~ocio_vp.plates.reader.PlateInfo`, an (h, w, >=3) array, or a
        list of them (frames, averaged pixel by pixel); their encoding if display-referred.
    corners, rows, columns, inset
        (4, 2) pixel corners of the patch grid (TL, TR, BR, BL); the grid (a ColorChecker 24 is
        4 x 6); the margin of each patch left unsampled (a fraction, 0-0.45).
    method, trim, clip_level
        A :data:`ROBUST_MEAN_METHODS` name (``"trimmed"`` trims ``trim`` per side); the level
        of a clipped pixel (default 1.0 for integer plates, a detected flat top for float).
    outlier_sigma, max_outlier_fraction, max_spread, min_pixels
        An outlier is over ``outlier_sigma`` robust sigmas (1.4826 MAD) from its patch median;
        ``high_spread``: over ``max_outlier_fraction`` outliers, or a standard deviation over
        ``max_spread`` x the brightest patch mean. Under ``min_pixels`` pixels is an error.
    flat_field
        Flat-field plate(s) (forms of ``image``) dividing out vignetting
        (:func:`ocio_vp.plates.frames.flat_field_gain`); clipping is judged before the division.

    Raises
    ------
    InputError
        Unreadable plate, corners not convex or outside the image, too few pixels in a patch,
        or most patches clipped.

    Examples
    --------
    >>> img = np.zeros((40, 60, 3), np.float32); img[:20, :30] = 0.5
    >>> s = sample_chart(img, [[0, 0], [60, 0], [60, 40], [0, 40]], 2, 2, clip_level=1.0)
    >>> s.means[:, 0].tolist()
    [0.5, 0.0, 0.0, 0.0]
    """
    _check_grid(rows, columns, inset, source)
    frames, where = _frames_and_source(image, source)
    c = _check_corners(corners, where)
    box = _sampling_box(c)
    pixels, is_float, n_frames = frames_pixels(
        frames, box, encoding=encoding, source=source, what="chart corners' box"
    )
    labels = patch_labels(c, rows, columns, inset=inset, box=box)
    gain = None if flat_field is None else _gain(flat_field, box, encoding, frames[0], where)
    raw_groups, groups = _patch_pixels(pixels, labels, rows * columns, gain)
    _check_patch_sizes(groups, min_pixels, where)
    stats = patch_statistics(
        groups,
        method=method,
        trim=trim,
        clip_level=clip_level,
        is_float=is_float,
        outlier_sigma=outlier_sigma,
        max_outlier_fraction=max_outlier_fraction,
        max_spread=max_spread,
        raw_groups=raw_groups,
    )
    _check_not_mostly_clipped(stats["clipped_fraction"], rows * columns, where)
    return ChartSamples(box=box, method=method, frames=n_frames, **stats)  # type: ignore[arg-type]


def _sampling_box(corners: np.ndarray) -> Box:
    """The corners' pixel box, at least one pixel wide and high."""
    box = chart_box(corners)
    return (box[0], box[1], max(box[2], box[0] + 1), max(box[3], box[1] + 1))


def _check_grid(rows: int, columns: int, inset: float, source: object) -> None:
    if isinstance(rows, bool) or int(rows) < 1 or isinstance(columns, bool) or int(columns) < 1:
        raise InputError(f"rows and columns must be >= 1, got {rows} x {columns}", source=source)
    if not 0 <= inset <= 0.45:
        raise InputError(f"inset must be in [0, 0.45], got {inset!r}", source=source, key="inset")


def _frames_and_source(image: object, source: object) -> tuple[list, object]:
    """The frames to average, and what messages name (``source``, else the first path)."""
    frames = list(image) if isinstance(image, (list, tuple)) else [image]
    where = source or (str(frames[0]) if isinstance(frames[0], (str, os.PathLike)) else None)
    return frames, where


def _gain(flat_field: object, box: Box, encoding: str | None, frame: object, where: object):
    """The flat field's gain over ``box`` of a plate like ``frame``."""
    plate_box = data_window(frame, encoding)
    return flat_field_gain(flat_field, box, encoding=encoding, plate_box=plate_box, source=where)


def _patch_pixels(
    pixels: np.ndarray, labels: np.ndarray, n: int, gain: np.ndarray | None
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each patch's (k, 3) pixels in raster order: as read, and divided by ``gain`` if any."""
    order = np.argsort(labels.ravel(), kind="stable")
    starts = np.searchsorted(labels.ravel()[order], np.arange(n + 1))

    def split(values: np.ndarray) -> list[np.ndarray]:
        values = values.reshape(-1, 3)
        return [values[order[starts[j] : starts[j + 1]]] for j in range(n)]

    raw = split(pixels)
    return raw, (raw if gain is None else split(pixels / gain))


def _check_patch_sizes(groups: list[np.ndarray], min_pixels: int, where: object) -> None:
    small = [j for j, g in enumerate(groups) if len(g) < min_pixels]
    if small:
        raise InputError(
            f"patch {small[0]} has {len(groups[small[0]])} pixels (< {min_pixels}): the chart is "
            "too small in the image or the inset too large",
            source=where,
            key="corners",
        )


def _check_not_mostly_clipped(clipped_fraction: object, n: int, where: object) -> None:
    mostly = np.asarray(clipped_fraction) > 0.5
    if np.count_nonzero(mostly) * 2 >= n:
        raise InputError(
            f"{np.count_nonzero(mostly)} of {n} patches are clipped: expose lower and reshoot",
            source=where,
        )


def sample_region(
    image: object,
    box: Sequence[int],
    *,
    method: str = "trimmed",
    trim: float = 0.1,
    clip_level: float | None = None,
    encoding: str | None = None,
    outlier_sigma: float = 6.0,
    max_outlier_fraction: float = 0.005,
    max_spread: float = 0.05,
    flat_field: object = None,
    source: object = None,
) -> ChartSamples:
    """Sample one rectangle ``(x0, y0, x1, y1)`` (end-exclusive) of a plate.

    Used for the primaries (the columns of [SL], paper Section 3.3) and the black level
    b_camera (Section 3.4). Same statistics and flags as :func:`sample_chart`, one row.
    """
    values = [int(v) for v in box]
    if len(values) != 4:
        raise InputError(f"expected a region [x0, y0, x1, y1], got {list(box)}", source=source)
    b: Box = (values[0], values[1], values[2], values[3])
    frames, where = _frames_and_source(image, source)
    pixels, is_float, n_frames = frames_pixels(
        frames, b, encoding=encoding, source=where, what="region"
    )
    gain = None if flat_field is None else _gain(flat_field, b, encoding, frames[0], where)
    raw, corrected = _patch_pixels(pixels, np.zeros(pixels.shape[:2], np.int32), 1, gain)
    stats = patch_statistics(
        corrected,
        method=method,
        trim=trim,
        clip_level=clip_level,
        is_float=is_float,
        outlier_sigma=outlier_sigma,
        max_outlier_fraction=max_outlier_fraction,
        max_spread=np.inf,  # a region has no brightest patch to compare with
        raw_groups=raw,
    )
    return ChartSamples(box=b, method=method, frames=n_frames, **stats)  # type: ignore[arg-type]
