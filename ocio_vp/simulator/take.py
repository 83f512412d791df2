"""A camera filming the wall play a pattern sequence: one continuous, unsynchronised take.

The player shows sequence frame ``f`` during ``[f, f + 1) / fps`` seconds; the camera rolls
``preroll`` seconds earlier at its own rate, and frame ``i`` integrates the wall's light over its
shutter, each row ``readout`` frames later than the one above (rolling shutter). The wall's
drive passes through the panel's response (:class:`PanelResponse`) and [SL]; ``bounce``,
``flicker``, ``flare``, ``spill`` onto a textured set, noise, ``dropped`` frames and a
``truncate``d take are as docs/simulator.md (*The simulated take*) describes. The truth for
the checks is :func:`true_frame_times` and :meth:`PanelResponse.__call__` with [SL].
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.patterns.sequence import FILE_FORMATS, PatternSequence

#: The rolling shutter is modelled in this many bands of rows.
_ROW_BANDS = 64

__all__ = [
    "PanelResponse",
    "TakeOptions",
    "frame_drives",
    "render_frames",
    "take_frame_count",
    "take_signal",
    "true_frame_times",
    "wall_box_pixels",
    "write_take",
]


@dataclass(frozen=True)
class PanelResponse:
    """Light per channel against drive: ``d (1 - a exp(-d / knee))`` (1.0 at full drive).

    ``a`` per channel: how much darker than linear the wall is near black (0: linear). The
    default, 25 / 15 / 35 %, is within what OpenVPCal's published ramps show (docs/linearity.md).
    """

    darkening: tuple[float, float, float] = (0.25, 0.15, 0.35)
    knee: float = 0.02

    def __call__(self, drive: np.ndarray) -> np.ndarray:
        d = np.maximum(np.asarray(drive, dtype=np.float64), 0.0)
        a = np.asarray(self.darkening, dtype=np.float64)
        return d * (1.0 - a * np.exp(-d / self.knee))


@dataclass(frozen=True)
class TakeOptions:
    """The simulated camera and wall (docs/simulator.md, *The simulated take*). Sizes in
    pixels, times in s; ``wall_box`` in fractions of the frame."""

    fps: float = 25.0
    shutter: float = 0.5
    readout: float = 0.25
    preroll: float = 1.0
    postroll: float = 1.0
    size: tuple[int, int] = (96, 54)
    wall_box: tuple[float, float, float, float] = (0.2, 0.15, 0.85, 0.8)
    spill: float = 0.02
    flare: float = 0.001
    flicker: float = 0.01
    flicker_hz: float = 3.1
    noise: float = 0.01
    read_noise: float = 1e-4
    exposure: float = 1.0
    bounce: tuple[float, float, float] | None = None
    response: PanelResponse = field(default_factory=PanelResponse)
    dropped: tuple[int, ...] = ()
    truncate: int | None = None
    first_frame: int = 1
    seed: int = 0


def _frame_count(sequence: PatternSequence, options: TakeOptions) -> int:
    seconds = options.preroll + sequence.duration + options.postroll
    count = int(np.floor(seconds * options.fps)) + len(options.dropped)
    return count if options.truncate is None else min(count, options.truncate)


def take_frame_count(sequence: PatternSequence, options: TakeOptions) -> int:
    """How many frames :func:`write_take` writes."""
    return len(_recorded(options, _frame_count(sequence, options)))


def _recorded(options: TakeOptions, count: int) -> np.ndarray:
    """Indices of the camera's exposures that reach the take (dropped ones do not)."""
    dropped = set(options.dropped)
    return np.array([i for i in range(count) if i not in dropped], dtype=np.int64)


def true_frame_times(sequence: PatternSequence, options: TakeOptions) -> np.ndarray:
    """Player frame time (``first_frame`` units) at the centre of each recorded frame's
    exposure (middle row): the truth an alignment is judged against."""
    exposures = _recorded(options, _frame_count(sequence, options))
    centre = exposures / options.fps - options.preroll
    centre = centre + (options.shutter + options.readout) / (2 * options.fps)
    return sequence.first_frame + centre * sequence.fps


def frame_drives(sequence: PatternSequence) -> Callable[[np.ndarray], np.ndarray]:
    """Player frame numbers -> (n, 3) drive the wall shows, from the frames on disk when
    they exist (decoded as the wall decodes them), else from ``sequence.yaml``'s drives."""
    table: dict[int, np.ndarray] = {}
    cache: dict[tuple[int, int], np.ndarray] = {}
    for patch in sequence.patches:
        for frame in range(patch.first, patch.last + 1):
            path = sequence.frame_path(frame) if sequence.source else None
            if path is None or not path.exists():
                table[frame] = sequence.drive_at(np.array([frame]))[0]
                continue
            stat = path.stat()
            key = (stat.st_dev, stat.st_ino)
            if key not in cache:
                cache[key] = _read_centre(path)
            value = cache[key]
            if sequence.file_format != "exr":
                full = 2 ** FILE_FORMATS[sequence.file_format] - 1
                value = np.round(value * full) / full  # the code value, as the wall receives it
                value = (
                    _wall_decode(value, sequence)
                    / _wall_decode(np.array([_top_signal(sequence)]), sequence)[0]
                )
            table[frame] = value

    def lookup(frames: np.ndarray) -> np.ndarray:
        out = np.zeros((len(frames), 3))
        for i, f in enumerate(np.asarray(frames, dtype=np.int64)):
            out[i] = table.get(int(f), 0.0)
        return out

    return lookup


def _wall_decode(signal: np.ndarray, sequence: PatternSequence) -> np.ndarray:
    """Light the wall emits for its signal, as colour-science decodes it (an implementation
    independent of :mod:`ocio_vp.wall.encoding`, which wrote the frames): cd/m2 for PQ."""
    import colour

    signal = np.maximum(np.asarray(signal, dtype=np.float64), 0.0)
    if sequence.encoding == "pq":
        return np.asarray(colour.models.eotf_ST2084(signal), dtype=np.float64)
    if sequence.encoding == "srgb":
        return np.asarray(colour.models.eotf_sRGB(signal), dtype=np.float64)
    if sequence.encoding == "gamma2.4":
        return np.asarray(colour.models.gamma_function(signal, 2.4), dtype=np.float64)
    return signal


def _top_signal(sequence: PatternSequence) -> float:
    """The signal of drive 1.0 as written (the white patch's code value)."""
    white = [p for p in sequence.patches if p.kind in ("white", "sync")]
    return float(max(white[0].signal)) if white else 1.0


def _read_centre(path: Path) -> np.ndarray:
    """The value of a flat pattern frame (its centre pixel, as written)."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise OSError(f"{path}: cannot read: {oiio.geterror()}")
    try:
        spec = inp.spec()
        y = spec.y + spec.height // 2
        row = inp.read_scanlines(0, 0, y, y + 1, 0, 0, 3, oiio.FLOAT)
    finally:
        inp.close()
    return np.asarray(row, dtype=np.float64).reshape(-1, 3)[spec.width // 2]


def _wall_frames(
    sequence: PatternSequence, SL: np.ndarray, options: TakeOptions, rows: int
) -> Iterator[tuple[float, np.ndarray]]:
    """Per recorded frame, its flicker gain and the wall's (rows, 3) camera RGB before flicker,
    flare and noise: the panel light (the response to the drive, 1.0 at full drive) integrated
    over each band of rows' exposure through [SL], plus the stage's light bounced off the
    panels (``bounce``, when the environment is lit)."""
    drives = frame_drives(sequence)
    SL = np.asarray(SL, dtype=np.float64)
    fs, fc = sequence.fps, options.fps
    first, last = sequence.first_frame, sequence.last_frame
    delays = options.readout * (np.arange(rows) + 0.5) / rows / fc
    span = options.shutter / fc * fs
    for i in _recorded(options, _frame_count(sequence, options)):
        a = (i / fc - options.preroll + delays) * fs + first  # (rows,) exposure starts
        b = a + span
        frames = np.arange(int(np.floor(a.min())), int(np.floor(b.max())) + 1)
        weights = np.minimum(frames[None] + 1, b[:, None]) - np.maximum(frames[None], a[:, None])
        weights = np.clip(weights, 0.0, None) * ((frames >= first) & (frames <= last))[None]
        light = options.response(drives(frames))
        wall = options.exposure * (weights @ light / span) @ SL.T
        if options.bounce is not None:
            wall = wall + options.exposure * np.asarray(options.bounce, dtype=np.float64)
        t = i / options.fps
        yield 1.0 + options.flicker * np.sin(2 * np.pi * options.flicker_hz * t + 0.3), wall


def wall_box_pixels(options: TakeOptions) -> tuple[int, int, int, int]:
    """The wall's rectangle (x0, y0, x1, y1) in pixels, end-exclusive."""
    width, height = options.size
    x0, y0, x1, y1 = options.wall_box
    return (round(x0 * width), round(y0 * height), round(x1 * width), round(y1 * height))


def take_signal(
    sequence: PatternSequence, SL: np.ndarray, options: TakeOptions = TakeOptions()
) -> tuple[np.ndarray, np.ndarray]:
    """(frame numbers, (n, 3) mean camera RGB of the whole wall box per recorded frame), with
    flicker, flare and the noise of a mean over the box's pixels; no image is rendered."""
    rng = np.random.default_rng(options.seed)
    x0, y0, x1, y1 = wall_box_pixels(options)
    pixels = max(1, (x1 - x0) * (y1 - y0))
    white = options.exposure * np.asarray(SL, dtype=np.float64).sum(axis=1)
    means = []
    for flicker, wall in _wall_frames(sequence, SL, options, 8):
        light = wall.mean(axis=0) * flicker + options.flare * white
        sigma = np.sqrt((options.noise * light) ** 2 + options.read_noise**2) / np.sqrt(pixels)
        means.append(light + sigma * rng.standard_normal(3))
    numbers = options.first_frame + np.arange(len(means))
    return numbers, np.array(means)


def render_frames(
    sequence: PatternSequence, SL: np.ndarray, options: TakeOptions = TakeOptions()
) -> Iterator[np.ndarray]:
    """The take's frames, (height, width, 3) float32 linear camera RGB, in order."""
    width, height = options.size
    rng = np.random.default_rng(options.seed)
    x0, y0, x1, y1 = wall_box_pixels(options)
    white = options.exposure * np.asarray(SL, dtype=np.float64).sum(axis=1)
    ys, xs = np.mgrid[0:height, 0:width]
    texture = 0.03 + 0.02 * np.sin(xs / 7.0) * np.cos(ys / 5.0) + 0.01 * (xs / width)
    set_colour = np.array([1.0, 0.9, 0.75])
    bands = min(height, _ROW_BANDS)
    band_of_row = np.minimum(np.arange(height) * bands // height, bands - 1)
    for flicker, wall in _wall_frames(sequence, SL, options, bands):
        light = wall[band_of_row] * flicker
        mean_light = light[y0:y1].mean(axis=0)
        image = texture[..., None] * set_colour * white + options.spill * mean_light
        image[y0:y1, x0:x1] = light[y0:y1, None, :]
        image = image + options.flare * white
        sigma = np.sqrt((options.noise * image) ** 2 + options.read_noise**2)
        image = image + sigma * rng.standard_normal(image.shape)
        yield image.astype(np.float32)


def write_plate(
    path: str | Path,
    image: ArrayLike,
    *,
    dtype: str = "half",
    channels: tuple[str, ...] = ("R", "G", "B"),
    scale: float = 1.0,
    tile: int = 0,
    compression: str | None = None,
) -> Path:
    """Write ``image * scale`` with OpenImageIO as ``dtype`` ("half", "float", "uint16", ...),
    with the format's default ``compression`` unless one is named.

    Channel names beyond R, G, B get zeros; another order is honoured by name (``layer.R``
    counts as R). Integer types are clipped to [0, 1] first.

    Raises
    ------
    OSError
        When OpenImageIO cannot write the file.
    """
    import OpenImageIO as oiio  # deferred: heavy, and only plate writing needs it

    path = Path(path)
    data = np.asarray(image, dtype=np.float32) * np.float32(scale)
    h, w, _ = data.shape
    planes = []
    for name in channels:
        index = {"R": 0, "G": 1, "B": 2}.get(name.rpartition(".")[2])
        planes.append(data[..., index] if index is not None else np.zeros((h, w), np.float32))
    full = np.ascontiguousarray(np.stack(planes, axis=-1))
    if dtype.startswith("uint"):
        full = np.clip(full, 0, 1)
    spec = oiio.ImageSpec(w, h, len(channels), dtype)
    spec.channelnames = channels
    if tile:
        spec.tile_width = spec.tile_height = tile
    if compression:
        spec.attribute("compression", compression)
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), spec):
        raise OSError(f"{path}: cannot write: {oiio.geterror()}")
    ok = out.write_image(full)
    error = out.geterror()
    out.close()
    if not ok:
        raise OSError(f"{path}: cannot write: {error}")
    return path


def write_take(
    sequence: PatternSequence,
    SL: np.ndarray,
    folder: str | Path,
    options: TakeOptions = TakeOptions(),
    *,
    name: str = "A001",
    file_format: str = "exr",
    encoding: str | None = None,
    on_frame: Callable[[], None] | None = None,
) -> str:
    """Render and write the take as ``folder/<name>.####.<ext>``; returns that pattern's file
    name. ``file_format``: ``exr`` (half float, linear) or ``tiff`` (16-bit, ``encoding`` a
    colour-science encoding such as ``ARRI LogC3``, applied before quantisation)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    extension = {"exr": "exr", "tiff": "tif"}[file_format]
    for k, image in enumerate(render_frames(sequence, SL, options)):
        if encoding is not None:
            import colour

            image = np.asarray(colour.cctf_encoding(np.maximum(image, 0.0), function=encoding))
        path = folder / f"{name}.{options.first_frame + k:04d}.{extension}"
        dtype, compression = ("half", "zip") if file_format == "exr" else ("uint16", None)
        write_plate(path, image, dtype=dtype, compression=compression)
        if on_frame is not None:
            on_frame()
    return f"{name}.####.{extension}"
