"""The pattern sequence and its file, ``sequence.yaml`` (format ``ocio-vp/patterns``, version 1):
which frames hold which patch, at what drive. Other tools may write it, so it is validated like
every file ocio-vp reads; docs/patterns.md documents every key. Frame ``f`` is shown during
``[f, f + 1)`` in units of ``1 / fps`` seconds, from ``first_frame`` on.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.formats.jsontypes import JsonObject, JsonValue, YamlValue
from ocio_vp.formats.measurements import CHANNELS, Validator, read_document

__all__ = [
    "FILE_FORMATS",
    "FORMAT",
    "MEASURED_KINDS",
    "PATCH_KINDS",
    "VERSION",
    "Patch",
    "PatternSequence",
    "Validation",
    "load_sequence",
    "sequence_from_dict",
    "sequence_to_dict",
]

FORMAT = "ocio-vp/patterns"
VERSION = 1
#: ``lead``: black before and after the patterns (not measured); ``sync``: white flashes a
#: take is aligned to; ``black``: the wall at drive 0; ``primary``: one channel at full drive;
#: ``white``: every channel at full drive; ``ramp``: one channel stepped from 0 to full drive;
#: ``chart``: a chart colour sent through a calibration's config (validation).
PATCH_KINDS = ("lead", "sync", "black", "primary", "white", "ramp", "chart")
#: The kinds a take is measured on (the others only place it in time).
MEASURED_KINDS = ("black", "primary", "white", "ramp", "chart")
#: Frame file formats and the bits per sample each is written with.
FILE_FORMATS = {"exr": 16, "tiff": 16, "dpx": 10}
_MAX_FRAMES = 1_000_000
_ONE_FRAME_FIELD = re.compile(r"[^#]*#+[^#]*")


@dataclass(frozen=True)
class Patch:
    """One patch of the sequence: frames ``first``..``last`` (inclusive) show ``drive``.

    ``flashes`` (``sync`` patches): the inclusive frame ranges showing ``drive``, the frames
    between them black. ``channel``/``step``: ramps (and primaries: ``channel``). ``index`` and
    ``content``: a chart patch's position in the chart and the content colour sent through the
    config (validation sequences).
    """

    name: str
    kind: str
    first: int
    last: int
    drive: tuple[float, float, float]
    signal: tuple[float, float, float]
    channel: str | None = None
    step: int | None = None
    flashes: tuple[tuple[int, int], ...] = ()
    index: int | None = None
    content: tuple[float, float, float] | None = None

    @property
    def frames(self) -> int:
        return self.last - self.first + 1


@dataclass(frozen=True)
class Validation:
    """What a validation sequence was made from: an environment's solve and its config."""

    environment: str
    stage: str
    solution_sha256: str
    in_frustum: str
    reference: str
    content_scale: float = 1.0
    #: The solve's model (``diagnostics.model`` or ``method``) and when its ``solution.json``
    #: was written (UTC, ISO 8601): what a refusal names when the solve has changed since.
    model: str | None = None
    solved: str | None = None
    #: Patches pulled into the wall's gamut: (chart index, saturation kept in [0, 1)).
    pulled: tuple[tuple[int, float], ...] = ()


@dataclass(frozen=True)
class PatternSequence:
    """A validated ``sequence.yaml``: the frames, their timing and every patch."""

    frames: str
    first_frame: int
    fps: float
    encoding: str
    peak_nits: float | None
    size: tuple[int, int]
    file_format: str
    hold: int
    patches: tuple[Patch, ...]
    validation: Validation | None = None
    source: str | None = None
    sha256: str | None = None

    @property
    def last_frame(self) -> int:
        return self.patches[-1].last

    @property
    def duration(self) -> float:
        """Seconds from the first frame's start to the last frame's end."""
        return (self.last_frame - self.first_frame + 1) / self.fps

    def of_kind(self, *kinds: str) -> tuple[Patch, ...]:
        return tuple(p for p in self.patches if p.kind in kinds)

    def patch(self, name: str) -> Patch:
        for patch in self.patches:
            if patch.name == name:
                return patch
        raise KeyError(name)

    def frame_path(self, frame: int) -> Path:
        """The file of player frame ``frame`` (``#`` runs replaced, zero-padded)."""
        base = Path(self.source).parent if self.source else Path()
        return base / expand_frame(self.frames, frame)

    def drive_at(self, frames: np.ndarray) -> np.ndarray:
        """(n, 3) linear drive the wall shows at player frames ``frames`` (black outside)."""
        frames = np.asarray(frames, dtype=np.int64)
        out = np.zeros((len(frames), 3))
        starts = np.array([p.first for p in self.patches])
        index = np.searchsorted(starts, frames, side="right") - 1
        for i, (frame, k) in enumerate(zip(frames, index, strict=True)):
            if k < 0 or frame > self.patches[k].last:
                continue
            patch = self.patches[k]
            if patch.kind != "sync" or any(a <= frame <= b for a, b in patch.flashes):
                out[i] = patch.drive
        return out


def expand_frame(pattern: str, frame: int) -> str:
    """``patterns.####.exr`` with frame 7 -> ``patterns.0007.exr`` (one run of ``#``)."""
    return re.sub("#+", lambda run: f"{frame:0{len(run[0])}d}", pattern, count=1)


# --------------------------------------------------------------------------------------------
# Reading and validating.


def _rgb(ctx: Validator, value: JsonValue, key: tuple[str | int, ...], low: float) -> tuple:
    return tuple(float(v) for v in ctx.rgb(value, key, minimum=low, maximum=1e4))


_PATCH_KEYS = ("channel", "step", "flashes", "index", "content")


def _patch(
    ctx: Validator, raw: JsonValue, i: int, previous_last: int, seen: dict[str, int]
) -> Patch:
    key: tuple[str | int, ...] = ("patches", i)
    entry = ctx.mapping(raw, key, ("name", "kind", "first", "last", "drive", "signal"), _PATCH_KEYS)
    name = ctx.unique_name(entry["name"], key, seen)
    kind = ctx.choice(entry["kind"], (*key, "kind"), PATCH_KINDS, what="kind")
    first = ctx.whole(entry["first"], (*key, "first"), -_MAX_FRAMES)
    last = ctx.whole(entry["last"], (*key, "last"), -_MAX_FRAMES)
    if first != previous_last + 1 or last < first:
        raise ctx.error(
            (*key, "first"),
            f"frames {first}-{last} do not follow the previous patch (which ends at "
            f"{previous_last}): patches must cover the frames in order, without gaps",
        )
    channel = entry.get("channel")
    if kind in ("primary", "ramp"):
        channel = ctx.choice(channel, (*key, "channel"), CHANNELS)
    step = entry.get("step")
    if kind == "ramp":
        step = ctx.whole(step, (*key, "step"))
    flashes: list[tuple[int, int]] = []
    if kind == "sync":
        raw_flashes = entry.get("flashes")
        if not isinstance(raw_flashes, list) or not raw_flashes:
            raise ctx.error(
                (*key, "flashes"), "a sync patch lists its flashes [[first, last], ...]"
            )
        low = first
        for j, pair in enumerate(raw_flashes):
            if not isinstance(pair, list) or len(pair) != 2:
                raise ctx.error((*key, "flashes", j), "expected [first, last]")
            a, b = (ctx.whole(v, (*key, "flashes", j), -_MAX_FRAMES) for v in pair)
            if a < low or b < a or b > last:
                raise ctx.error((*key, "flashes", j), "flashes must be in order, inside the patch")
            flashes.append((a, b))
            low = b + 2
    index = entry.get("index")
    content = None
    if kind == "chart":
        index = ctx.whole(index, (*key, "index"))
        content = _rgb(ctx, entry.get("content"), (*key, "content"), -1e4)
    return Patch(
        name=name,
        kind=kind,
        first=first,
        last=last,
        drive=_rgb(ctx, entry["drive"], (*key, "drive"), 0.0),
        signal=_rgb(ctx, entry["signal"], (*key, "signal"), 0.0),
        channel=channel if kind in ("primary", "ramp") else None,
        step=step if kind == "ramp" else None,
        flashes=tuple(flashes),
        index=index if kind == "chart" else None,
        content=content,
    )


def _validation(ctx: Validator, raw: JsonValue) -> Validation:
    keys = ("environment", "stage", "solution_sha256", "in_frustum", "reference")
    optional = ("model", "solved")
    entry = ctx.mapping(raw, ("validation",), keys, ("content_scale", "pulled", *optional))
    text = {
        name: ctx.text(entry[name], ("validation", name), limit=None)
        for name in (*keys, *(k for k in optional if k in entry))
    }
    scale = ctx.number(
        entry.get("content_scale", 1.0), ("validation", "content_scale"), strict=True
    )
    pulled = entry.get("pulled") or {}
    kept = {  # chart index (a YAML integer key, read as its text) -> saturation kept
        int(k): float(v)
        for k, v in (pulled.items() if isinstance(pulled, dict) else ())
        if k.isdecimal() and isinstance(v, (int, float)) and 0 <= v <= 1
    }
    if not isinstance(pulled, dict) or len(kept) != len(pulled):
        raise ctx.error(("validation", "pulled"), "expected {chart index: saturation kept}")
    return Validation(**text, content_scale=scale, pulled=tuple(kept.items()))


def _checked_patches(ctx: Validator, raw: JsonValue, first_frame: int) -> tuple[Patch, ...]:
    patches: list[Patch] = []
    seen: dict[str, int] = {}
    for i, entry in enumerate(ctx.items(raw, ("patches",), "patches")):
        patches.append(
            _patch(ctx, entry, i, patches[-1].last if patches else first_frame - 1, seen)
        )
    if patches[-1].last - first_frame + 1 > _MAX_FRAMES:
        raise ctx.error(("patches",), f"more than {_MAX_FRAMES} frames")
    ramps: dict[str, list[Patch]] = {}
    for patch in patches:
        if patch.kind == "ramp":
            ramps.setdefault(patch.channel or "", []).append(patch)
    for channel, steps in ramps.items():
        drives = [p.drive[CHANNELS.index(channel)] for p in steps]
        if any(b <= a for a, b in itertools.pairwise(drives)) or drives[-1] != 1.0:
            raise ctx.error(
                ("patches",),
                f"the {channel} ramp's drives must increase strictly and end at exactly 1.0",
            )
    return tuple(patches)


def sequence_from_dict(
    data: JsonValue, *, source: str = "<sequence>", sha256: str | None = None
) -> PatternSequence:
    """Validate a parsed ``sequence.yaml`` document.

    Raises
    ------
    InputError
        Naming ``source``, the key path and the problem.
    """
    ctx = Validator(source)
    required = ("format", "version", "frames", "first_frame", "fps", "encoding", "size", "patches")
    optional = ("peak_nits", "file_format", "hold", "validation")
    top = ctx.mapping(data, (), required, optional)
    ctx.header(top, FORMAT, VERSION)
    frames = top["frames"]
    if not isinstance(frames, str) or not _ONE_FRAME_FIELD.fullmatch(frames):
        raise ctx.error(("frames",), "expected a file pattern with one run of '#', e.g. a.####.exr")
    if Path(frames).is_absolute() or ".." in Path(frames).parts:
        raise ctx.error(("frames",), "expected a path relative to the sequence file's folder")
    first_frame = ctx.whole(top["first_frame"], ("first_frame",), -_MAX_FRAMES)
    fps = ctx.number(top["fps"], ("fps",), strict=True, maximum=1000.0)
    encoding = ctx.wall_encoding(top["encoding"], ("encoding",))
    peak = top.get("peak_nits")
    if encoding == "pq":
        peak = ctx.peak_nits(peak, ("peak_nits",))
    elif peak is not None:
        raise ctx.error(("peak_nits",), f"only a pq sequence has a peak, this one is {encoding}")
    width, height = ctx.size(top["size"], ("size",))
    file_format = top.get("file_format", Path(frames).suffix.lstrip(".").lower())
    if file_format == "tif":
        file_format = "tiff"
    file_format = ctx.choice(file_format, ("file_format",), FILE_FORMATS)
    hold = ctx.whole(top.get("hold", 1), ("hold",), 1)
    patches = _checked_patches(ctx, top["patches"], first_frame)
    validation = _validation(ctx, top["validation"]) if "validation" in top else None
    return PatternSequence(
        frames=frames,
        first_frame=first_frame,
        fps=fps,
        encoding=encoding,
        peak_nits=None if peak is None else float(peak),
        size=(width, height),
        file_format=file_format,
        hold=hold,
        patches=patches,
        validation=validation,
        source=source,
        sha256=sha256,
    )


def load_sequence(path: str | Path) -> PatternSequence:
    """Load and validate a ``sequence.yaml`` (``ocio-vp/patterns`` v1)."""
    data, sha256 = read_document(path)
    return sequence_from_dict(data, source=str(path), sha256=sha256)


def _plain(values: tuple[float, ...]) -> list[float]:
    return [float(v) for v in values]


def sequence_to_dict(sequence: PatternSequence) -> dict[str, YamlValue]:
    """The inverse of :func:`sequence_from_dict` (plain types, file key order)."""
    patches = []
    for p in sequence.patches:
        entry: JsonObject = {"name": p.name, "kind": p.kind}
        if p.channel is not None:
            entry["channel"] = p.channel
        if p.step is not None:
            entry["step"] = p.step
        if p.index is not None:
            entry["index"] = p.index
        entry.update(first=p.first, last=p.last, drive=_plain(p.drive), signal=_plain(p.signal))
        if p.content is not None:
            entry["content"] = _plain(p.content)
        if p.flashes:
            entry["flashes"] = [[a, b] for a, b in p.flashes]
        patches.append(entry)
    fps = sequence.fps
    data: dict[str, YamlValue] = {
        "format": FORMAT,
        "version": VERSION,
        "frames": sequence.frames,
        "file_format": sequence.file_format,
        "first_frame": sequence.first_frame,
        "fps": int(fps) if float(fps).is_integer() else float(fps),
        "hold": sequence.hold,
        "encoding": sequence.encoding,
        "peak_nits": sequence.peak_nits,
        "size": list(sequence.size),
    }
    if sequence.validation is not None:
        v = sequence.validation
        pulled: dict[int, YamlValue] = dict(v.pulled)  # chart index: saturation kept
        data["validation"] = {
            "environment": v.environment,
            "stage": v.stage,
            "solution_sha256": v.solution_sha256,
            "in_frustum": v.in_frustum,
            "reference": v.reference,
            "content_scale": v.content_scale,
            **({"pulled": pulled} if pulled else {}),
            **({"model": v.model} if v.model else {}),
            **({"solved": v.solved} if v.solved else {}),
        }
    data["patches"] = patches
    return data
