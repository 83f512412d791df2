"""Optional ColorChecker detection (``pip install ocio-vp[detect]``) for ``corners: detect``.

Uses colour-checker-detection's *segmentation* method (classical OpenCV contours, no downloaded
model, works offline). The plate is reduced to the detector's working width (1440 pixels) with
OpenImageIO, exposed so its 99th percentile sits at 0.9 and sRGB-encoded (the detector expects
display-like values). The chart quadrilateral it returns is scaled back to plate pixels and
put in the TL, TR, BR, BL order of the chart: of the orientations that keep the grid's aspect,
the one whose patch order best matches the detector's own swatch colours wins. The corners are
written back into the capture file by ``ocio-vp measure`` so later runs are reproducible.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.reader import PlateInfo, linearise

__all__ = ["detect_chart_corners", "detector"]

_WORKING_WIDTH = 1440


def detector(*, source: object = None) -> Callable[..., np.ndarray]:
    """The detection function for :func:`ocio_vp.plates.measure.measure_capture`."""
    try:
        import colour_checker_detection  # noqa: F401
    except ImportError:
        raise InputError(
            "corners: detect needs the optional detector: pip install 'ocio-vp[detect]'",
            source=source,
        ) from None
    return detect_chart_corners


def _working_image(info: PlateInfo) -> np.ndarray:
    import OpenImageIO as oiio

    height = max(1, round(_WORKING_WIDTH * info.height / info.width))
    if info.file_format.startswith("raw ("):  # camera raw: as measured, not as OIIO develops it
        from ocio_vp.plates.reader import read_region

        buf = oiio.ImageBuf(oiio.ImageSpec(info.width, info.height, 3, oiio.FLOAT))
        buf.set_pixels(oiio.ROI(0, info.width, 0, info.height), read_region(info, info.box))
    else:
        buf = oiio.ImageBuf(info.path)
    roi = oiio.ROI(0, _WORKING_WIDTH, 0, height, 0, 1, 0, buf.nchannels)
    small = oiio.ImageBufAlgo.resize(buf, roi=roi)
    pixels = small.get_pixels(oiio.FLOAT)
    if pixels is None or small.has_error:
        raise InputError(f"cannot read for detection: {small.geterror()}", source=info.path)
    rgb = linearise(pixels[..., list(info.rgb)], info.encoding)
    level = float(np.percentile(rgb, 99)) or 1.0
    x = np.clip(rgb / level * 0.9, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def detect_chart_corners(info: PlateInfo, *, rows: int = 4, columns: int = 6) -> np.ndarray:
    """Find a ColorChecker Classic on a plate and return its (4, 2) corners TL, TR, BR, BL.

    Raises
    ------
    InputError
        No chart found, or the grid is not the detector's 4 x 6 ColorChecker Classic.
    """
    from colour_checker_detection import (
        SETTINGS_SEGMENTATION_COLORCHECKER_CLASSIC,
        detect_colour_checkers_segmentation,
    )

    from ocio_vp.plates.sampling import sample_chart

    if (rows, columns) != (4, 6):
        raise InputError("automatic detection knows the 4 x 6 ColorChecker only", source=info.path)
    if info.height > info.width:
        raise InputError("automatic detection needs a landscape plate", source=info.path)
    image = _working_image(info)
    found = detect_colour_checkers_segmentation(
        image, additional_data=True, **SETTINGS_SEGMENTATION_COLORCHECKER_CLASSIC
    )
    if not found:
        raise InputError(
            "no ColorChecker found (corners: detect); give the corners by hand", source=info.path
        )
    data = found[0]
    quad = np.asarray(data.quadrilateral, dtype=np.float64).reshape(4, 2)
    quad *= [info.width / image.shape[1], info.height / image.shape[0]]
    quad += [info.x, info.y]
    # Image order TL, TR, BR, BL by angle about the centre (y down: clockwise on screen).
    centre = quad.mean(axis=0)
    angles = np.arctan2(quad[:, 1] - centre[1], quad[:, 0] - centre[0])
    ordered = quad[np.argsort(angles)]  # from -pi: TL, TR, BR, BL for a mildly tilted chart
    reference = np.asarray(data.swatch_colours, dtype=np.float64).reshape(-1, 3)
    best, best_score = ordered, -np.inf
    for shift in (0, 2):  # the two orientations that keep a landscape grid landscape
        candidate = np.roll(ordered, -shift, axis=0)
        means = sample_chart(info, candidate, rows, columns, inset=0.3, clip_level=np.inf).means
        score = np.corrcoef(
            np.log(np.maximum(means, 1e-9)).ravel(), np.log(np.maximum(reference, 1e-9)).ravel()
        )[0, 1]
        if score > best_score:
            best, best_score = candidate, score
    return best
