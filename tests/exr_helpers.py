"""Writing small test images with OpenImageIO (shared by the image tests)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import OpenImageIO as oiio


def write_exr(path, image, fmt=oiio.FLOAT, names: Sequence[str] | None = None, **attrs) -> None:
    """Write ``image`` (h, w, c) to ``path`` as ``fmt``, with optional channel names and attributes."""
    h, w, c = image.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    if names is not None:
        spec.channelnames = tuple(names)
    for key, value in attrs.items():
        spec.attribute(key, value)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec)
    assert out.write_image(np.ascontiguousarray(image, dtype=np.float32))
    out.close()
