"""Reading a camera take: its numbered frames, and statistics of bands of rows of each.

Only bands of rows inside the wall's region are decoded, whole chunks of the file's scanlines,
and per frame only :class:`FrameStats` is kept, so memory does not grow with the take's length;
frames are read on a few threads (OpenImageIO decodes without holding Python's lock).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.plates.reader import PlateInfo, check_read, linearise, open_input

__all__ = [
    "FrameStats",
    "band_rows",
    "chunk_rows",
    "frame_stats",
    "list_take_frames",
    "read_frame_stats",
    "take_threads",
]

#: Scanlines per chunk of an OpenEXR file, by compression (OpenEXR's documentation).
_EXR_CHUNK = {
    "none": 1,
    "rle": 1,
    "zips": 1,
    "zip": 16,
    "piz": 32,
    "pxr24": 16,
    "b44": 32,
    "b44a": 32,
    "dwaa": 32,
    "dwab": 256,
    "htj2k": 32,
}
_MAX_TAKE_FRAMES = 1_000_000
#: A band has at least this many rows (fewer makes too many small reads).
_MIN_BAND = 16


@dataclass(frozen=True)
class FrameStats:
    """Statistics of one frame's sampled pixels (linear RGB, float64 sums).

    ``peak``: the brightest value per channel; ``at_peak``: pixels within 1e-6 of it (a clipped
    sensor gives many); ``at_clip``: pixels at or above the clip level, when one is known.
    """

    count: int
    total: np.ndarray
    squares: np.ndarray
    peak: np.ndarray
    at_peak: np.ndarray
    at_clip: np.ndarray

    @property
    def mean(self) -> np.ndarray:
        return self.total / max(self.count, 1)

    @property
    def std(self) -> np.ndarray:
        variance = self.squares / max(self.count, 1) - self.mean**2
        return np.sqrt(np.maximum(variance, 0.0))


def list_take_frames(pattern: str | Path) -> list[tuple[int, Path]]:
    """(frame number, path) of every file matching ``pattern`` (one run of ``#`` standing for
    the zero-padded frame number, e.g. ``take/A001.####.exr``), by number.

    Raises
    ------
    InputError
        No ``#`` run, or no file matching.
    """
    path = Path(pattern)
    match = re.fullmatch(r"([^#]*)(#+)([^#]*)", path.name)
    if match is None:
        raise InputError(
            "expected a frame pattern with one run of '#', e.g. A001.####.exr", source=pattern
        )
    prefix, hashes, suffix = match.groups()
    digits = r"\d+" if len(hashes) == 1 else rf"\d{{{len(hashes)},}}"
    regex = re.compile(re.escape(prefix) + f"({digits})" + re.escape(suffix))
    folder = path.parent
    found = []
    if folder.is_dir():
        with os.scandir(folder) as entries:
            for entry in entries:
                m = regex.fullmatch(entry.name)
                if m and entry.is_file():
                    found.append((int(m.group(1)), folder / entry.name))
                    if len(found) > _MAX_TAKE_FRAMES:
                        raise InputError(f"more than {_MAX_TAKE_FRAMES} frames", source=pattern)
    if not found:
        raise InputError("no frames match this pattern", source=pattern)
    return sorted(found)


def chunk_rows(path: str | Path) -> int:
    """Rows per stored chunk (scanlines decoded together) of an image file."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        return 1
    try:
        spec = inp.spec()
        name = str(inp.format_name())
        if spec.tile_height:
            return int(spec.tile_height)
        if name == "openexr":
            compression = str(spec.get_string_attribute("compression", "zip")).split(":")[0]
            return _EXR_CHUNK.get(compression.lower(), 16)
        if name == "tiff":
            return max(1, int(spec.get_int_attribute("tiff:RowsPerStrip", 1)))
        return 1
    finally:
        inp.close()


def band_rows(
    info: PlateInfo, region: tuple[int, int, int, int], bands: int, chunk: int
) -> list[tuple[int, int]]:
    """``bands`` row ranges inside ``region``'s rows, evenly spread, whole chunks aligned to the
    data window (all the region's rows when that is less)."""
    _, y0, _, y1 = region
    height = max(_MIN_BAND, chunk)
    if bands * height >= y1 - y0:
        return [(y0, y1)]
    out: list[tuple[int, int]] = []
    for centre in np.linspace(y0 + height / 2, y1 - height / 2, bands):
        start = int(info.y + (int(centre - height / 2) - info.y) // chunk * chunk)
        start = min(max(start, y0), y1 - height)
        band = (start, start + height)
        if not out or band[0] >= out[-1][1]:
            out.append(band)
    return out


def frame_stats(pixels: np.ndarray, clip: float | None) -> FrameStats:
    """:class:`FrameStats` of linear RGB ``pixels`` (..., 3); ``clip`` the clip level if known.
    The channels are laid out one after the other first (contiguous reductions are faster)."""
    channels = np.ascontiguousarray(np.asarray(pixels, dtype=np.float64).reshape(-1, 3).T)
    peak = channels.max(axis=1)
    return FrameStats(
        count=int(channels.shape[1]),
        total=channels.sum(axis=1),
        squares=np.einsum("ij,ij->i", channels, channels),
        peak=peak,
        at_peak=np.count_nonzero(channels >= (peak - 1e-6 * np.abs(peak))[:, None], axis=1),
        at_clip=np.zeros(3, np.int64)
        if clip is None
        else np.count_nonzero(channels >= clip * (1 - 1e-6), axis=1),
    )


def _read_frame(
    path: Path,
    info: PlateInfo,
    region: tuple[int, int, int, int],
    rows: Sequence[tuple[int, int]],
    clip: float | None,
) -> FrameStats:
    import OpenImageIO as oiio

    x0, _, x1, _ = region
    ch0, ch1 = min(info.rgb), max(info.rgb) + 1
    select = [c - ch0 for c in info.rgb]
    inp = open_input(str(path), "frame")
    try:
        spec = inp.spec()
        if (spec.x, spec.y, spec.width, spec.height) != (info.x, info.y, info.width, info.height):
            raise InputError(
                f"frame size {spec.width}x{spec.height} differs from the take's first frame "
                f"({info.width}x{info.height})",
                source=path,
            )
        parts = []
        for ya, yb in rows:
            data = inp.read_scanlines(info.subimage, 0, ya, yb, 0, ch0, ch1, oiio.FLOAT)
            data = check_read(data, inp, str(path), (yb - ya, info.width, ch1 - ch0))
            parts.append(data[:, x0 - info.x : x1 - info.x][..., select])
    finally:
        inp.close()
    pixels = np.concatenate(parts, axis=0)
    if not np.all(np.isfinite(pixels)):
        raise InputError("NaN/Inf pixels in the wall region", source=path)
    if info.encoding != "linear":
        pixels = linearise(pixels, info.encoding)
    return frame_stats(pixels, clip)


def take_threads() -> int:
    """Threads reading frames: the cores this process may use, at most 8."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cores = os.cpu_count() or 1
    return max(1, min(8, cores))


def read_frame_stats(
    paths: Sequence[Path],
    info: PlateInfo,
    region: tuple[int, int, int, int],
    rows: Sequence[tuple[int, int]],
    *,
    clip: float | None = None,
    on_frame: Callable[[], None] | None = None,
) -> list[FrameStats]:
    """:class:`FrameStats` of ``rows`` x the region's columns of every frame, in order."""

    def one(path: Path) -> FrameStats:
        stats = _read_frame(path, info, region, rows, clip)
        if on_frame is not None:
            on_frame()
        return stats

    threads = take_threads()
    if threads == 1 or len(paths) < 4:
        return [one(p) for p in paths]
    with ThreadPoolExecutor(threads) as pool:
        return list(pool.map(one, paths))
