"""Finding the wall in a take: the largest rectangle of pixels that change with the patterns.

The patterns switch the wall between black and white while the set stays, so: :data:`SAMPLES`
frames block-averaged to at most :data:`GRID` cells wide; per cell the range of R + G + B over
them; the largest connected part above half its 99th percentile; its largest axis-aligned
rectangle, shrunk by :data:`INSET` and one cell on each side (no edge, bezel or blur of it).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.reader import PlateInfo, block_means

__all__ = ["GRID", "INSET", "SAMPLES", "find_wall", "largest_rectangle", "wall_mask"]

#: Frames read whole to find the wall.
SAMPLES = 16
#: Block-averaged width (and height limit) the search works at.
GRID = 256
#: Fraction of the found rectangle's width and height left out on each side.
INSET = 0.05
#: The wall must be at least this many pixels each way once found.
MIN_SIZE = 8


def wall_mask(stack: np.ndarray) -> np.ndarray:
    """(h, w) bool: the largest connected set of cells whose R + G + B range over the frames
    ``stack`` (k, h, w, 3) exceeds half its 99th percentile."""
    from scipy import ndimage

    level = stack.sum(axis=-1)
    spread = level.max(axis=0) - level.min(axis=0)
    top = float(np.percentile(spread, 99))
    if not top > 0:
        return np.zeros(spread.shape, dtype=bool)
    labels, count = ndimage.label(spread > 0.5 * top)
    if count == 0:
        return np.zeros(spread.shape, dtype=bool)
    sizes = np.bincount(labels.ravel())[1:]
    return labels == 1 + int(np.argmax(sizes))


def largest_rectangle(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1), end-exclusive, of the largest all-True axis-aligned rectangle.

    Examples
    --------
    >>> m = np.zeros((5, 6), bool); m[1:4, 2:6] = True; m[0, 0] = True
    >>> largest_rectangle(m)
    (2, 1, 6, 4)
    """
    height, width = mask.shape
    heights = np.zeros(width, dtype=np.int64)
    best, area = None, 0
    for y in range(height):
        heights = np.where(mask[y], heights + 1, 0)
        stack: list[int] = []
        for x in range(width + 1):
            h = int(heights[x]) if x < width else 0
            while stack and heights[stack[-1]] >= h:
                top = stack.pop()
                left = stack[-1] + 1 if stack else 0
                size = int(heights[top]) * (x - left)
                if size > area:
                    area = size
                    best = (left, y - int(heights[top]) + 1, x, y + 1)
            stack.append(x)
    return best


def find_wall(
    paths: Sequence[Path],
    info: PlateInfo,
    *,
    source: object = None,
    frames: tuple[int, Callable[[int, int], np.ndarray]] | None = None,
) -> tuple[int, int, int, int]:
    """The wall's region ``(x0, y0, x1, y1)`` in pixels (see the module docstring).

    ``frames``: for a take that is not one file a frame (a movie), its frame count and a
    function giving frame ``k`` already reduced, ``reduced(k, factor)`` (cells_y, cells_x,
    3); ``paths`` is then not read.

    Raises
    ------
    InputError
        When no part of the picture changes, or the part that does is too small.
    """
    factor = max(1, -(-max(info.width, info.height) // GRID))
    count = len(paths) if frames is None else frames[0]
    picks = np.unique(np.linspace(0, count - 1, min(SAMPLES, count)).round().astype(int))
    reduced = []
    for k in picks:
        if frames is not None:
            # block_means's rule: a decoding's NaN/+-Inf (a pure power below black) counts as 0
            cells = np.asarray(frames[1](int(k), factor), dtype=np.float64)
            reduced.append(np.nan_to_num(cells, posinf=0.0, neginf=0.0))
            continue
        frame_info = info if k == 0 else dataclasses.replace(info, path=str(paths[k]))
        reduced.append(block_means(frame_info, factor))
    mask = wall_mask(np.stack(reduced))
    rect = largest_rectangle(mask)
    hint = "give the take's region: [x0, y0, x1, y1] in the capture file"
    if rect is None:
        raise InputError(
            f"no part of the picture changes over the take: no wall found; {hint}", source=source
        )
    x0, y0, x1, y1 = rect
    dx, dy = INSET * (x1 - x0), INSET * (y1 - y0)
    cx0, cy0 = int(np.ceil(x0 + dx)) + 1, int(np.ceil(y0 + dy)) + 1
    cx1, cy1 = int(np.floor(x1 - dx)) - 1, int(np.floor(y1 - dy)) - 1
    region = (
        info.x + cx0 * factor,
        info.y + cy0 * factor,
        info.x + cx1 * factor,
        info.y + cy1 * factor,
    )
    if region[2] - region[0] < MIN_SIZE or region[3] - region[1] < MIN_SIZE:
        raise InputError(
            f"the wall found is too small ({max(0, region[2] - region[0])}x"
            f"{max(0, region[3] - region[1])} pixels); {hint}",
            source=source,
        )
    return region
