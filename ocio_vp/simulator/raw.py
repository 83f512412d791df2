"""Simulated plates written as camera raw: a DNG of the Bayer mosaic, with pidng.

:func:`write_dng` samples a rendered plate (linear camera RGB, the same picture an EXR plate
holds) through an RGGB colour filter array, one channel per photosite, and stores it as a
14-bit sensor would: ``black + value x (white - black)``, rounded, clipped at the white level
(1.0 camera unit = the sensor's clip). The DNG states its black and white levels, an
identity colour matrix and neutral white balance (the values are camera-native; ocio-vp applies
neither when reading). Reading it back with :func:`ocio_vp.plates.raw.read_raw` gives the
plate's values (at each 2x2 block's own samples) within the 14-bit step.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["BLACK", "WHITE", "mosaic", "write_dng"]

#: The simulated sensor's black and white (saturation) levels, in 14-bit code values.
BLACK = 512
WHITE = 16383


def mosaic(image: np.ndarray) -> np.ndarray:
    """The RGGB mosaic (h, w) of a linear RGB image (h, w, 3) with even sides, as code values."""
    height, width, _ = image.shape
    if height % 2 or width % 2:
        raise ValueError(f"a Bayer plate needs even sides, got {width}x{height}")
    channel = np.empty((height, width), dtype=np.intp)
    channel[0::2, 0::2], channel[0::2, 1::2] = 0, 1
    channel[1::2, 0::2], channel[1::2, 1::2] = 1, 2
    values = np.take_along_axis(image, channel[..., None], axis=2)[..., 0]
    codes = np.round(BLACK + np.asarray(values, dtype=np.float64) * (WHITE - BLACK))
    return np.clip(codes, 0, WHITE).astype(np.uint16)


def write_dng(path: str | Path, image: np.ndarray) -> Path:
    """Write ``image`` (linear camera RGB, (h, w, 3)) as an uncompressed 16-bit DNG mosaic."""
    from pidng.core import RAW2DNG
    from pidng.defs import (
        CalibrationIlluminant,
        CFAPattern,
        DNGVersion,
        Orientation,
        PhotometricInterpretation,
        PreviewColorSpace,
    )
    from pidng.dng import DNGTags, Tag

    path = Path(path)
    data = mosaic(np.asarray(image))
    height, width = data.shape
    tags = DNGTags()
    tags.set(Tag.ImageWidth, width)
    tags.set(Tag.ImageLength, height)
    tags.set(Tag.TileWidth, width)
    tags.set(Tag.TileLength, height)
    tags.set(Tag.Orientation, Orientation.Horizontal)
    tags.set(Tag.PhotometricInterpretation, PhotometricInterpretation.Color_Filter_Array)
    tags.set(Tag.SamplesPerPixel, 1)
    tags.set(Tag.BitsPerSample, 16)
    tags.set(Tag.CFARepeatPatternDim, [2, 2])
    tags.set(Tag.CFAPattern, CFAPattern.RGGB)
    tags.set(Tag.BlackLevel, BLACK)
    tags.set(Tag.WhiteLevel, WHITE)
    tags.set(
        Tag.ColorMatrix1, [[1, 1], [0, 1], [0, 1], [0, 1], [1, 1], [0, 1], [0, 1], [0, 1], [1, 1]]
    )
    tags.set(Tag.CalibrationIlluminant1, CalibrationIlluminant.D65)
    tags.set(Tag.AsShotNeutral, [[1, 1], [1, 1], [1, 1]])
    tags.set(Tag.BaselineExposure, [[0, 100]])
    tags.set(Tag.Make, "ocio-vp")
    tags.set(Tag.Model, "simulated sensor")
    tags.set(Tag.UniqueCameraModel, "ocio-vp simulated sensor")
    tags.set(Tag.DNGVersion, DNGVersion.V1_4)
    tags.set(Tag.DNGBackwardVersion, DNGVersion.V1_2)
    tags.set(Tag.PreviewColorSpace, PreviewColorSpace.sRGB)
    writer = RAW2DNG()
    writer.options(tags, path=str(path.parent), compress=False)
    writer.convert(data, filename=path.stem)
    written = path.parent / f"{path.stem}.dng"
    if written != path:
        written.replace(path)
    return path
