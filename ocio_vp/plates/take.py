"""Measuring one continuous camera take of a pattern sequence (``take`` in a capture file;
docs/capture.md, *The take*, gives the steps and the refusals).

The wall's region is given or found (:mod:`ocio_vp.plates.wall_region`); a band of rows at its
middle aligns the take with the sequence (:mod:`ocio_vp.plates.alignment`); each patch's stable
frames are averaged over a few bands of rows (:mod:`ocio_vp.plates.take_reader`) into a
:class:`TakeReading`: each patch's mean camera RGB, black not subtracted.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.patterns.sequence import MEASURED_KINDS, Patch, PatternSequence
from ocio_vp.plates.alignment import GUARD, Alignment, align_take, kept_frames
from ocio_vp.plates.movie import (
    MovieInfo,
    is_movie,
    movie_rows,
    open_movie,
    read_movie_frame,
    reduced_frame,
    scan_movie,
)
from ocio_vp.plates.reader import PlateInfo, check_box, linearise, open_plate, read_region
from ocio_vp.plates.take_reader import (
    FrameStats,
    band_rows,
    chunk_rows,
    list_take_frames,
    read_frame_stats,
)

__all__ = [
    "BANDS",
    "CLIPPED_FRACTION",
    "UNDER_EXPOSED_STOPS",
    "PatchReading",
    "TakeReading",
    "TakeRef",
    "measure_take",
    "rows_read",
]

#: Bands of rows read per kept frame (each a whole number of the file's chunks).
BANDS = 8
#: White or a primary is clipped when this fraction of its pixels reaches the clip level.
CLIPPED_FRACTION = 1e-3
#: White this many stops or more below full code is under-exposed in a linear integer take
#: (16-bit linear: the ramps' darkest steps would fall under a few code values).
UNDER_EXPOSED_STOPS = 5.0
#: White less than this many times the black's pixel noise is under-exposed (any take).
MIN_WHITE_SNR = 20.0
#: A frame straying from its patch's median by more than this (relative) and
#: :data:`STRAY_SIGMAS` robust sigmas is not stable.
STRAY_RELATIVE = 0.05
STRAY_SIGMAS = 6.0


@dataclass(frozen=True)
class TakeRef:
    """A take as the capture file describes it (paths resolved against the capture file)."""

    frames: Path
    sequence: Path
    region: tuple[int, int, int, int] | None = None
    encoding: str | None = None
    layer: str | None = None
    clip_level: float | None = None
    key: str = "take"
    #: A movie's part to measure (frame numbers from 0, or timecode) and the Y'CbCr matrix
    #: and range when the stream does not declare them (:mod:`ocio_vp.plates.movie`).
    in_point: int | str | None = None
    out_point: int | str | None = None
    matrix: str | None = None
    range: str | None = None


@dataclass(frozen=True)
class PatchReading:
    """One patch measured: mean linear camera RGB over the frames kept, black not subtracted;
    ``spread`` the standard deviation of the kept frames' means (flicker and noise)."""

    name: str
    kind: str
    mean: np.ndarray
    spread: np.ndarray
    frames: tuple[int, ...]
    rejected: tuple[int, ...]
    pixels: int
    window: tuple[float, float]


@dataclass(frozen=True)
class TakeReading:
    """A take measured against its sequence (see the module docstring)."""

    take: TakeRef
    sequence: PatternSequence
    info: PlateInfo
    region: tuple[int, int, int, int]
    region_found: bool
    numbers: np.ndarray
    signal: np.ndarray
    alignment: Alignment
    patches: Mapping[str, PatchReading]
    warnings: tuple[str, ...] = ()
    clip_level: float | None = None
    paths: tuple[Path, ...] = field(default=(), repr=False)
    #: The movie the take was read from (``paths`` is then that one file), else None.
    movie: MovieInfo | None = None

    def frame_reader(self, index: int) -> Callable[[tuple[int, int, int, int]], np.ndarray]:
        """``read(box)`` of the frame at position ``index`` of :attr:`numbers` (linear RGB)."""
        if self.movie is not None:
            return read_movie_frame(self.movie, int(self.numbers[index]))
        frame = dataclasses.replace(self.info, path=str(self.paths[index]))
        return lambda box: read_region(frame, box)

    @property
    def black(self) -> np.ndarray:
        return self.patches["black"].mean

    def net(self, name: str) -> np.ndarray:
        """A patch's mean with the black patch subtracted."""
        return self.patches[name].mean - self.black


def _clip_level(info: PlateInfo, given: float | None) -> float | None:
    """The linear value of full code for integer takes; the given level for float ones."""
    if given is not None:
        return float(given)
    if info.is_float:
        return None
    return float(np.max(linearise(np.ones(3), info.encoding)))


def _window_check(
    reading_times: np.ndarray, alignment: Alignment, patch: Patch, source: object, key: str
) -> tuple[float, float]:
    start, end = (float(v) for v in alignment.to_camera(np.array([patch.first, patch.last + 1.0])))
    first, last = float(reading_times[0]), float(reading_times[-1])
    if end - GUARD > last:
        missing = math.ceil(end - last)
        raise InputError(
            f"the take is truncated: it ends at frame {int(last)}, before patch {patch.name!r} "
            f"(about {missing} more frames were needed); record the whole sequence",
            source=source,
            key=key,
        )
    if start + GUARD < first:
        raise InputError(
            f"the take starts at frame {int(first)}, after patch {patch.name!r} began; roll the "
            "camera before the player starts",
            source=source,
            key=key,
        )
    return start, end


def _stable(values: np.ndarray, floor: float) -> np.ndarray:
    """Mask of the frames whose mean stays near the patch's median (:data:`STRAY_RELATIVE`
    and :data:`STRAY_SIGMAS`)."""
    median = np.median(values, axis=0)
    scale = max(float(np.max(np.abs(median))), floor)
    deviation = np.max(np.abs(values - median), axis=1) / scale
    sigma = 1.4826 * float(np.median(np.abs(deviation - np.median(deviation))))
    return deviation <= max(STRAY_RELATIVE, STRAY_SIGMAS * sigma)


def _reading(patch: Patch, numbers, kept, stats: list[FrameStats], floor, window) -> PatchReading:
    means = np.array([s.mean for s in stats])
    stable = _stable(means, floor)
    chosen = means[stable]
    return PatchReading(
        name=patch.name,
        kind=patch.kind,
        mean=chosen.mean(axis=0),
        spread=chosen.std(axis=0) if len(chosen) > 1 else np.zeros(3),
        frames=tuple(int(numbers[i]) for i in kept[stable]),
        rejected=tuple(int(numbers[i]) for i in kept[~stable]),
        pixels=int(stats[0].count),
        window=window,
    )


def _check_length(count: int, take: TakeRef, source) -> None:
    if count < 8:
        message = f"the take has {count} frames: too short to hold the sequence"
        raise InputError(message, source=source, key=take.key)


def _patch_frames(measured, alignment: Alignment, numbers: np.ndarray, source, key: str):
    """Per measured patch, its window in camera frames and the frames kept (refusing a
    truncated take and a patch too short for the camera)."""
    windows, kept = {}, {}
    for patch in measured:
        windows[patch.name] = _window_check(numbers, alignment, patch, source, key)
        kept[patch.name] = kept_frames(alignment, patch, numbers)
        if len(kept[patch.name]) == 0:
            raise InputError(
                f"patch {patch.name!r} has no stable frame: it lasts "
                f"{alignment.rate * patch.frames:.1f} camera frames and {GUARD:g} are left out "
                "next to each change; play the patterns with a longer --hold",
                source=source,
                key=key,
            )
    return windows, kept


def rows_read(
    info: PlateInfo, region: tuple[int, int, int, int], movie: MovieInfo | None
) -> tuple[list[tuple[int, int]], list[tuple[int, int]]]:
    """(the band of rows at the region's middle the alignment reads, the :data:`BANDS` bands
    read in each kept frame): whole chunks of an image file; a few rows of a movie
    (:func:`ocio_vp.plates.movie.movie_rows`)."""
    if movie is not None:
        middle = movie_rows(region, 1)[0]
        centre = (region[1] + region[3] - (middle[1] - middle[0])) // 4 * 2
        centre = min(max(centre, region[1]), region[3] - (middle[1] - middle[0]))
        return [(centre, centre + middle[1] - middle[0])], movie_rows(region, BANDS)
    chunk = chunk_rows(info.path)
    return band_rows(info, region, 1, chunk)[:1], band_rows(info, region, BANDS, chunk)


@dataclass(frozen=True)
class _Scan:
    """What one pass over the take gave: frame numbers, the alignment's per-frame signal, and
    a function giving the measuring bands' stats of frames by position (reading them then,
    for a sequence of files; kept from the pass, for a movie)."""

    numbers: np.ndarray
    signal: np.ndarray
    bands: Callable[[np.ndarray], list[FrameStats]]


def _open_frames(
    take: TakeRef, source
) -> tuple[np.ndarray, list[Path], PlateInfo, MovieInfo | None]:
    """The take's frame numbers, files, header and (for a movie) the movie's header."""
    if not is_movie(take.frames):
        listed = list_take_frames(take.frames)
        _check_length(len(listed), take, source)
        numbers = np.array([n for n, _ in listed], dtype=np.float64)  # the time coordinate
        paths = [p for _, p in listed]
        return numbers, paths, open_plate(paths[0], encoding=take.encoding, layer=take.layer), None
    movie = open_movie(
        take.frames,
        encoding=take.encoding,
        matrix=take.matrix,
        range_=take.range,
        in_point=take.in_point,
        out_point=take.out_point,
    )
    end = movie.last + 1 if movie.last is not None else max(movie.frames, movie.first + 1)
    numbers = np.arange(movie.first, end, dtype=np.float64)
    return numbers, [take.frames], movie.plate_info(), movie


def _scan(take, frames, region, clip, on_progress, source) -> _Scan:
    """The pass over every frame (see :class:`_Scan`)."""
    numbers, paths, info, movie = frames
    tick = (lambda: on_progress("frame", 1)) if on_progress else None
    signal_rows, rows = rows_read(info, region, movie)
    if movie is not None:
        if on_progress:
            on_progress("decoding", len(numbers))
        numbers, signal_stats, band_stats = scan_movie(
            movie, region, signal_rows, rows, clip=clip, on_frame=tick
        )
        _check_length(len(numbers), take, source)
        return _Scan(
            numbers,
            np.array([s.mean for s in signal_stats]),
            lambda wanted: [band_stats[i] for i in wanted.tolist()],
        )
    if on_progress:
        on_progress("aligning", len(paths))
    signal_stats = read_frame_stats(paths, info, region, signal_rows, on_frame=tick)

    def bands(wanted: np.ndarray) -> list[FrameStats]:
        if on_progress:
            on_progress("measuring", len(wanted))
        return read_frame_stats(
            [paths[i] for i in wanted], info, region, rows, clip=clip, on_frame=tick
        )

    return _Scan(numbers, np.array([s.mean for s in signal_stats]), bands)


def measure_take(
    take: TakeRef,
    *,
    source: object = None,
    on_progress: Callable[[str, int], None] | None = None,
) -> TakeReading:
    """Measure ``take`` against its sequence (see the module docstring).

    ``on_progress(stage, frames)`` is called before each pass over frames ("aligning",
    "measuring"; "decoding" for a movie's one pass) with the number of frames it will read,
    then with ("frame", 1) per frame.

    Raises
    ------
    InputError
        One line naming the capture file (``source``), the ``take`` key and the problem.
    """
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.plates.wall_region import find_wall

    sequence = load_sequence(take.sequence)
    frames = _open_frames(take, source)
    numbers, paths, info, movie = frames
    region = take.region
    if region is None:
        reader = None
        if movie is not None:
            reader = (len(numbers), lambda k, f: reduced_frame(movie, int(numbers[k]), f))
        where = f"{source}: {take.key}" if source else None
        region = find_wall(paths, info, source=where, frames=reader)
    else:
        check_box(info, region)
    clip = _clip_level(info, take.clip_level)
    scan = _scan(take, frames, region, clip, on_progress, source)
    numbers, signal = scan.numbers, scan.signal
    alignment = align_take(signal, numbers, sequence, source=source)
    measured = [p for p in sequence.patches if p.kind in MEASURED_KINDS]
    windows, kept = _patch_frames(measured, alignment, numbers, source, take.key)
    wanted = np.unique(np.concatenate(list(kept.values())))
    by_index = dict(zip(wanted.tolist(), scan.bands(wanted), strict=True))
    floor = 2e-3 * float(np.max(np.percentile(signal, 99.5, axis=0)))
    patches = {
        p.name: _reading(
            p,
            numbers,
            kept[p.name],
            [by_index[i] for i in kept[p.name].tolist()],
            floor,
            windows[p.name],
        )
        for p in measured
    }
    reading = TakeReading(
        take=take,
        sequence=sequence,
        info=info,
        region=region,
        region_found=take.region is None,
        numbers=numbers,
        signal=signal,
        alignment=alignment,
        patches=patches,
        clip_level=clip,
        paths=tuple(paths),
        movie=movie,
    )
    _check_exposure(reading, by_index, kept, source)
    return dataclasses.replace(reading, warnings=tuple(_alignment_notes(reading)))


def _alignment_notes(reading: TakeReading) -> list[str]:
    a = reading.alignment
    notes = []
    for T, frames in a.steps:
        what = "dropped" if frames < 0 else "repeated"
        notes.append(
            f"{reading.take.key}: {abs(frames)} camera frame(s) {what} near sequence frame "
            f"{T:g}; the patches on either side are placed apart"
        )
    rejected = [(p.name, len(p.rejected)) for p in reading.patches.values() if p.rejected]
    if rejected:
        listed = ", ".join(f"{name} ({n})" for name, n in rejected[:6])
        more = f" and {len(rejected) - 6} more patches" if len(rejected) > 6 else ""
        notes.append(f"{reading.take.key}: unstable frames left out: {listed}{more}")
    return notes


def _clipped(stats: list[FrameStats], clip: float | None) -> tuple[bool, float | None]:
    """Whether most frames have CLIPPED_FRACTION of their pixels at the clip level (or, with
    no clip level, on a shared flat top), and that level."""
    hits, level = 0, None
    for s in stats:
        if clip is not None:
            if np.any(s.at_clip >= max(4, CLIPPED_FRACTION * s.count)):
                hits += 1
                level = clip
        else:
            channel = int(np.argmax(s.at_peak))
            if s.at_peak[channel] >= max(4, CLIPPED_FRACTION * s.count):
                hits += 1
                level = float(s.peak[channel])
    return hits > len(stats) / 2, level


def _bright_patches(reading: TakeReading) -> tuple[str, list[str]]:
    """(the reference patch, the patches judged for clipping): white and the primaries of a
    calibration take; the brightest chart patch, and every chart patch, of a validation one."""
    if "white" in reading.patches:
        return "white", ["white", *(p.name for p in reading.sequence.of_kind("primary"))]
    charts = [p.name for p in reading.sequence.of_kind("chart")] or list(reading.patches)
    brightest = max(charts, key=lambda name: float(np.max(reading.net(name))))
    return brightest, charts


def _check_exposure(reading: TakeReading, by_index, kept, source) -> None:
    """Refuse clipping (:data:`CLIPPED_FRACTION`) and under-exposure (:data:`MIN_WHITE_SNR`,
    :data:`UNDER_EXPOSED_STOPS`)."""
    key = reading.take.key
    clip = reading.clip_level
    reference, judged = _bright_patches(reading)
    primaries = [p.name for p in reading.sequence.of_kind("primary")]
    states = {name: _clipped([by_index[i] for i in kept[name].tolist()], clip) for name in judged}
    clipped = [name for name, (state, _) in states.items() if state]
    if clipped:
        level = next(states[name][1] for name in clipped)
        if any(name in primaries for name in clipped) or reference != "white" or not level:
            advice = "close the iris by at least 1 stop and shoot again"
        else:
            predicted = reading.black + sum(reading.net(name) for name in primaries)
            stops = math.log2(max(float(np.max(predicted)) / level, 1.0)) + 1 / 3
            advice = f"close the iris by about {math.ceil(stops * 2) / 2:g} stop(s) and shoot again"
        names = ", ".join(clipped[:4]) + (
            f" and {len(clipped) - 4} more" if len(clipped) > 4 else ""
        )
        raise InputError(
            f"clipped in camera: {names} (pixels at the clip level {level:.6g}); {advice}",
            source=source,
            key=key,
        )
    white = reading.net(reference)
    if not float(np.max(white)) > 0:
        raise InputError(
            f"the {reference} patch reads no brighter than black: was the wall lit?",
            source=source,
            key=key,
        )
    if reference == "white":
        _check_matches(reading, source)
    if clip is not None and not reading.info.is_float and reading.info.encoding == "linear":
        stops = math.log2(clip / float(np.max(white + reading.black)))
        if stops >= UNDER_EXPOSED_STOPS:
            raise InputError(
                f"under-exposed: {reference} is {stops:.1f} stops below full code of this linear "
                f"integer take; open up by about {math.floor((stops - 1) * 2) / 2:g} stops "
                "(white about 1 stop under clip)",
                source=source,
                key=key,
            )
    black_frames = [by_index[i] for i in kept["black"].tolist()]
    noise = float(np.max(np.mean([s.std for s in black_frames], axis=0)))
    if noise > 0 and float(np.max(white)) < MIN_WHITE_SNR * noise:
        raise InputError(
            f"under-exposed: {reference} is only {float(np.max(white)) / noise:.1f} times the "
            f"black's pixel noise (at least {MIN_WHITE_SNR:g} needed); open up",
            source=source,
            key=key,
        )


def _check_matches(reading: TakeReading, source) -> None:
    """White holds every primary, black is darker than white: else not this sequence."""
    white = reading.net("white")
    for patch in reading.sequence.of_kind("primary"):
        net = reading.net(patch.name)
        if np.any(net > 1.2 * white + 1e-9 * np.max(white)):
            raise InputError(
                f"the take does not match the sequence: {patch.name} reads brighter than white "
                "in some channel; is take.sequence the sequence that was played?",
                source=source,
                key=reading.take.key,
            )
