"""Read calibration plates with OpenImageIO, one region at a time.

A plate is opened once for its header (:func:`open_plate`); then only the rows, columns and
channels a chart or region covers are decoded (:func:`read_region`), in bands of scanlines (or
tiles), as float32. Pixel coordinates are OpenImageIO's (docs/capture.md, *Coordinates*).
Linear plates are used as they are, camera raw plates are read by :mod:`ocio_vp.plates.raw`,
and display-referred plates (8 bits, PNG, JPEG ...) are refused unless their encoding is stated
(:data:`ENCODINGS`), then decoded to linear on the region only.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.choices import ENCODINGS, canonical_encoding
from ocio_vp.deprecation import warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.formats.documents import check_regular_file
from ocio_vp.plates.raw import is_raw

__all__ = [
    "DISPLAY_FORMATS",
    "ENCODINGS",
    "PlateInfo",
    "block_means",
    "canonical_encoding",
    "linearise",
    "open_plate",
    "read_region",
]

#: File formats that hold display-referred pictures whatever their bit depth.
DISPLAY_FORMATS = frozenset({"png", "jpeg", "webp", "heif", "gif", "bmp", "targa"})
#: DPX transfer characteristics that are not linear (OIIO's ``dpx:Transfer`` names).
_LOG_TRANSFERS = frozenset({"Printing density", "Logarithmic"})
#: Read this many bytes of scanlines at a time (bounds memory for wide plates).
_BAND_BYTES = 32 * 2**20


def linearise(values: np.ndarray, encoding: str) -> np.ndarray:
    """Decode encoded plate values to linear, float64 (``linear`` returns them as float64).

    Uses colour-science's ``colour.cctf_decoding`` so the transfer functions are the published
    ones (IEC 61966-2-1 for ``sRGB``, a pure power for ``Gamma 2.4``, the vendors' log curves).
    """
    values = np.asarray(values, dtype=np.float64)
    if encoding == "linear":
        return values
    import colour

    return np.asarray(colour.cctf_decoding(values, function=encoding), dtype=np.float64)


@dataclass(frozen=True)
class PlateInfo:
    """What :func:`open_plate` learnt from a plate's header.

    ``x``, ``y``, ``width``, ``height`` are the data window; ``rgb`` the channel indices of R, G,
    B; ``bits`` bits per sample; ``is_float`` whether samples are floating point (so there is no
    natural clip level); ``encoding`` the encoding to decode with (``linear`` unless stated).
    """

    path: str
    file_format: str
    width: int
    height: int
    bits: int
    is_float: bool
    encoding: str
    x: int = 0
    y: int = 0
    rgb: tuple[int, int, int] = (0, 1, 2)
    tile_width: int = 0
    tile_height: int = 0
    subimage: int = 0
    #: A camera raw plate's demosaicing method (:data:`ocio_vp.plates.raw.DEMOSAIC_METHODS`).
    demosaic: str | None = None

    @property
    def box(self) -> tuple[int, int, int, int]:
        """The data window as ``(x0, y0, x1, y1)``, end-exclusive."""
        return (self.x, self.y, self.x + self.width, self.y + self.height)


def _find_rgb(names: tuple[str, ...], layer: str | None, path: str) -> tuple[int, int, int]:
    """Indices of R, G, B by name: ``R``/``red`` or ``<layer>.R`` (case-insensitive)."""
    wanted = {"r": 0, "red": 0, "g": 1, "green": 1, "b": 2, "blue": 2}
    layers: dict[str, list[int | None]] = {}
    for index, name in enumerate(names):
        prefix, _, last = name.rpartition(".")
        if last.lower() in wanted:
            slots = layers.setdefault(prefix, [None, None, None])
            slots[wanted[last.lower()]] = index
    complete = {p: s for p, s in layers.items() if None not in s}
    have = ", ".join(names) or "none"
    if layer is not None:
        if layer not in complete:
            raise InputError(
                f"no R, G, B channels in layer {layer!r} (channels: {have})", source=path
            )
        chosen = complete[layer]
    elif "" in complete:
        chosen = complete[""]
    elif len(complete) == 1:
        chosen = next(iter(complete.values()))
    elif not complete:
        raise InputError(f"no R, G, B channels (channels: {have})", source=path)
    else:
        raise InputError(
            f"several RGB layers ({', '.join(sorted(complete))}): say which with 'layer'",
            source=path,
        )
    return (int(chosen[0]), int(chosen[1]), int(chosen[2]))  # type: ignore[arg-type]


def open_input(path: str, what: str = "plate"):  # -> oiio.ImageInput
    """``path`` opened by OpenImageIO; ``what`` it is (``plate``, ``frame``) names it when missing."""
    import OpenImageIO as oiio

    if not os.path.exists(path):
        raise InputError(f"{what} not found", source=path)
    if os.path.isdir(path):
        raise InputError("is a folder, expected an image", source=path)
    check_regular_file(path)  # a FIFO or device would block or never end
    inp = oiio.ImageInput.open(path)
    if inp is None:
        message = " ".join(oiio.geterror().split()) or "unknown reason"
        raise InputError(f"cannot read as an image: {message[:200]}", source=path)
    return inp


def open_plate(
    path: str | os.PathLike[str],
    *,
    encoding: str | None = None,
    layer: str | None = None,
    subimage: int = 0,
    demosaic: str | None = None,
) -> PlateInfo:
    """Open a plate's header, find its R, G, B channels and check it can be measured.

    Parameters
    ----------
    path
        The image file (anything OpenImageIO reads: OpenEXR, DPX, TIFF, ...).
    encoding
        How the pixel values are encoded; ``None`` means linear, which is refused for
        display-referred plates (8-bit, PNG, JPEG ...): state their encoding instead.
    layer
        The EXR layer whose ``.R``, ``.G``, ``.B`` to use when there are several.
    subimage, demosaic
        The subimage (EXR part) to read; a raw plate's demosaicing (default ``superpixel``).

    Raises
    ------
    InputError
        Missing or unreadable file, no R/G/B channels, a display-referred plate without encoding.
    """
    source = str(path)
    if is_raw(source):
        return _open_raw(source, encoding, demosaic)
    inp = open_input(source)
    try:
        if subimage and not inp.seek_subimage(subimage, 0):
            raise InputError(f"has no subimage {subimage}", source=source)
        spec = inp.spec()
        file_format = str(inp.format_name())
    finally:
        inp.close()
    names = tuple(str(n) for n in spec.channelnames)
    rgb = _find_rgb(names, layer, source)
    basetype = str(spec.format)
    is_float = basetype in ("half", "float", "double")
    bits = int(spec.get_int_attribute("oiio:BitsPerSample", 0)) or 8 * spec.format.size()
    transfer = str(spec.get_string_attribute("dpx:Transfer", ""))
    if encoding is None:
        if transfer in _LOG_TRANSFERS:
            raise InputError(
                f"DPX transfer is {transfer!r} (log-encoded): state its 'encoding' "
                "(e.g. Cineon, ARRI LogC3)",
                source=source,
            )
        if bits <= 8 or file_format in DISPLAY_FORMATS:
            raise InputError(
                f"{file_format} plate with {bits} bits per sample is display-referred; "
                "measure linear plates (EXR, DPX, 16-bit TIFF) or state its 'encoding' "
                "(e.g. sRGB, Gamma 2.4)",
                source=source,
            )
        encoding = "linear"
    else:
        encoding = canonical_encoding(encoding, source=source, key="encoding")
    if spec.depth > 1:
        raise InputError("volume images are not plates", source=source)
    return PlateInfo(
        path=source,
        file_format=file_format,
        x=int(spec.x),
        y=int(spec.y),
        width=int(spec.width),
        height=int(spec.height),
        rgb=rgb,
        bits=bits,
        is_float=is_float,
        tile_width=int(spec.tile_width),
        tile_height=int(spec.tile_height),
        encoding=encoding,
        subimage=subimage,
    )


def _open_raw(source: str, encoding: str | None, demosaic: str | None) -> PlateInfo:
    """A camera raw plate's header (:mod:`ocio_vp.plates.raw`): linear by definition."""
    from ocio_vp.plates.raw import DEFAULT_DEMOSAIC, raw_size

    demosaic = demosaic or DEFAULT_DEMOSAIC
    if encoding not in (None, "linear"):
        raise InputError(
            f"a camera raw plate is linear sensor data: remove its encoding ({encoding!r})",
            source=source,
        )
    height, width = raw_size(source)
    return PlateInfo(
        path=source,
        file_format=f"raw (LibRaw, {demosaic} demosaic)",
        width=int(width),
        height=int(height),
        bits=16,
        is_float=False,
        encoding="linear",
        demosaic=demosaic,
    )


def check_box(info: PlateInfo, box: tuple[int, int, int, int], *, what: str = "region") -> None:
    """Raise :class:`InputError` unless ``box`` (x0, y0, x1, y1) is non-empty and inside."""
    x0, y0, x1, y1 = box
    px0, py0, px1, py1 = info.box
    if x1 <= x0 or y1 <= y0:
        raise InputError(f"{what} {list(box)} is empty", source=info.path)
    if x0 < px0 or y0 < py0 or x1 > px1 or y1 > py1:
        raise InputError(
            f"{what} {list(box)} is outside the image (data window {list(info.box)})",
            source=info.path,
        )


def read_region(
    plate: PlateInfo | str | os.PathLike[str],
    box: tuple[int, int, int, int],
    *,
    encoding: str | None = None,
) -> np.ndarray:
    """Read the R, G, B pixels of ``box`` = ``(x0, y0, x1, y1)`` (end-exclusive), linearised.

    Only the scanline bands (or tiles) that cover ``box`` are decoded, a bounded number of bytes
    at a time, and only the channels from the first to the last of R, G, B.

    Returns
    -------
    numpy.ndarray
        ``(y1 - y0, x1 - x0, 3)`` float32 linear RGB (float64 if an encoding was decoded).
    """
    import OpenImageIO as oiio

    info = plate if isinstance(plate, PlateInfo) else open_plate(plate, encoding=encoding)
    check_box(info, box)
    if info.file_format.startswith("raw ("):
        from ocio_vp.plates.raw import DEFAULT_DEMOSAIC, read_raw

        method = info.demosaic or DEFAULT_DEMOSAIC
        return read_raw(info.path, tuple(int(v) for v in box), method)  # type: ignore[arg-type]
    x0, y0, x1, y1 = (int(v) for v in box)
    ch0, ch1 = min(info.rgb), max(info.rgb) + 1
    select = [c - ch0 for c in info.rgb]
    out = np.empty((y1 - y0, x1 - x0, 3), dtype=np.float32)
    inp = open_input(info.path)
    try:
        if info.subimage:
            inp.seek_subimage(info.subimage, 0)
        if info.tile_width:
            tw, th = info.tile_width, info.tile_height or 1
            # Tile-aligned bounds, clamped to the data window.
            tx0 = info.x + (x0 - info.x) // tw * tw
            tx1 = min(info.x + -(-(x1 - info.x) // tw) * tw, info.x + info.width)
            band = max(th, (_BAND_BYTES // max(1, (tx1 - tx0) * (ch1 - ch0) * 4)) // th * th)
            ty = info.y + (y0 - info.y) // th * th
            while ty < y1:
                ty1 = min(ty + band, info.y + info.height)
                data = inp.read_tiles(
                    info.subimage, 0, tx0, tx1, ty, ty1, 0, 1, ch0, ch1, oiio.FLOAT
                )
                check_read(data, inp, info.path, (ty1 - ty, tx1 - tx0, ch1 - ch0))
                r0, r1 = max(ty, y0), min(ty1, y1)
                out[r0 - y0 : r1 - y0] = data[r0 - ty : r1 - ty, x0 - tx0 : x1 - tx0][..., select]
                ty = ty1
        else:
            rows = max(1, _BAND_BYTES // max(1, info.width * (ch1 - ch0) * 4))
            for ya in range(y0, y1, rows):
                yb = min(ya + rows, y1)
                data = inp.read_scanlines(info.subimage, 0, ya, yb, 0, ch0, ch1, oiio.FLOAT)
                check_read(data, inp, info.path, (yb - ya, info.width, ch1 - ch0))
                out[ya - y0 : yb - y0] = data[:, x0 - info.x : x1 - info.x][..., select]
    finally:
        inp.close()
    if not np.all(np.isfinite(out)):
        bad = int(np.count_nonzero(~np.isfinite(out)))
        raise InputError(f"{bad} NaN/Inf samples in region {list(box)}", source=info.path)
    if info.encoding != "linear":
        return linearise(out, info.encoding)
    return out


def block_means(info: PlateInfo, factor: int, *, zero_non_finite: bool | None = None) -> np.ndarray:
    """(height // factor, width // factor, 3) float64: the plate averaged over blocks of
    ``factor`` x ``factor`` pixels (whole blocks only), read in bands. NaN and +-Inf (only a
    stated encoding's decoding gives them: :func:`read_region` refuses them in a file) count
    as 0, so one sample cannot turn a whole search's statistics into NaN; ``zero_non_finite``
    (deprecated) False still carries them into their block's mean."""
    if zero_non_finite is not None:
        warn_deprecated("block_means(zero_non_finite=...)", "block_means(info, factor)")
    cells_x, cells_y = info.width // factor, info.height // factor
    out = np.empty((cells_y, cells_x, 3), dtype=np.float64)
    band = max(1, (1 << 21) // max(1, info.width * factor * 3))
    for cy in range(0, cells_y, band):
        cy1 = min(cells_y, cy + band)
        box = (info.x, info.y + cy * factor, info.x + cells_x * factor, info.y + cy1 * factor)
        pixels = read_region(info, box).astype(np.float64)
        if zero_non_finite is not False:
            pixels = np.nan_to_num(pixels, posinf=0.0, neginf=0.0)
        out[cy:cy1] = pixels.reshape(cy1 - cy, factor, cells_x, factor, 3).mean(axis=(1, 3))
    return out


def check_read(data: object, inp: object, source: str, shape: tuple[int, ...]) -> np.ndarray:
    """OpenImageIO's pixels ``data`` as an array of ``shape``, or the reader's error, one line."""
    if data is None or not isinstance(data, np.ndarray) or inp.has_error:  # type: ignore[attr-defined]
        message = " ".join(str(inp.geterror()).split()) or "read failed"  # type: ignore[attr-defined]
        raise InputError(f"cannot read pixels (corrupt file?): {message[:200]}", source=source)
    if data.ndim == 2:  # one channel comes back as (rows, width)
        data.shape = (*data.shape, 1)
    if tuple(data.shape) != shape:
        raise InputError(f"read {data.shape} pixels, expected {shape}", source=source)
    return data


def plate_path(base: str | os.PathLike[str], value: str) -> Path:
    """Resolve a plate path written in a file relative to that file's folder."""
    path = Path(value).expanduser()
    return path if path.is_absolute() else Path(base).parent / path
