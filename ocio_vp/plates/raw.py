"""Camera raw plates (DNG, CR2/CR3, NEF, ARW, RAF, ...) as camera-native linear RGB, with LibRaw:
``(value - black) / (white - black)`` with the file's levels, nothing a raw developer applies.
Demosaicing is ``superpixel`` by default or one of LibRaw's (:data:`DEMOSAIC_METHODS`);
docs/capture.md (*Camera raw plates*) says when each is needed.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.formats.documents import check_regular_file

__all__ = [
    "DEMOSAIC_METHODS",
    "MAX_CONDITION_RAW",
    "RAW_SUFFIXES",
    "CameraSpace",
    "RawMosaic",
    "dng_colour_matrix",
    "is_raw",
    "library_message",
    "raw_mosaic",
    "raw_size",
    "read_raw",
    "sensor_to_camera",
]

#: File name endings read as camera raw.
RAW_SUFFIXES = frozenset(
    {".dng", ".cr2", ".cr3", ".nef", ".nrw", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw"}
)
#: Demosaicing methods: ``superpixel`` (ours, no interpolation) or LibRaw's, by name.
DEMOSAIC_METHODS = ("superpixel", "linear", "vng", "ppg", "ahd", "dcb", "dht", "aahd")
DEFAULT_DEMOSAIC = "superpixel"
#: A raw camera matrix (DNG ColorMatrix, ``raw.to_camera``) above this condition is singular.
MAX_CONDITION_RAW = 1e6


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

    @property
    def bayer(self) -> bool:
        """A 2x2 pattern holding R, B and two G (superpixel works)."""
        return self.pattern.shape == (2, 2) and sorted(
            int(c) for c in self.colours[:2, :2].ravel()
        ) == [0, 1, 2, 3]


def library_message(exc: Exception) -> str:
    """A decoding library's exception as one short line (its class name if it says nothing)."""
    return " ".join(str(exc).split())[:160] or type(exc).__name__


def _open(path: str):  # -> rawpy.RawPy (LibRaw decodes the mosaic only when it is read)
    import rawpy

    try:
        return rawpy.imread(path)
    except (rawpy.LibRawError, OSError, ValueError) as exc:
        raise InputError(
            f"LibRaw cannot read this raw file ({type(exc).__name__}: {library_message(exc)})",
            source=path,
        ) from None


def _stamp(path: str | os.PathLike[str]) -> tuple[str, tuple[int, int]]:
    """The path and (mtime, size) that key the decoding caches; refuses a missing file."""
    path = str(path)
    if not os.path.exists(path):
        raise InputError("plate not found", source=path)
    info = check_regular_file(path)
    return path, (info.st_mtime_ns, info.st_size)


def raw_size(path: str | os.PathLike[str]) -> tuple[int, int]:
    """The visible (height, width) the file states, read from its header without decoding."""
    path, _ = _stamp(path)
    with _open(path) as raw:
        return int(raw.sizes.height), int(raw.sizes.width)


def _levels(raw, path: str) -> tuple[tuple[float, ...], float]:
    """The black level per colour index and the white level, refused unless white > black."""
    blacks = tuple(float(v) for v in raw.black_level_per_channel)
    white = float(raw.white_level)
    if not white > max(blacks):
        raise InputError(f"white level {white:g} not above black {blacks}", source=path)
    return blacks, white


def _check_cfa(raw, path: str) -> None:
    """Refuse a file whose samples are not one colour per photosite (both demosaicing paths)."""
    if raw.raw_type != 0 and raw.num_colors != 3:
        raise InputError("not a colour-filter-array raw file", source=path)


def _check_size(raw, shape: tuple[int, ...], path: str) -> None:
    """Refuse a decoded picture whose size is not the header's (:func:`raw_size`, the size the
    plate was opened with and its boxes checked against)."""
    height, width = int(raw.sizes.height), int(raw.sizes.width)
    if tuple(shape[:2]) != (height, width):
        raise InputError(
            f"LibRaw decoded {shape[1]}x{shape[0]} pixels where the file's header states "
            f"{width}x{height}",
            source=path,
        )


@functools.lru_cache(maxsize=2)
def _cached(path: str, stamp: tuple[int, int]) -> RawMosaic:
    with _open(path) as raw:
        _check_cfa(raw, path)
        mosaic = np.array(raw.raw_image_visible, dtype=np.uint16)
        _check_size(raw, mosaic.shape, path)
        colours = np.array(raw.raw_colors_visible, dtype=np.uint8)
        blacks, white = _levels(raw, path)
        return RawMosaic(
            path=path,
            mosaic=mosaic,
            colours=colours,
            black=blacks,  # type: ignore[arg-type]
            white=white,
            pattern=np.array(raw.raw_pattern),
        )


def raw_mosaic(path: str | os.PathLike[str]) -> RawMosaic:
    """The file's mosaic and levels (see :class:`RawMosaic`), decoded once per file version."""
    return _cached(*_stamp(path))


def _superpixel(raw: RawMosaic, box: tuple[int, int, int, int]) -> np.ndarray:
    """No interpolation: each 2x2 Bayer block's R, mean G and B on its four pixels."""
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

    algorithm = rawpy.DemosaicAlgorithm[method.upper()]  # DEMOSAIC_METHODS[1:] are its names
    with _open(path) as raw:
        _check_cfa(raw, path)
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
        _check_size(raw, image.shape, path)
        blacks, white = _levels(raw, path)
    black = np.asarray(blacks, dtype=np.float32)
    # no_auto_scale: LibRaw leaves the samples in the file's units with black subtracted
    levels = np.array([black[0], (black[1] + black[3]) / 2, black[2]], dtype=np.float32)
    return (image.astype(np.float32)) / (np.float32(white) - levels)


def read_raw(
    path: str | os.PathLike[str], box: tuple[int, int, int, int], method: str = DEFAULT_DEMOSAIC
) -> np.ndarray:
    """Camera-native linear RGB (rows, columns, 3), float32, of ``box`` (x0, y0, x1, y1) in the
    sensor's visible pixels: 1.0 = the raw white level (see the module docstring)."""
    if method == "superpixel":
        raw = raw_mosaic(path)
        if not raw.bayer:
            raise InputError(
                "the sensor's colour filter is not a 2x2 Bayer pattern (X-Trans?): superpixel "
                f"demosaicing cannot read it; choose one of {', '.join(DEMOSAIC_METHODS[1:])}",
                source=raw.path,
            )
        return _superpixel(raw, box)
    image = _developed(*_stamp(path), method)
    x0, y0, x1, y1 = box
    return image[y0:y1, x0:x1]


# -- one camera space: sensor RGB -> the cinema camera's encoding gamut -------------------------

#: DNG tags (DNG 1.4 specification): ColorMatrix1/2 (XYZ -> camera native, SRATIONAL x 9) and
#: CalibrationIlluminant1/2 (EXIF LightSource codes).
_COLOR_MATRIX = (50721, 50722)
_ILLUMINANT = (50778, 50779)
#: EXIF LightSource codes with a CIE illuminant colour-science knows (others: give a matrix).
_LIGHT_SOURCES = {17: "A", 20: "D55", 21: "D65", 22: "D75", 23: "D50"}


@dataclass(frozen=True)
class CameraSpace:
    """How a raw plate's sensor RGB becomes the camera gamut's RGB (``stage.camera_colorspace``):
    ``matrix`` (3x3, applied to column vectors of sensor RGB) and where it came from."""

    matrix: np.ndarray
    source: str


def _tiff_tags(path: str, wanted: set[int]) -> dict[int, tuple[float, ...]]:
    """Numeric values of the ``wanted`` tags of a TIFF/DNG file's first IFD (SHORT, LONG,
    RATIONAL, SRATIONAL)."""
    import struct

    sizes = {3: 2, 4: 4, 5: 8, 8: 2, 9: 4, 10: 8}
    out: dict[int, tuple[float, ...]] = {}
    with open(path, "rb") as fh:
        head = fh.read(8)
        if len(head) < 8 or head[:2] not in (b"II", b"MM"):
            raise InputError("not a TIFF-based raw file (DNG): no colour matrix", source=path)
        order = "<" if head[:2] == b"II" else ">"
        fh.seek(struct.unpack(order + "I", head[4:8])[0])
        (count,) = struct.unpack(order + "H", fh.read(2))
        entries = [struct.unpack(order + "HHI4s", fh.read(12)) for _ in range(min(count, 4096))]
        for tag, kind, n, value in entries:
            if tag not in wanted or kind not in sizes or n > 64:
                continue
            size = sizes[kind] * n
            if size > 4:
                fh.seek(struct.unpack(order + "I", value)[0])
                value = fh.read(size)
            if kind in (5, 10):
                code = order + ("%di" if kind == 10 else "%dI") % (2 * n)
                pairs = struct.unpack(code, value[:size])
                if any(d == 0 for d in pairs[1::2]):
                    raise InputError(f"DNG tag {tag} has a zero denominator", source=path)
                out[tag] = tuple(a / b for a, b in zip(pairs[0::2], pairs[1::2], strict=True))
            else:
                code = order + {3: "H", 4: "I", 8: "h", 9: "i"}[kind] * n
                out[tag] = tuple(float(v) for v in struct.unpack(code, value[:size]))
    return out


def dng_colour_matrix(path: str | os.PathLike[str]) -> tuple[np.ndarray, str]:
    """The DNG's XYZ -> camera matrix (3, 3) and its calibration illuminant's name: the
    ColorMatrix calibrated under D65 when there is one, else the first."""
    path = str(path)
    try:
        tags = _tiff_tags(path, {*_COLOR_MATRIX, *_ILLUMINANT})
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror}", source=path) from None
    found = []
    for matrix_tag, light_tag in zip(_COLOR_MATRIX, _ILLUMINANT, strict=True):
        if len(tags.get(matrix_tag, ())) == 9:
            light = int(tags.get(light_tag, (0,))[0])
            found.append((np.array(tags[matrix_tag]).reshape(3, 3), light))
    if not found:
        raise InputError("the DNG has no 3-colour ColorMatrix: give raw.to_camera", source=path)
    matrix, light = next((f for f in found if f[1] == 21), found[0])
    if light not in _LIGHT_SOURCES:
        raise InputError(
            f"the DNG's ColorMatrix is calibrated under light source {light}, not a CIE "
            "illuminant ocio-vp knows (A, D50, D55, D65, D75): give raw.to_camera",
            source=path,
        )
    return matrix, _LIGHT_SOURCES[light]


def sensor_to_camera(path: str | os.PathLike[str], colourspace: str) -> CameraSpace:
    """The DNG's sensor RGB -> ``colourspace`` RGB: the inverse of its ColorMatrix (camera ->
    XYZ under its calibration illuminant), CAT02 to the gamut's white, colour-science's XYZ ->
    RGB of the gamut. The DNG's normalisation stays: camera values (1.0 = the raw white level)
    whose neutral under the illuminant peaks at 1 map to Y = 1."""
    import colour

    matrix, illuminant = dng_colour_matrix(path)
    condition = np.linalg.cond(matrix)
    if not np.isfinite(condition) or condition > MAX_CONDITION_RAW:
        raise InputError(
            f"the DNG's ColorMatrix cannot be inverted (condition number {condition:.3g})",
            source=path,
        )
    space = colour.RGB_COLOURSPACES[colourspace]
    white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"][illuminant]
    adapt = colour.adaptation.matrix_chromatic_adaptation_VonKries(
        colour.xy_to_XYZ(white), colour.xy_to_XYZ(space.whitepoint), transform="CAT02"
    )
    to_camera = np.asarray(space.matrix_XYZ_to_RGB) @ adapt @ np.linalg.inv(matrix)
    source = f"the DNG's ColorMatrix ({illuminant}) inverted, CAT02, XYZ to {space.name}"
    return CameraSpace(to_camera.astype(np.float64), source)
