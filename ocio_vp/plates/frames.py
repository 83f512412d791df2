"""Pixels of a box from one plate or several frames (averaged pixel by pixel, float64 over the
box only), and flat-field gains: the lens's vignetting and colour shading (docs/capture.md,
*Vignetting*), which the plate's pixels are divided by.
"""

from __future__ import annotations

import os

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.reader import PlateInfo, check_box, open_plate, read_region

__all__ = ["flat_field_gain", "frames_pixels"]

Box = tuple[int, int, int, int]


def _load_pixels(
    image: object, box: Box, *, encoding: str | None, source: object, what: str
) -> tuple[np.ndarray, bool]:
    """One frame's pixels over ``box`` and whether its samples are floating point."""
    if isinstance(image, (str, os.PathLike, PlateInfo)):
        info = image if isinstance(image, PlateInfo) else open_plate(image, encoding=encoding)
        check_box(info, box, what=what)
        return read_region(info, box), info.is_float or info.encoding != "linear"
    array = np.asarray(image)
    if array.ndim != 3 or array.shape[2] < 3:
        raise InputError(f"expected an (h, w, >=3) image, got shape {array.shape}", source=source)
    x0, y0, x1, y1 = box
    if x0 < 0 or y0 < 0 or x1 > array.shape[1] or y1 > array.shape[0] or x1 <= x0 or y1 <= y0:
        raise InputError(
            f"{what} {list(box)} is outside the image ({array.shape[1]}x{array.shape[0]})",
            source=source,
        )
    return array[y0:y1, x0:x1, :3], not np.issubdtype(array.dtype, np.integer)


def frames_pixels(
    image: object, box: Box, *, encoding: str | None, source: object, what: str
) -> tuple[np.ndarray, bool, int]:
    frames = list(image) if isinstance(image, (list, tuple)) else [image]
    if not frames:
        raise InputError("no frames given", source=source)
    total: np.ndarray | None = None
    is_float = False
    for frame in frames:
        pixels, frame_float = _load_pixels(frame, box, encoding=encoding, source=source, what=what)
        is_float = is_float or frame_float
        if total is None:
            total = pixels.astype(np.float64 if len(frames) > 1 else pixels.dtype, copy=True)
        else:
            total += pixels
    assert total is not None
    if len(frames) > 1:
        total /= len(frames)
    if not is_float and np.issubdtype(total.dtype, np.integer):
        total = total / float(np.iinfo(total.dtype).max)
    return total, is_float, len(frames)


def data_window(frame: object, encoding: str | None) -> Box:
    """A plate's (or an array's) data window ``(x0, y0, x1, y1)``."""
    if isinstance(frame, (str, os.PathLike, PlateInfo)):
        info = frame if isinstance(frame, PlateInfo) else open_plate(frame, encoding=encoding)
        return info.box
    shape = np.shape(np.asarray(frame))
    return (0, 0, int(shape[1]), int(shape[0]))


def flat_field_gain(
    flat: object,
    box: Box,
    *,
    encoding: str | None = None,
    plate_box: Box | None = None,
    source: object = None,
) -> np.ndarray:
    """(h, w, 3) relative gain of the lens over ``box``, 1.0 at the frame's centre.

    ``flat`` is a path, :class:`~ocio_vp.plates.reader.PlateInfo`, array or list of frames (averaged).
    The centre level is the mean over a window 1/20 of the frame's width and height.

    Raises
    ------
    InputError
        A flat of another size than the plate (``plate_box``), or with pixels <= 0 in ``box``.
    """
    frames = list(flat) if isinstance(flat, (list, tuple)) else [flat]
    where = str(frames[0]) if isinstance(frames[0], (str, os.PathLike)) else source
    x0, y0, x1, y1 = data_window(frames[0], encoding)
    if plate_box is not None and (x0, y0, x1, y1) != tuple(plate_box):
        raise InputError(
            f"flat field's data window {[x0, y0, x1, y1]} differs from the plate's "
            f"{list(plate_box)}",
            source=where,
        )
    cw, ch = max(4, (x1 - x0) // 20), max(4, (y1 - y0) // 20)
    cx, cy = (x0 + x1) // 2, (y0 + y1) // 2
    centre_box = (cx - cw // 2, cy - ch // 2, cx - cw // 2 + cw, cy - ch // 2 + ch)
    centre = frames_pixels(frames, centre_box, encoding=encoding, source=where, what="centre")[0]
    level = np.asarray(centre, dtype=np.float64).reshape(-1, 3).mean(axis=0)
    region = frames_pixels(frames, box, encoding=encoding, source=where, what="flat field box")[0]
    gain = np.asarray(region, dtype=np.float64) / np.where(level > 0, level, np.nan)
    if not np.all(gain > 0):  # also catches NaN from a black centre
        raise InputError(
            "flat field has black or negative pixels where the plate is sampled", source=where
        )
    return gain
