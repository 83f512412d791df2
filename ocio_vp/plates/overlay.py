"""Overlay PNGs: the sampled part of a plate (plus a margin) at full resolution, other pixels
dimmed, each patch or region outlined by its state (:data:`OUTLINE_COLOURS`). The label map drawn
is the one the sampling used (:func:`ocio_vp.plates.sampling.patch_labels`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = ["OUTLINE_COLOURS", "overlay_image", "tone_map", "write_png"]

#: Outline colours (8-bit sRGB) by patch state.
OUTLINE_COLOURS = {
    "ok": (40, 220, 60),
    "high_spread": (235, 30, 30),
    "clipped": (250, 220, 0),
}
_DIM = 0.3


def tone_map(pixels: np.ndarray, *, white: float) -> np.ndarray:
    """Linear RGB -> 8-bit sRGB: scale so ``white`` maps to 1, clip, IEC 61966-2-1 encode."""
    x = np.clip(np.asarray(pixels, dtype=np.float32) / np.float32(max(white, 1e-12)), 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def _outline(mask: np.ndarray) -> np.ndarray:
    """Pixels of ``mask`` with a 4-neighbour outside it."""
    padded = np.pad(mask, 1, constant_values=False)
    interior = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:] & mask
    return mask & ~interior


def overlay_image(
    pixels: np.ndarray, labels: np.ndarray, states: Sequence[str], *, white: float | None = None
) -> np.ndarray:
    """Build the overlay picture.

    Parameters
    ----------
    pixels
        (h, w, 3) linear RGB of the overlay box.
    labels
        (h, w) int: index into ``states`` of the sample each pixel belongs to, -1 if unsampled.
    states
        Per sample: ``"ok"``, ``"high_spread"`` or ``"clipped"`` (see :data:`OUTLINE_COLOURS`).
    white
        Linear value shown as white; default the 99.5th percentile of the sampled pixels.

    Returns
    -------
    numpy.ndarray
        (h, w, 3) uint8 sRGB.
    """
    sampled = labels >= 0
    if white is None:
        source = pixels[sampled] if np.any(sampled) else pixels.reshape(-1, 3)
        white = float(np.percentile(source.max(axis=1), 99.5)) if source.size else 1.0
    image = tone_map(pixels, white=white)
    image[~sampled] = (image[~sampled] * _DIM).astype(np.uint8)
    for index, state in enumerate(states):
        edge = _outline(labels == index)
        image[edge] = OUTLINE_COLOURS[state]
    return image


def write_png(path: str | Path, image: np.ndarray) -> None:
    """Write an (h, w, 3) uint8 image as PNG with OpenImageIO."""
    import OpenImageIO as oiio

    from ocio_vp.errors import InputError

    image = np.ascontiguousarray(image, dtype=np.uint8)
    spec = oiio.ImageSpec(image.shape[1], image.shape[0], 3, oiio.UINT8)
    spec.attribute("oiio:ColorSpace", "sRGB")
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), spec):
        raise InputError(f"cannot write PNG: {oiio.geterror()}", source=path)
    try:
        if not out.write_image(image):
            raise InputError(f"cannot write PNG: {out.geterror()}", source=path)
    finally:
        out.close()
