"""Reading a camera take recorded as a movie file (QuickTime, MP4, MXF) with PyAV;
docs/capture.md (*A take as a movie*) gives the in/out points, timecode and refusals.

A movie is decoded once, front to back (:func:`scan_movie`), keeping per frame only
:class:`~ocio_vp.plates.take_reader.FrameStats`. Y'CbCr is converted here, at the decoder's bit
depth, with the matrix and range the stream declares or the capture file gives, subsampled
chroma repeated onto its luma pixels; then the log encoding is decoded. Frames count from 0.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.raw import library_message
from ocio_vp.plates.reader import PlateInfo, linearise
from ocio_vp.plates.take_reader import FrameStats, frame_stats

__all__ = [
    "AV_MATRICES",
    "AV_RANGES",
    "BAND_PIXELS",
    "MATRICES",
    "MOVIE_SUFFIXES",
    "RANGES",
    "MovieInfo",
    "decode_frame",
    "decode_log",
    "is_movie",
    "movie_rows",
    "open_movie",
    "parse_point",
    "read_movie_frame",
    "reduced_frame",
    "scan_movie",
    "ycbcr_to_rgb",
]

#: File name endings read as movies.
MOVIE_SUFFIXES = frozenset({".mov", ".mp4", ".mxf", ".m4v"})
#: Y'CbCr matrices by name: (Kr, Kb) (ITU-R BT.709, BT.2020 non-constant luminance, BT.601).
MATRICES = {"rec709": (0.2126, 0.0722), "rec2020": (0.2627, 0.0593), "rec601": (0.299, 0.114)}
#: Ranges: ``legal`` (video: Y' 16-235, C 16-240 at 8 bits) or ``full``.
RANGES = ("legal", "full")
#: FFmpeg's colour-space codes (AVColorSpace, H.273 MatrixCoefficients) we convert.
AV_MATRICES = {1: "rec709", 9: "rec2020", 5: "rec601", 6: "rec601"}
#: AVColorRange: 1 = MPEG (legal), 2 = JPEG (full).
AV_RANGES = {1: "legal", 2: "full"}
_PIX_FMT = re.compile(r"(yuv|yuva|yuvj|gbr|gbra)(444|422|420)?p(\d+)?(le)?")


def is_movie(path: str | Path) -> bool:
    """Whether ``path`` names a movie file (by its ending, case-insensitive)."""
    return Path(path).suffix.lower() in MOVIE_SUFFIXES


@dataclass(frozen=True)
class MovieInfo:
    """What :func:`open_movie` learnt: size, pixel layout, colour tags and the frame grid.

    ``first``/``last``: the frames to measure (inclusive, 0 = the file's first frame);
    ``matrix``/``range`` and where each came from (``stream`` or ``capture file``);
    ``rate``: frames per second; ``frames``: the count the container states (0 if unknown).
    """

    path: Path
    codec: str
    pix_fmt: str
    width: int
    height: int
    bits: int
    rgb: bool
    subsampling: tuple[int, int]
    matrix: str
    range: str
    tags_from: str
    rate: Fraction
    frames: int
    first: int
    last: int | None
    timecode: str | None
    encoding: str

    def plate_info(self) -> PlateInfo:
        """The take's header as the rest of the take's code reads it."""
        return PlateInfo(
            path=str(self.path),
            file_format=f"movie ({self.codec})",
            width=self.width,
            height=self.height,
            bits=self.bits,
            is_float=False,
            encoding=self.encoding,
        )


def _error(message: str, path: Path, key: str | None = None) -> InputError:
    return InputError(message, source=path, key=key)


def _open(path: Path):  # -> av.container.InputContainer
    import av

    if not path.exists():
        raise _error("movie not found", path)
    if not path.is_file():
        raise _error("is not a regular file, expected a movie", path)
    try:
        return av.open(str(path), "r")
    except (av.FFmpegError, OSError, ValueError) as exc:
        raise _error(
            f"cannot open as a movie (truncated or not a movie?): {library_message(exc)}", path
        ) from None


def _layout(pix_fmt: str, path: Path) -> tuple[int, bool, tuple[int, int]]:
    """(bits, is RGB, (horizontal, vertical) chroma subsampling) of a planar pixel format."""
    match = _PIX_FMT.fullmatch(pix_fmt or "")
    if match is None:
        raise _error(
            f"pixel format {pix_fmt!r} is not a planar Y'CbCr or RGB format ocio-vp reads "
            "(yuv444p/422p/420p or gbrp at 8-16 bits)",
            path,
        )
    kind, chroma, bits = match.group(1), match.group(2) or "444", int(match.group(3) or 8)
    sub = {"444": (1, 1), "422": (2, 1), "420": (2, 2)}[chroma]
    return bits, kind.startswith("gbr"), sub


def _tags(ctx, matrix: str | None, range_: str | None, path: Path, rgb: bool):
    """The matrix and range to convert with, and where they came from."""
    stream_matrix = "rgb" if rgb else AV_MATRICES.get(int(ctx.colorspace or 2))
    stream_range = AV_RANGES.get(int(ctx.color_range or 0))
    if int(ctx.colorspace or 2) == 10:
        raise _error("the stream is Rec.2020 constant luminance, which ocio-vp does not read", path)
    chosen_matrix = matrix or stream_matrix
    chosen_range = range_ or stream_range
    missing = [
        key
        for key, value in (("take.matrix", chosen_matrix), ("take.range", chosen_range))
        if value is None
    ]
    if missing:
        raise _error(
            f"the movie's stream declares no {' and no '.join(k.split('.')[1] for k in missing)}"
            f": give {' and '.join(missing)} in the capture file (matrix: "
            f"{', '.join(MATRICES)}; range: {', '.join(RANGES)})",
            path,
        )
    given = (matrix is not None) or (range_ is not None)
    return chosen_matrix, chosen_range, "capture file" if given else "stream"


def _timecode(container, stream) -> str | None:
    for meta in (stream.metadata, container.metadata):
        value = meta.get("timecode")
        if value:
            return str(value)
    return None


def parse_point(value: int | str, rate: Fraction, timecode: str | None, key: str, path) -> int:
    """A frame number (0 = the file's first frame) from an int or a timecode ``HH:MM:SS:FF``
    counted on the file's start timecode (non-drop frame).

    Examples
    --------
    >>> parse_point("01:00:01:05", Fraction(25), "01:00:00:00", "take.in", "a.mov")
    30
    >>> parse_point(12, Fraction(25), None, "take.in", "a.mov")
    12
    """
    if isinstance(value, int) and not isinstance(value, bool):
        if value < 0:
            raise InputError(f"frame number {value} is negative", source=path, key=key)
        return value

    def frames_of(text: str, what: str) -> int:
        m = re.fullmatch(r"(\d{1,2}):(\d{2}):(\d{2})([:;])(\d{2,3})", str(text).strip())
        if m is None or m.group(4) == ";":
            raise InputError(
                f"expected a frame number or non-drop timecode HH:MM:SS:FF, got {what} "
                f"{str(text)[:40]!r}",
                source=path,
                key=key,
            )
        h, mi, s, f = (int(m.group(i)) for i in (1, 2, 3, 5))
        base = round(rate)
        if f >= base or mi > 59 or s > 59:
            raise InputError(f"timecode {text} is not valid at {base} fps", source=path, key=key)
        return ((h * 60 + mi) * 60 + s) * base + f

    if not isinstance(value, str):
        raise InputError(
            f"expected a frame number or timecode, got {value!r}", source=path, key=key
        )
    start = frames_of(timecode, "the file's start timecode") if timecode else 0
    frame = frames_of(value, "") - start
    if frame < 0:
        raise InputError(
            f"timecode {value} is before the movie's start timecode {timecode or '00:00:00:00'}",
            source=path,
            key=key,
        )
    return frame


def open_movie(
    path: Path,
    *,
    encoding: str | None,
    matrix: str | None = None,
    range_: str | None = None,
    in_point: int | str | None = None,
    out_point: int | str | None = None,
) -> MovieInfo:
    """Open a movie's header and check it can be measured (see the module docstring).

    Raises
    ------
    InputError
        Not found, unreadable or truncated, no video stream, a codec FFmpeg cannot decode, a
        pixel format other than planar Y'CbCr/RGB, no colour tags in the stream or the capture
        file, in/out points outside the movie or in the wrong order.
    """
    container = _open(path)
    try:
        if not container.streams.video:
            raise _error("the movie has no video stream", path)
        stream = container.streams.video[0]
        ctx = stream.codec_context
        if ctx is None or not ctx.name:
            raise _error("the movie's video codec is not one FFmpeg (PyAV) decodes", path)
        bits, rgb, sub = _layout(ctx.pix_fmt or "", path)
        chosen = _tags(ctx, matrix, range_, path, rgb)
        rate = Fraction(stream.average_rate or stream.guessed_rate or 0)
        if rate <= 0:
            raise _error("the movie states no frame rate", path)
        frames = int(stream.frames or 0)
        if not frames and stream.duration and stream.time_base:
            frames = round(stream.duration * stream.time_base * rate)
        timecode = _timecode(container, stream)
        info = MovieInfo(
            path=path,
            codec=str(ctx.name),
            pix_fmt=str(ctx.pix_fmt),
            width=int(ctx.width),
            height=int(ctx.height),
            bits=bits,
            rgb=rgb,
            subsampling=sub,
            matrix=chosen[0],
            range=chosen[1],
            tags_from=chosen[2],
            rate=rate,
            frames=frames,
            first=0,
            last=None,
            timecode=timecode,
            encoding=encoding or "linear",
        )
    finally:
        container.close()
    first = 0 if in_point is None else parse_point(in_point, rate, timecode, "take.in", path)
    last = None if out_point is None else parse_point(out_point, rate, timecode, "take.out", path)
    if last is not None and last < first:
        raise _error(f"take.out (frame {last}) is before take.in (frame {first})", path, None)
    for key, point in (("take.in", first), ("take.out", last)):
        if frames and point is not None and point >= frames:
            raise _error(
                f"{key} is frame {point}, but the movie has {frames} frames (0 to {frames - 1})",
                path,
            )
    return replace(info, first=first, last=last)


def ycbcr_to_rgb(
    y: np.ndarray, cb: np.ndarray, cr: np.ndarray, *, bits: int, matrix: str, range_: str
) -> np.ndarray:
    """R'G'B' (..., 3) float32 from integer Y', Cb, Cr code values (ITU-R BT.709 / BT.2020
    / BT.601 equations; legal range per BT.709 Table 4.6 scaled to ``bits``, full range per
    ITU-T H.273).

    Examples
    --------
    >>> ycbcr_to_rgb(np.array([940]), np.array([512]), np.array([512]), bits=10,
    ...              matrix="rec709", range_="legal").round(6).tolist()
    [[1.0, 1.0, 1.0]]
    """
    kr, kb = MATRICES[matrix]
    kg = 1.0 - kr - kb
    yn = _levels(y, bits, range_)
    if range_ == "legal":
        c_off, c_div = 128.0 * (1 << (bits - 8)), 224.0 * (1 << (bits - 8))
    else:
        c_off, c_div = float(1 << (bits - 1)), float((1 << bits) - 1)
    pb = (cb.astype(np.float32) - np.float32(c_off)) / np.float32(c_div)
    pr = (cr.astype(np.float32) - np.float32(c_off)) / np.float32(c_div)
    out = np.empty((*yn.shape, 3), dtype=np.float32)
    out[..., 0] = yn + np.float32(2 * (1 - kr)) * pr
    out[..., 2] = yn + np.float32(2 * (1 - kb)) * pb
    out[..., 1] = (
        yn - np.float32(2 * kb * (1 - kb) / kg) * pb - np.float32(2 * kr * (1 - kr) / kg) * pr
    )
    return out


def _plane(frame, index: int, bits: int) -> np.ndarray:
    """A plane of a decoded frame as a 2-D integer array, read in place (no copy)."""
    plane = frame.planes[index]
    dtype = np.uint16 if bits > 8 else np.uint8
    data = np.frombuffer(plane, dtype=dtype)
    return data.reshape(plane.height, plane.line_size // data.itemsize)[:, : plane.width]


def _chroma(plane: np.ndarray, box, sub: tuple[int, int]) -> np.ndarray:
    """A subsampled chroma plane's samples over ``box``, each repeated onto its luma pixels."""
    x0, y0, x1, y1 = box
    sx, sy = sub
    if sub == (1, 1):
        return plane[y0:y1, x0:x1]
    part = plane[y0 // sy : (y1 - 1) // sy + 1, x0 // sx : (x1 - 1) // sx + 1]
    part = np.repeat(np.repeat(part, sy, axis=0), sx, axis=1)
    return part[y0 - y0 // sy * sy :][: y1 - y0, x0 - x0 // sx * sx :][:, : x1 - x0]


def _levels(code: np.ndarray, bits: int, range_: str) -> np.ndarray:
    """Y' (or R', G', B') code values as float32: 0 at black, 1 at white of ``range_``."""
    code = code.astype(np.float32)
    if range_ == "legal":
        scale = float(1 << (bits - 8))
        return (code - np.float32(16 * scale)) / np.float32(219 * scale)
    return code / np.float32((1 << bits) - 1)


def _planes_rgb(planes: list[np.ndarray], info: MovieInfo) -> np.ndarray:
    """R'G'B' (..., 3) float32 from a frame's three planes (planar G, B, R or Y', Cb, Cr)."""
    if not info.rgb:
        return ycbcr_to_rgb(*planes, bits=info.bits, matrix=info.matrix, range_=info.range)
    g, b, r = planes
    return _levels(np.stack([r, g, b], axis=-1), info.bits, info.range)


def frame_rgb(frame, info: MovieInfo, box: tuple[int, int, int, int]) -> np.ndarray:
    """R'G'B' float32 (rows, columns, 3) of ``box`` (x0, y0, x1, y1) of a decoded frame
    (an RGB stream's subsampling is (1, 1))."""
    x0, y0, x1, y1 = box
    planes = [_plane(frame, k, info.bits) for k in range(3)]
    chroma = [_chroma(p, box, info.subsampling) for p in planes[1:]]
    return _planes_rgb([planes[0][y0:y1, x0:x1], *chroma], info)


#: The decoding table's domain and size (:func:`decode_log`).
_TABLE = (-0.25, 1.5, 2**16 + 1)


@functools.lru_cache(maxsize=8)
def _table(encoding: str) -> tuple[np.ndarray, np.ndarray]:
    lo, hi, size = _TABLE
    codes = np.linspace(lo, hi, size)
    with np.errstate(invalid="ignore"):  # a pure power has no negative values: NaN there
        return codes, linearise(codes, encoding)


def decode_log(values: np.ndarray, encoding: str) -> np.ndarray:
    """Linear values of encoded R'G'B' (float64): colour-science's decoding sampled evenly over
    :data:`_TABLE` and interpolated linearly; values outside the table, or next to a value the
    curve does not define (a pure power's negative side), are decoded directly. ``linear``
    returns the values as float64."""
    values = np.asarray(values)
    if encoding == "linear":
        return values.astype(np.float64)
    codes, linear = _table(encoding)
    lo, hi, size = _TABLE
    position = (values.astype(np.float64) - lo) * ((size - 1) / (hi - lo))
    index = np.clip(position.astype(np.int64), 0, size - 2)
    fraction = position - index
    out = linear[index] + fraction * (linear[index + 1] - linear[index])
    outside = (values < lo) | (values > hi) | ~np.isfinite(out)
    if np.any(outside):
        out[outside] = linearise(values[outside], encoding)
    return out


def _decoded(info: MovieInfo, container, stream) -> Iterator[tuple[int, Any]]:
    """(frame number, frame) of every frame from ``info.first`` to ``info.last``, checking the
    frame grid (VFR refused) and mapping FFmpeg's errors to one-line refusals."""
    import av

    step = 1 / (info.rate * stream.time_base) if stream.time_base else None
    origin = None
    index = -1
    try:
        for frame in container.decode(stream):
            index += 1
            if frame.pts is not None and step is not None:
                if origin is None:
                    origin = frame.pts
                position = (frame.pts - origin) / step
                if abs(position - index) > 0.5:
                    raise _error(
                        f"variable frame rate: frame {index} is stamped at "
                        f"{float(position):.2f} frame periods of {float(info.rate):g} fps; "
                        "transcode to a constant rate (e.g. ffmpeg -fps_mode cfr)",
                        info.path,
                    )
            if index < info.first:
                continue
            if info.last is not None and index > info.last:
                break
            yield index, frame
    except av.FFmpegError as exc:
        raise _error(
            f"cannot decode frame {index + 1} (truncated or corrupt?): {library_message(exc)}",
            info.path,
        ) from None
    if info.last is not None and index < info.last:
        raise _error(
            f"take.out is frame {info.last}, but the movie ends at frame {index}", info.path
        )
    if info.frames and index + 1 < info.frames and (info.last is None or info.last >= index):
        raise _error(
            f"the movie ends at frame {index} of the {info.frames} its header lists (truncated?)",
            info.path,
        )


def _stream(info: MovieInfo, threads: str = "AUTO"):
    """The movie opened for decoding: ``AUTO`` (frame threads) for a pass over many frames,
    ``SLICE`` for one frame (frame threads would decode several ahead before returning it)."""
    container = _open(info.path)
    stream = container.streams.video[0]
    stream.thread_type = threads
    return container, stream


def scan_movie(
    info: MovieInfo,
    region: tuple[int, int, int, int],
    signal_rows: Sequence[tuple[int, int]],
    rows: Sequence[tuple[int, int]],
    *,
    clip: float | None,
    on_frame: Callable[[], None] | None = None,
) -> tuple[np.ndarray, list[FrameStats], list[FrameStats]]:
    """One pass over the movie: (frame numbers, the signal band's stats, the measuring bands'
    stats) of every frame from ``info.first`` to ``info.last``. Per frame, the rows are
    converted and decoded together, in one call."""
    x0, _, x1, _ = region
    numbers, signal, bands = [], [], []
    split = sum(b - a for a, b in signal_rows)
    container, stream = _stream(info)
    try:
        for index, frame in _decoded(info, container, stream):
            parts = [frame_rgb(frame, info, (x0, ya, x1, yb)) for ya, yb in (*signal_rows, *rows)]
            pixels = decode_log(np.concatenate(parts, axis=0), info.encoding)
            if not np.all(np.isfinite(pixels)):
                raise _error(
                    f"NaN/Inf in frame {index} after decoding (check take.encoding)", info.path
                )
            numbers.append(index)
            signal.append(frame_stats(pixels[:split], None))
            bands.append(frame_stats(pixels[split:], clip))
            if on_frame is not None:
                on_frame()
    finally:
        container.close()
    return np.array(numbers, dtype=np.float64), signal, bands


#: A band of a movie's rows holds at least this many pixels (a 4K wall: two rows).
BAND_PIXELS = 2048


def movie_rows(region: tuple[int, int, int, int], bands: int) -> list[tuple[int, int]]:
    """``bands`` bands of an even number of rows (at least two, at least
    :data:`BAND_PIXELS` pixels), spread evenly over ``region``, starting on even rows (a
    4:2:0 chroma row covers each pair); all the region's rows when that is less. A movie is
    decoded whole anyway, so a band needs no more rows than the statistics do.

    Examples
    --------
    >>> movie_rows((0, 10, 3000, 50), 4)
    [(10, 12), (22, 24), (34, 36), (48, 50)]
    >>> movie_rows((0, 10, 100, 50), 4)
    [(10, 50)]
    """
    x0, y0, x1, y1 = region
    height = max(2, -(-BAND_PIXELS // max(1, x1 - x0)))
    height += height % 2
    first, last = y0 + (y0 % 2), y1 - height
    if bands * height >= y1 - y0 or last < first:
        return [(y0, y1)]
    starts = np.unique(np.linspace(first, last, bands).round().astype(int) // 2 * 2)
    return [(int(s), int(s) + height) for s in starts]


def decode_frame(info: MovieInfo, index: int):  # -> av.VideoFrame
    """Frame ``index`` (0 = the file's first), found by seeking (a keyframe at or before it,
    then decoding forward)."""
    container, stream = _stream(info, "SLICE")
    try:
        target, tick = None, 0.0
        if stream.time_base:
            tick = float(1 / (info.rate * stream.time_base))
            target = int((stream.start_time or 0) + round(index * tick))
            container.seek(target, stream=stream, backward=True, any_frame=False)
        everything = replace(info, first=0, last=None, frames=0)
        for number, frame in _decoded(everything, container, stream):
            if target is None and number == index:
                return frame
            if target is not None and frame.pts is not None and frame.pts >= target - tick / 2:
                return frame
    finally:
        container.close()
    raise _error(f"cannot decode frame {index}", info.path)


def read_movie_frame(
    info: MovieInfo, index: int
) -> Callable[[tuple[int, int, int, int]], np.ndarray]:
    """A reader of frame ``index``'s linear RGB in a box (the contact sheet's picture)."""
    frame = decode_frame(info, index)
    return lambda box: decode_log(frame_rgb(frame, info, box), info.encoding)


#: Pixels averaged per cell and axis by :func:`reduced_frame`.
_CELL_SAMPLES = 4


def reduced_frame(info: MovieInfo, index: int, factor: int) -> np.ndarray:
    """Frame ``index`` on a grid of ``factor`` x ``factor`` cells, (cells_y, cells_x, 3) linear
    RGB: each cell the mean code values of a few pixels spread inside it, then converted
    (for finding the wall; not for measuring)."""
    frame = decode_frame(info, index)
    cells_x, cells_y = info.width // factor, info.height // factor
    n = min(factor, _CELL_SAMPLES)
    offsets = (np.arange(n) * factor) // n + (factor // n) // 2
    ys = (np.arange(cells_y)[:, None] * factor + offsets[None, :]).ravel()
    xs = (np.arange(cells_x)[:, None] * factor + offsets[None, :]).ravel()
    sx, sy = info.subsampling  # (1, 1) for an RGB stream
    planes = []
    for k in range(3):
        plane = _plane(frame, k, info.bits)
        rows, cols = (ys, xs) if k == 0 else (ys // sy, xs // sx)
        values = plane[np.ix_(rows, cols)].astype(np.float32)
        planes.append(values.reshape(cells_y, n, cells_x, n).mean(axis=(1, 3)))
    return decode_log(_planes_rgb(planes, info), info.encoding)
