"""Camera raw plates (DNG, CR2/CR3, NEF, ARW, RAF, ...) as camera-native linear RGB, with LibRaw.

A raw file holds the sensor's mosaic: one colour per photosite behind a colour filter array.
ocio-vp reads it with LibRaw (rawpy) and applies **nothing** a raw developer would: no white
balance, no colour matrix, no gamma, no brightening. Each sample becomes
``(value - black) / (white - black)`` with the black level of its colour channel and the white
(saturation) level the file states, so 1.0 is the sensor's clip: :mod:`ocio_vp.plates.sampling`
judges clipping there, as for any integer plate.

Demosaicing (:data:`DEMOSAIC_METHODS`): chart patches are averaged over many pixels, so the
default is the cheapest method with no interpolation at all, ``superpixel``: each 2x2 Bayer
block gives R, the mean of its two G and B, on all four of its pixels (coordinates stay the
sensor's). LibRaw's interpolating methods (``linear``, ``vng``, ``ppg``, ``ahd``, ``dcb``,
``dht``, ``aahd``) are the alternatives, run with the same no-processing settings; a sensor
whose pattern is not 2x2 Bayer (Fujifilm X-Trans) needs one of them. Their effect on chart
patches is measured in tests/test_plates_raw.py.

LibRaw decodes the whole file, so the decoded mosaic of the last few files is kept (a plate is
read for its samples and again for its overlay).
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError

__all__ = ["DEMOSAIC_METHODS", "RAW_SUFFIXES", "RawMosaic", "is_raw", "raw_mosaic", "read_raw"]

#: File name endings read as camera raw.
RAW_SUFFIXES = frozenset(
    {".dng", ".cr2", ".cr3", ".nef", ".nrw", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw"}
)
#: Demosaicing methods: ``superpixel`` (ours, no interpolation) or LibRaw's, by name.
DEMOSAIC_METHODS = ("superpixel", "linear", "vng", "ppg", "ahd", "dcb", "dht", "aahd")
DEFAULT_DEMOSAIC = "superpixel"


def is_raw(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` names a camera raw file (by its ending, case-insensitive)."""
    return Path(path).suffix.lower() in RAW_SUFFIXES


@dataclass(frozen=True)
class RawMosaic:
    """A raw file's visible mosaic (uint16), each pixel's colour index (0 R, 1 G, 2 B, 3 the
    second G), and the black level per colour index and white level the file states."""

    path: str
    mosaic: np.ndarray
    colours: np.ndarray
    black: tuple[float, float, float, float]
    white: float
    pattern: np.ndarray
    make: str

    @property
    def bayer(self) -> bool:
        """A 2x2 pattern holding R, B and two G (superpixel works)."""
        return self.pattern.shape == (2, 2) and sorted(
            int(c) for c in self.colours[:2, :2].ravel()
        ) == [0, 1, 2, 3]


def _open(path: str):  # -> rawpy.RawPy
    import rawpy

    if not os.path.exists(path):
        raise InputError("plate not found", source=path)
    try:
        return rawpy.imread(path)
    except (rawpy.LibRawError, OSError, ValueError) as exc:
        message = " ".join(str(exc).split())[:160] or type(exc).__name__
        raise InputError(
            f"LibRaw cannot read this raw file ({type(exc).__name__}: {message})", source=path
        ) from None


@functools.lru_cache(maxsize=2)
def _cached(path: str, stamp: tuple[int, int]) -> RawMosaic:
    with _open(path) as raw:
        if raw.raw_type != 0 and raw.num_colors != 3:  # pragma: no cover - unusual sensors
            raise InputError("not a colour-filter-array raw file", source=path)
        colours = np.array(raw.raw_colors_visible, dtype=np.uint8)
        blacks = tuple(float(v) for v in raw.black_level_per_channel)
        white = float(raw.white_level)
        if not white > max(blacks):
            raise InputError(f"white level {white:g} not above black {blacks}", source=path)
        return RawMosaic(
            path=path,
            mosaic=np.array(raw.raw_image_visible, dtype=np.uint16),
            colours=colours,
            black=blacks,  # type: ignore[arg-type]
            white=white,
            pattern=np.array(raw.raw_pattern),
            make=str(getattr(raw, "camera_make", "") or ""),
        )


def raw_mosaic(path: str | os.PathLike[str]) -> RawMosaic:
    """The file's mosaic and levels (see :class:`RawMosaic`), decoded once per file version."""
    path = str(path)
    try:
        info = os.stat(path)
    except OSError:
        raise InputError("plate not found", source=path) from None
    return _cached(path, (info.st_mtime_ns, info.st_size))


def _superpixel(raw: RawMosaic, box: tuple[int, int, int, int]) -> np.ndarray:
    x0, y0, x1, y1 = box
    bx0, by0 = x0 // 2 * 2, y0 // 2 * 2
    bx1, by1 = min(-(-x1 // 2) * 2, raw.mosaic.shape[1]), min(-(-y1 // 2) * 2, raw.mosaic.shape[0])
    block = raw.mosaic[by0:by1, bx0:bx1].astype(np.float32)
    h, w = block.shape[0] // 2, block.shape[1] // 2
    block = block[: 2 * h, : 2 * w].reshape(h, 2, w, 2)
    where = {int(raw.colours[by0 + i, bx0 + j]): (i, j) for i in range(2) for j in range(2)}
    scale = raw.white - np.asarray(raw.black, dtype=np.float32)

    def channel(index: int) -> np.ndarray:
        i, j = where[index]
        return (block[:, i, :, j] - np.float32(raw.black[index])) / np.float32(scale[index])

    rgb = np.stack([channel(0), (channel(1) + channel(3)) / 2, channel(2)], axis=-1)
    full = np.repeat(np.repeat(rgb, 2, axis=0), 2, axis=1)
    return full[y0 - by0 : y1 - by0, x0 - bx0 : x1 - bx0]


@functools.lru_cache(maxsize=1)
def _developed(path: str, stamp: tuple[int, int], method: str) -> np.ndarray:
    """The whole picture demosaiced by LibRaw with no processing, float32 normalised."""
    import rawpy

    algorithm = {
        "linear": rawpy.DemosaicAlgorithm.LINEAR,
        "vng": rawpy.DemosaicAlgorithm.VNG,
        "ppg": rawpy.DemosaicAlgorithm.PPG,
        "ahd": rawpy.DemosaicAlgorithm.AHD,
        "dcb": rawpy.DemosaicAlgorithm.DCB,
        "dht": rawpy.DemosaicAlgorithm.DHT,
        "aahd": rawpy.DemosaicAlgorithm.AAHD,
    }[method]
    with _open(path) as raw:
        image = raw.postprocess(
            demosaic_algorithm=algorithm,
            use_camera_wb=False,
            use_auto_wb=False,
            user_wb=[1.0, 1.0, 1.0, 1.0],
            output_color=rawpy.ColorSpace.raw,
            gamma=(1.0, 1.0),
            no_auto_bright=True,
            no_auto_scale=True,
            user_flip=0,
            output_bps=16,
            highlight_mode=rawpy.HighlightMode.Clip,
        )
        black = np.asarray(raw.black_level_per_channel, dtype=np.float32)
        white = float(raw.white_level)
    # no_auto_scale: LibRaw leaves the samples in the file's units with black subtracted
    levels = np.array([black[0], (black[1] + black[3]) / 2, black[2]], dtype=np.float32)
    return (image.astype(np.float32)) / (np.float32(white) - levels)


def read_raw(
    path: str | os.PathLike[str], box: tuple[int, int, int, int], method: str = DEFAULT_DEMOSAIC
) -> np.ndarray:
    """Camera-native linear RGB (rows, columns, 3), float32, of ``box`` (x0, y0, x1, y1) in the
    sensor's visible pixels: 1.0 = the raw white level (see the module docstring)."""
    raw = raw_mosaic(path)
    if method == "superpixel":
        if not raw.bayer:
            raise InputError(
                "the sensor's colour filter is not a 2x2 Bayer pattern (X-Trans?): superpixel "
                f"demosaicing cannot read it; choose one of {', '.join(DEMOSAIC_METHODS[1:])}",
                source=raw.path,
            )
        return _superpixel(raw, box)
    info = os.stat(raw.path)
    image = _developed(raw.path, (info.st_mtime_ns, info.st_size), method)
    x0, y0, x1, y1 = box
    return image[y0:y1, x0:x1]
