"""The calibration sequence: what the wall plays, frame by frame, and at which code values.

Its layout, the sync marks (``sync_g``: ``g + 2`` white flashes that place a take in time,
:mod:`ocio_vp.plates.alignment`), the ramps (spaced evenly in the wall's own signal, in gamma
2.4 for a linear wall) and the code values each file format holds: docs/patterns.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocio_vp.choices import DEFAULT_PEAK_NITS, WALL_ENCODINGS
from ocio_vp.errors import InputError
from ocio_vp.patterns.sequence import FILE_FORMATS, Patch, PatternSequence
from ocio_vp.wall.encoding import decode, encode
from ocio_vp.wall.linearity import CHANNELS

__all__ = [
    "DEFAULT_FPS",
    "DEFAULT_HOLD",
    "DEFAULT_SIZE",
    "DEFAULT_STEPS",
    "PatternOptions",
    "SequenceBuilder",
    "calibration_sequence",
    "flash_frames",
    "quantise",
    "ramp_drives",
    "ramp_levels",
]

DEFAULT_FPS = 24.0
#: Frames per patch: half a second at 24 fps leaves ~8 unblended frames per patch to a camera
#: at 25 fps after 2 guard frames each side (docs/patterns.md).
DEFAULT_HOLD = 12
#: Ramp steps per channel, the zero and the full-drive step included.
DEFAULT_STEPS = 17
DEFAULT_SIZE = (1920, 1080)
#: A flash lasts this long (at least 2 frames): short next to a patch, long next to a frame.
FLASH_SECONDS = 1.0 / 6.0
#: Black before and after the patterns, in seconds (a camera started late loses only this).
LEAD_SECONDS = 1.0
_PRIMARY = {c: tuple(float(i == k) for i in range(3)) for k, c in enumerate(CHANNELS)}


@dataclass(frozen=True)
class PatternOptions:
    """How ``ocio-vp patterns`` writes a sequence (every option of the command)."""

    fps: float = DEFAULT_FPS
    hold: int = DEFAULT_HOLD
    steps: int = DEFAULT_STEPS
    encoding: str = "linear"
    peak_nits: float | None = None
    size: tuple[int, int] = DEFAULT_SIZE
    file_format: str = "exr"
    first_frame: int = 1
    name: str = "patterns"

    def __post_init__(self) -> None:
        if self.encoding not in WALL_ENCODINGS:
            raise InputError(f"expected one of {WALL_ENCODINGS}", key="--wall-encoding")
        if (self.encoding == "pq") != (self.peak_nits is not None):
            raise InputError(
                "give --peak-nits with --wall-encoding pq, and only then", key="--peak-nits"
            )
        if self.peak_nits is not None and not 0 < self.peak_nits <= 10000:
            raise InputError(
                f"expected 0 < cd/m2 <= 10000, got {self.peak_nits:g}", key="--peak-nits"
            )
        if self.file_format not in FILE_FORMATS:
            raise InputError(f"expected one of {tuple(FILE_FORMATS)}", key="--format")
        if not 0 < self.fps <= 1000:
            raise InputError(f"expected 0 < fps <= 1000, got {self.fps:g}", key="--fps")
        if not 2 <= self.hold <= 10000:
            raise InputError(f"expected 2 <= frames <= 10000, got {self.hold}", key="--hold")
        if not 4 <= self.steps <= 1024:
            raise InputError(f"expected 4 <= steps <= 1024, got {self.steps}", key="--steps")
        width, height = self.size
        if not (1 <= width <= 16384 and 1 <= height <= 16384):
            raise InputError(f"expected 1..16384 pixels a side, got {width}x{height}", key="--size")

    def frame_pattern(self, last_frame: int) -> str:
        """``<name>.####.<ext>``, as many ``#`` as the last frame number needs (at least 4)."""
        extension = {"exr": "exr", "tiff": "tif", "dpx": "dpx"}[self.file_format]
        digits = max(4, len(str(abs(last_frame))), len(str(abs(self.first_frame))))
        return f"{self.name}.{'#' * digits}.{extension}"

    @property
    def max_code(self) -> int:
        return 2 ** FILE_FORMATS[self.file_format] - 1


def _triple(values: np.ndarray) -> tuple[float, float, float]:
    r, g, b = (float(v) for v in values)
    return r, g, b


def flash_frames(fps: float) -> int:
    """Frames per sync flash (and per gap between flashes): ~1/6 s, at least 2."""
    return max(2, round(fps * FLASH_SECONDS))


def quantise(drive: np.ndarray, options: PatternOptions) -> tuple[np.ndarray, np.ndarray]:
    """(drive shown, signal written) for requested linear ``drive`` (..., 3).

    EXR: the half-float drive (both the same). TIFF/DPX: the code value of the encoded drive,
    as a fraction of full code, and its decoded drive normalised at the top code.

    Examples
    --------
    >>> o = PatternOptions(file_format="tiff", encoding="pq", peak_nits=1000.0)
    >>> drive, signal = quantise(np.array([1.0, 0.5, 0.0]), o)
    >>> [round(float(v), 5) for v in drive], [round(float(v) * 65535) for v in signal]
    ([1.0, 0.5, 0.0], [49271, 44340, 0])
    """
    drive = np.maximum(np.asarray(drive, dtype=np.float64), 0.0)
    if options.file_format == "exr":
        half = drive.astype(np.float16).astype(np.float64)
        return half, half
    peak, top = options.peak_nits or DEFAULT_PEAK_NITS, options.max_code
    codes = np.round(encode(drive, options.encoding, peak_nits=peak) * top)
    top_code = np.round(encode(np.array(1.0), options.encoding, peak_nits=peak) * top)
    signal = np.minimum(codes, top) / top
    shown = decode(signal, options.encoding, peak_nits=peak)
    return shown / float(decode(top_code / top, options.encoding, peak_nits=peak)), signal


def ramp_levels(options: PatternOptions) -> tuple[np.ndarray, np.ndarray]:
    """(drive shown, signal written) of a ramp's steps: 0 ... 1.0, evenly spaced in the wall's
    signal (rounded to code values: integer formats round the spaced signal itself).

    Raises
    ------
    InputError
        When the frames' code values cannot hold that many distinct steps.
    """
    # Spaced in the wall's signal, or in gamma 2.4 for a linear wall.
    encoding = "gamma2.4" if options.encoding == "linear" else options.encoding
    peak = options.peak_nits or DEFAULT_PEAK_NITS
    top = float(encode(np.array(1.0), encoding, peak_nits=peak))
    top = 1.0 if abs(top - 1.0) < 1e-12 else top  # sRGB's 1.055 - 0.055 is 1 - 1 ulp
    spaced = np.linspace(0.0, top, options.steps)
    if options.file_format == "exr" or encoding != options.encoding:
        wanted = decode(spaced, encoding, peak_nits=peak)
        wanted[-1] = 1.0
        shown, signal = quantise(wanted, options)
    else:
        codes = np.round(spaced * options.max_code)
        signal = codes / options.max_code
        decoded = decode(signal, options.encoding, peak_nits=peak)
        shown = decoded / decoded[-1]
    if np.any(np.diff(shown) <= 0):
        raise InputError(
            f"{options.steps} ramp steps do not fit in distinct {options.file_format} code "
            "values near black; use fewer --steps",
            key="--steps",
        )
    return shown, signal


def ramp_drives(options: PatternOptions) -> np.ndarray:
    """(steps,) the drives of a ramp as shown (see :func:`ramp_levels`).

    Examples
    --------
    >>> d = ramp_drives(PatternOptions(steps=5))
    >>> [round(float(v), 6) for v in d]
    [0.0, 0.035889, 0.189453, 0.501465, 1.0]
    """
    return ramp_levels(options)[0]


@dataclass
class SequenceBuilder:
    """Appends patches one after the other, numbering their frames."""

    options: PatternOptions
    patches: list[Patch] = field(default_factory=list)
    syncs: int = 0

    @property
    def next_frame(self) -> int:
        return self.patches[-1].last + 1 if self.patches else self.options.first_frame

    def add(
        self,
        name: str,
        kind: str,
        drive: Any,
        frames: int | None = None,
        *,
        signal: Any = None,
        **extra: Any,
    ) -> None:
        """Append a patch at requested ``drive`` (quantised here), or at a drive already
        shown with its ``signal`` (a ramp's levels)."""
        if signal is None:
            shown, signal = quantise(np.asarray(drive, dtype=np.float64), self.options)
        else:
            shown = np.asarray(drive, dtype=np.float64)
        first = self.next_frame
        last = first + (self.options.hold if frames is None else frames) - 1
        self.patches.append(
            Patch(
                name=name,
                kind=kind,
                first=first,
                last=last,
                drive=_triple(shown),
                signal=_triple(signal),
                **extra,
            )
        )

    def lead(self, name: str) -> None:
        self.add(name, "lead", (0.0, 0.0, 0.0), max(1, round(LEAD_SECONDS * self.options.fps)))

    def sync(self) -> None:
        """The next sync mark: ``syncs + 2`` flashes (docs/patterns.md, *Sync marks*)."""
        f = flash_frames(self.options.fps)
        count = self.syncs + 2
        first = self.next_frame
        flashes = tuple(
            (first + 2 * f + 2 * f * k, first + 3 * f + 2 * f * k - 1) for k in range(count)
        )
        self.add(
            f"sync_{self.syncs}", "sync", (1.0, 1.0, 1.0), 3 * f + 2 * f * count, flashes=flashes
        )
        self.syncs += 1

    def build(self, **extra: Any) -> PatternSequence:
        o = self.options
        return PatternSequence(
            frames=o.frame_pattern(self.next_frame - 1),
            first_frame=o.first_frame,
            fps=float(o.fps),
            encoding=o.encoding,
            peak_nits=o.peak_nits,
            size=o.size,
            file_format=o.file_format,
            hold=o.hold,
            patches=tuple(self.patches),
            **extra,
        )


def calibration_sequence(options: PatternOptions = PatternOptions()) -> PatternSequence:
    """The calibration sequence (docs/patterns.md, *The sequence*).

    Examples
    --------
    >>> s = calibration_sequence(PatternOptions(steps=5))
    >>> [p.name for p in s.patches][:8]
    ['lead_in', 'sync_0', 'black', 'red', 'green', 'blue', 'white', 'sync_1']
    >>> s.last_frame, round(s.duration, 2)
    (508, 21.17)
    """
    b = SequenceBuilder(options)
    b.lead("lead_in")
    b.sync()
    b.add("black", "black", (0.0, 0.0, 0.0))
    for channel in CHANNELS:
        b.add(channel, "primary", _PRIMARY[channel], channel=channel)
    b.add("white", "white", (1.0, 1.0, 1.0))
    b.sync()
    shown, signals = ramp_levels(options)
    width = max(2, len(str(options.steps - 1)))
    for k, channel in enumerate(CHANNELS):
        for i, (level, code) in enumerate(zip(shown, signals, strict=True)):
            drive, signal = np.zeros(3), np.zeros(3)
            drive[k], signal[k] = level, code
            name = f"ramp_{channel}_{i:0{width}d}"
            b.add(name, "ramp", drive, signal=signal, channel=channel, step=i)
        b.sync()
    b.lead("lead_out")
    return b.build()
