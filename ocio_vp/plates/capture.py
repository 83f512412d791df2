"""The capture file (format ``ocio-vp/capture``, version 1): which plates to measure, and where.

It describes the paper's calibration photographs once (Section 3.3: the primaries plate and the
chart lit by each LED channel; per environment the real-location chart and, Section 3.4, the
black-level plate) so ``ocio-vp measure`` can turn them into a measurements file. The ``stage``
section is passed through to the measurements file unchanged. ``docs/capture.md`` documents
every key. Plate paths are relative to the capture file.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ocio_vp.errors import format_key_path
from ocio_vp.formats.jsontypes import JsonMapping, JsonValue
from ocio_vp.formats.measurements import CHANNELS, Validator, parse_stage, read_document
from ocio_vp.plates.movie import MATRICES, RANGES, is_movie
from ocio_vp.plates.raw import DEFAULT_DEMOSAIC, DEMOSAIC_METHODS, MAX_CONDITION_RAW, is_raw
from ocio_vp.plates.reader import canonical_encoding, plate_path
from ocio_vp.plates.statistics import ROBUST_MEAN_METHODS
from ocio_vp.plates.take import TakeRef

__all__ = [
    "FORMAT",
    "VERSION",
    "Capture",
    "ChartShot",
    "EnvironmentCapture",
    "PanelCapture",
    "PlateRef",
    "RawOptions",
    "RegionShot",
    "capture_from_dict",
    "load_capture",
    "save_capture_document",
]

FORMAT = "ocio-vp/capture"
VERSION = 1
DETECT = "detect"
_PLATE_KEYS = ("plate", "encoding", "layer", "flat_field")


@dataclass(frozen=True)
class PlateRef:
    """A plate: one file or several frames (averaged), its encoding and EXR layer.

    ``key`` is where it was described in the capture file (for messages); ``name`` is a short
    file-safe label used for its overlay; ``flat_field`` the flat-field frames, if any.
    """

    paths: tuple[Path, ...]
    encoding: str | None
    layer: str | None
    key: str
    name: str
    flat_field: tuple[Path, ...] | None = None

    @property
    def label(self) -> str:
        """The first frame's path (what messages name)."""
        return str(self.paths[0])


@dataclass(frozen=True)
class ChartShot:
    """A chart on a plate; ``corners`` (4, 2) TL, TR, BR, BL, or ``None`` to detect them (the
    file gives no ``corners``, or ``corners: detect``)."""

    plate: PlateRef
    corners: np.ndarray | None
    key: tuple[str | int, ...]


@dataclass(frozen=True)
class RegionShot:
    """A rectangle ``(x0, y0, x1, y1)`` (pixels, end-exclusive) on a plate."""

    plate: PlateRef
    region: tuple[int, int, int, int]
    key: tuple[str | int, ...]


@dataclass(frozen=True)
class EnvironmentCapture:
    """One environment: its target chart photo, optional black-level region and w_avg.

    On a stage of several panel types (``panels``): ``panel_black_level`` per in-frustum type
    and ``panel_w_avg`` per type (as the measurements file's, checked there).
    """

    name: str
    target_chart: ChartShot
    black_level: RegionShot | None = None
    w_avg: np.ndarray | None = None
    panel_black_level: Mapping[str, RegionShot] | None = None
    panel_w_avg: Mapping[str, Any] | None = None


@dataclass(frozen=True)
class PanelCapture:
    """One panel type of a capture file with ``panels``: its primaries' and lit charts' plates
    and ``settings``, its other keys (``in_frustum``, ``calibration_panel``/``beta``,
    ``region``, ``encoding``, ``peak_nits``), copied to the measurements file as they are."""

    name: str
    settings: Mapping[str, Any]
    primaries: Mapping[str, RegionShot]
    lit_chart: Mapping[str, ChartShot]


@dataclass(frozen=True)
class RawOptions:
    """The capture file's ``raw`` section: how camera raw plates are developed.

    ``demosaic``: the method (:data:`ocio_vp.plates.raw.DEMOSAIC_METHODS`); ``to_camera``: the
    3x3 matrix from sensor RGB to ``stage.camera_colorspace``, ``"dng"`` (each DNG's own
    ColorMatrix, :func:`ocio_vp.plates.raw.sensor_to_camera`) or ``None`` (sensor RGB as read).
    """

    demosaic: str = DEFAULT_DEMOSAIC
    to_camera: np.ndarray | str | None = None


@dataclass(frozen=True)
class Capture:
    """A validated capture file. ``primaries`` (plates) or ``take`` gives the wall; sections
    the file leaves out are empty (the measurements file written is then a part, merged at
    solve time with the others, docs/measurements.md)."""

    stage: Mapping[str, Any]
    rows: int
    columns: int
    inset: float
    sampling: Mapping[str, Any]
    primaries: Mapping[str, RegionShot]
    lit_chart: Mapping[str, ChartShot]
    environments: tuple[EnvironmentCapture, ...]
    source: str
    document: Mapping[str, Any] = field(default_factory=dict)
    sha256: str | None = None
    take: TakeRef | None = None
    #: The panel types of a capture file with ``panels`` (``primaries`` and ``lit_chart`` are
    #: then empty); empty otherwise.
    panels: tuple[PanelCapture, ...] = ()
    #: How raw plates are developed (the ``raw`` section).
    raw: RawOptions = field(default_factory=RawOptions)

    def charts(self) -> list[ChartShot]:
        """Every chart shot, lit charts first."""
        lit = [*self.lit_chart.values(), *(c for p in self.panels for c in p.lit_chart.values())]
        return [*lit, *(e.target_chart for e in self.environments)]

    def shots(self) -> list[ChartShot | RegionShot]:
        """Every chart and region shot: primaries, charts, black levels, panel types'."""
        shots: list[ChartShot | RegionShot] = [*self.primaries.values(), *self.charts()]
        shots += [e.black_level for e in self.environments if e.black_level is not None]
        shots += [r for p in self.panels for r in p.primaries.values()]
        shots += [r for e in self.environments for r in (e.panel_black_level or {}).values()]
        return shots

    def plate_paths(self) -> list[Path]:
        """Every file the capture reads: plates, their frames and flat fields, the take's
        sequence file and the take's folder."""
        shots = self.shots()
        paths = [p for shot in shots for p in (*shot.plate.paths, *(shot.plate.flat_field or ()))]
        if self.take is not None:
            paths += [self.take.sequence, self.take.frames.parent]
        return sorted(set(paths))


# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Where:
    """Where relative paths start, and the capture-wide flat field (if any)."""

    base: Path
    flat_field: tuple[Path, ...] | None = None


def _paths(
    ctx: Validator, value: JsonValue, key: tuple[str | int, ...], base: Path
) -> tuple[Path, ...]:
    given = value if isinstance(value, list) else [value]
    frames = [f for f in given if isinstance(f, str) and f]
    if not frames or len(frames) != len(given):
        raise ctx.error(key, "expected a file path or a list of frame paths")
    return tuple(plate_path(base, f) for f in frames)


def _plate(
    ctx: Validator,
    raw: JsonMapping,
    key: tuple[str | int, ...],
    where: _Where,
    name: str,
    inherited: PlateRef | None = None,
) -> PlateRef:
    if "plate" not in raw:
        if inherited is None:
            raise ctx.error(key, "missing required key 'plate'")
        return inherited
    paths = _paths(ctx, raw["plate"], (*key, "plate"), where.base)
    flat = where.flat_field
    if "flat_field" in raw:  # null switches the capture-wide flat field off for this plate
        value = raw["flat_field"]
        flat = None if value is None else _paths(ctx, value, (*key, "flat_field"), where.base)
    encoding, layer = _encoding_layer(ctx, raw, key)
    return PlateRef(
        paths=paths,
        encoding=encoding,
        layer=layer,
        key=format_key_path(*key),
        name=name,
        flat_field=flat,
    )


def _encoding_layer(
    ctx: Validator, raw: JsonMapping, key: tuple[str | int, ...]
) -> tuple[str | None, str | None]:
    """A plate's or take's ``encoding`` (canonical spelling) and ``layer``, if given."""
    encoding = raw.get("encoding")
    if encoding is not None:
        encoding = canonical_encoding(
            encoding, source=ctx.source, key=format_key_path(*key, "encoding")
        )
    layer = raw.get("layer")
    if layer is not None and not isinstance(layer, str):
        raise ctx.error((*key, "layer"), f"expected a layer name, got {layer!r}")
    return encoding, layer


def _region(
    ctx: Validator, value: JsonValue, key: tuple[str | int, ...]
) -> tuple[int, int, int, int]:
    if not isinstance(value, list) or len(value) != 4:
        raise ctx.error(key, "expected a region [x0, y0, x1, y1] in pixels")
    numbers = [ctx.number(v, (*key, i)) for i, v in enumerate(value)]
    if any(v != int(v) for v in numbers):
        raise ctx.error(key, f"region corners must be whole pixels, got {value}")
    x0, y0, x1, y1 = (int(v) for v in numbers)
    if x1 <= x0 or y1 <= y0:
        raise ctx.error(key, f"empty region {value}: need x1 > x0 and y1 > y0")
    return (x0, y0, x1, y1)


def _corners(ctx: Validator, value: JsonValue, key: tuple[str | int, ...]) -> np.ndarray | None:
    if value == DETECT:
        return None
    return ctx.matrix(value, key, (4, 2), "4 corners [[x, y], ...] (TL, TR, BR, BL) or 'detect'")


def _chart(
    ctx: Validator, value: JsonValue, key: tuple[str | int, ...], where: _Where, name: str
) -> ChartShot:
    raw = ctx.mapping(value, key, required=("plate",), optional=(*_PLATE_KEYS, "corners"))
    return ChartShot(
        plate=_plate(ctx, raw, key, where, name),
        corners=_corners(ctx, raw.get("corners", DETECT), (*key, "corners")),
        key=key,
    )


def _region_shot(
    ctx: Validator,
    value: JsonValue,
    key: tuple[str | int, ...],
    where: _Where,
    name: str,
    shared: PlateRef | None,
) -> RegionShot:
    if isinstance(value, list) and shared is not None:  # a bare rectangle on the shared plate
        return RegionShot(plate=shared, region=_region(ctx, value, key), key=key)
    raw = ctx.mapping(value, key, required=("region",), optional=_PLATE_KEYS)
    plate = _plate(ctx, raw, key, where, name, inherited=shared)
    return RegionShot(plate=plate, region=_region(ctx, raw["region"], (*key, "region")), key=key)


def capture_from_dict(
    data: JsonValue, *, source: str = "<capture>", sha256: str | None = None
) -> Capture:
    """Validate a parsed capture document (paths are resolved relative to ``source``).

    Raises
    ------
    InputError
        Naming ``source``, the key path and the problem.
    """
    ctx = Validator(source)
    base = Path(source)
    top = _header(ctx, data)
    rows, columns, inset = _chart_grid(ctx, top.get("chart", {}))
    sampling = _sampling(ctx, top.get("sampling", {}))
    where = _Where(base)
    if top.get("flat_field") is not None:
        where = _Where(base, _paths(ctx, top["flat_field"], ("flat_field",), base))
    panels: tuple[PanelCapture, ...] = ()
    if "panels" in top:
        panels = _panels(ctx, top["panels"], where)
    primaries, lit_chart = _wall_shots(ctx, top, (), where, "")
    environments: tuple[EnvironmentCapture, ...] = ()
    if "environments" in top:
        environments = _environments(ctx, top["environments"], where, panels)
    capture = Capture(
        stage=dict(top["stage"]),
        rows=rows,
        columns=columns,
        inset=inset,
        sampling=sampling,
        primaries=primaries,
        lit_chart=lit_chart,
        environments=environments,
        source=source,
        document=top,
        sha256=sha256,
        take=_take(ctx, top["take"], base) if "take" in top else None,
        panels=panels,
        raw=_raw_options(ctx, top.get("raw", {}), top["stage"]),
    )
    _check_one_camera_space(ctx, capture)
    return capture


def _raw_options(ctx: Validator, value: JsonValue, stage: JsonMapping) -> RawOptions:
    """``raw``: ``demosaic`` (default superpixel) and ``to_camera`` (a 3x3 matrix or ``dng``,
    only with ``stage.camera_colorspace``)."""
    raw = ctx.mapping(value, ("raw",), (), ("demosaic", "to_camera"))
    demosaic = ctx.choice(
        raw.get("demosaic", DEFAULT_DEMOSAIC), ("raw", "demosaic"), DEMOSAIC_METHODS
    )
    to_camera = raw.get("to_camera")
    if to_camera is None:
        return RawOptions(demosaic)
    if not stage.get("camera_colorspace"):
        raise ctx.error(
            ("raw", "to_camera"), "needs stage.camera_colorspace (the gamut it converts to)"
        )
    if to_camera == "dng":
        return RawOptions(demosaic, "dng")
    matrix = ctx.matrix(
        to_camera, ("raw", "to_camera"), (3, 3), "a 3x3 matrix [[r], [g], [b]] or 'dng'"
    )
    condition = np.linalg.cond(matrix)
    if not np.isfinite(condition) or condition > MAX_CONDITION_RAW:
        raise ctx.error(("raw", "to_camera"), f"singular matrix (condition number {condition:.3g})")
    return RawOptions(demosaic, matrix)


def _check_one_camera_space(ctx: Validator, capture: Capture) -> None:
    """Raw plates are sensor RGB; with ``stage.camera_colorspace`` the rest of the file (and
    the configs) is in that encoding gamut, and nothing in the file says how to bring the
    sensor's RGB there: refuse rather than mix two spaces in [SL], [SRL]_j and p_j."""
    camera = capture.stage.get("camera_colorspace")
    if not camera:
        return
    to_camera = capture.raw.to_camera
    for shot in capture.shots():
        raws = [p for p in shot.plate.paths if is_raw(p)]
        if raws and to_camera is None:
            raise ctx.error(
                shot.key,
                f"a camera raw plate is sensor RGB, but stage.camera_colorspace says the "
                f"measurements are in {camera}: give raw.to_camera (the 3x3 sensor-to-"
                f"{camera} matrix, or dng for the DNG's ColorMatrix)",
            )
        if isinstance(to_camera, str) and any(p.suffix.lower() != ".dng" for p in raws):
            raise ctx.error(
                shot.key, "raw.to_camera: dng reads a DNG's ColorMatrix; this raw plate is "
                "not a DNG: give raw.to_camera as a 3x3 matrix"
            )  # fmt: skip


_TAKE_KEYS = ("region", "encoding", "layer", "clip_level", "in", "out", "matrix", "range")
_MOVIE_KEYS = ("in", "out", "matrix", "range")


def _take(ctx: Validator, value: JsonValue, base: Path) -> TakeRef:
    """``take``: the frames of one continuous take, the sequence it filmed, and options."""
    raw = ctx.mapping(value, ("take",), ("frames", "sequence"), _TAKE_KEYS)
    for name in ("frames", "sequence"):
        if not isinstance(raw[name], str) or not raw[name]:
            raise ctx.error(("take", name), "expected a path relative to the capture file")
    movie = is_movie(raw["frames"])
    if not movie and raw["frames"].count("#") == 0:
        raise ctx.error(
            ("take", "frames"),
            "expected a frame pattern, e.g. take/A001.####.exr, or a movie (.mov, .mp4, .mxf)",
        )
    for name in _MOVIE_KEYS:
        if name in raw and not movie:
            raise ctx.error(("take", name), "only for a movie take (.mov, .mp4, .mxf)")
    points = {n: _movie_point(ctx, raw[n], n) for n in ("in", "out") if n in raw}
    matrix = _movie_choice(ctx, raw, "matrix", MATRICES)
    range_ = _movie_choice(ctx, raw, "range", RANGES)
    encoding, layer = _encoding_layer(ctx, raw, ("take",))
    clip = raw.get("clip_level")
    if clip is not None:
        clip = ctx.number(clip, ("take", "clip_level"), strict=True)
    region = _region(ctx, raw["region"], ("take", "region")) if "region" in raw else None
    return TakeRef(
        frames=plate_path(base, raw["frames"]),
        sequence=plate_path(base, raw["sequence"]),
        region=region,
        encoding=encoding,
        layer=layer,
        clip_level=clip,
        in_point=points.get("in"),
        out_point=points.get("out"),
        matrix=matrix,
        range=range_,
    )


def _movie_point(ctx: Validator, value: JsonValue, name: str) -> int | str:
    """``take.in``/``take.out``: a frame number (0 = the movie's first frame) or a timecode."""
    if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
        return value
    if isinstance(value, str) and re.fullmatch(r"\d{1,2}:\d{2}:\d{2}:\d{2,3}", value.strip()):
        return value.strip()
    raise ctx.error(
        ("take", name), "expected a frame number (0 = first frame) or a timecode HH:MM:SS:FF"
    )


def _movie_choice(ctx: Validator, raw: JsonMapping, name: str, allowed) -> str | None:
    """``take.matrix`` / ``take.range``: one of ``allowed`` (case and punctuation ignored,
    ``bt709`` = ``rec709``)."""
    if name not in raw:
        return None
    value = raw[name]
    text = re.sub(r"[^a-z0-9]", "", str(value).lower()).replace("itur", "").replace("bt", "rec")
    if text in allowed:
        return text
    raise ctx.error(("take", name), f"expected one of {', '.join(allowed)}, got {value!r}")


def _wall_shots(
    ctx: Validator, top: JsonMapping, key: tuple[str | int, ...], where: _Where, stem: str
) -> tuple[dict[str, RegionShot], dict[str, ChartShot]]:
    """The primaries' regions and the lit charts of the wall, each empty when not given (or of
    one panel type, under ``key`` with plate names starting ``stem``)."""
    primaries: dict[str, RegionShot] = {}
    lit_chart: dict[str, ChartShot] = {}
    if "primaries" in top:
        prim_key = (*key, "primaries")
        prim = ctx.mapping(top["primaries"], prim_key, CHANNELS, _PLATE_KEYS)
        shared = None
        if "plate" in prim:
            shared = _plate(ctx, prim, prim_key, where, f"{stem}primaries")
        primaries = {
            c: _region_shot(ctx, prim[c], (*prim_key, c), where, f"{stem}primaries_{c}", shared)
            for c in CHANNELS
        }
    if "lit_chart" in top:
        lit_key = (*key, "lit_chart")
        lit = ctx.mapping(top["lit_chart"], lit_key, CHANNELS)
        lit_chart = {
            c: _chart(ctx, lit[c], (*lit_key, c), where, f"{stem}lit_{c}") for c in CHANNELS
        }
    return primaries, lit_chart


#: Keys of a panel type in a capture file beside its plates: copied to the measurements file.
_PANEL_SETTINGS = ("in_frustum", "calibration_panel", "beta", "region", "encoding", "peak_nits")


def _panels(ctx: Validator, value: JsonValue, where: _Where) -> tuple[PanelCapture, ...]:
    """``panels``: each type's name, settings and plates (the settings are checked when the
    measurements file is built from them, under the same key paths)."""
    panels: list[PanelCapture] = []
    seen: dict[str, int] = {}
    for i, raw in enumerate(ctx.items(value, ("panels",), "panel types")):
        key: tuple[str | int, ...] = ("panels", i)
        entry = ctx.mapping(raw, key, ("name", "in_frustum", "primaries", "lit_chart"),
                            _PANEL_SETTINGS[1:])  # fmt: skip
        name = ctx.unique_name(entry["name"], key, seen)
        primaries, lit_chart = _wall_shots(ctx, entry, key, where, f"{name}_")
        settings = {k: entry[k] for k in _PANEL_SETTINGS if k in entry}
        panels.append(PanelCapture(name, settings, primaries, lit_chart))
    return tuple(panels)


def _header(ctx: Validator, data: JsonValue) -> Mapping[str, Any]:
    """The top-level mapping, its format and version checked, its stage validated."""
    panels = isinstance(data, Mapping) and "panels" in data
    wall = ("panels", "environments") if panels else ()
    top = ctx.mapping(
        data,
        (),
        required=("format", "version", "stage", *wall),
        optional=(
            "chart",
            "sampling",
            "flat_field",
            "take",
            "raw",
            *(() if panels else ("primaries", "lit_chart", "environments")),
        ),
    )
    for key in ("primaries", "lit_chart") if panels else ():
        if key in top:
            raise ctx.error(
                (key,), "a capture file with panels gives each panel type its own: remove it"
            )
    ctx.header(top, FORMAT, VERSION)
    # Same rules as the measurements file it is copied to.
    parse_stage(ctx, top["stage"], calibration=not panels)
    if panels and "take" in top:
        raise ctx.error(
            ("take",), "a take measures one wall: with panels give each panel type its plates"
        )
    if "primaries" in top and "take" in top:
        raise ctx.error(("take",), "give the wall as primaries plates or as a take, not both")
    if not any(k in top for k in ("panels", "primaries", "take", "lit_chart", "environments")):
        raise ctx.error(
            (), "nothing to measure: give a take (or primaries), lit_chart or environments"
        )
    return top


def _chart_grid(ctx: Validator, value: JsonValue) -> tuple[int, int, float]:
    """``chart``: (rows, columns, inset), defaults 4, 6, 0.25."""
    chart = ctx.mapping(value, ("chart",), (), ("rows", "columns", "inset"))
    rows = ctx.whole(chart.get("rows", 4), ("chart", "rows"), 1)
    columns = ctx.whole(chart.get("columns", 6), ("chart", "columns"), 1)
    inset = ctx.number(chart.get("inset", 0.25), ("chart", "inset"))
    if inset > 0.45:
        raise ctx.error(("chart", "inset"), f"expected at most 0.45, got {inset!r}")
    return rows, columns, inset


def _sampling(ctx: Validator, value: JsonValue) -> dict[str, Any]:
    """``sampling``: the patch statistic's options (method, trim, clip_level), checked."""
    sampling = dict(ctx.mapping(value, ("sampling",), (), ("method", "trim", "clip_level")))
    if "trim" in sampling:
        sampling["trim"] = ctx.number(sampling["trim"], ("sampling", "trim"))
        if sampling["trim"] >= 0.5:
            raise ctx.error(("sampling", "trim"), "expected less than 0.5")
    if sampling.get("clip_level") is not None:
        sampling["clip_level"] = ctx.number(
            sampling["clip_level"], ("sampling", "clip_level"), strict=True
        )
    if "method" in sampling:
        ctx.choice(sampling["method"], ("sampling", "method"), ROBUST_MEAN_METHODS, what="method")
    return sampling


def _environments(
    ctx: Validator, envs: JsonValue, where: _Where, panels: tuple[PanelCapture, ...] = ()
) -> tuple[EnvironmentCapture, ...]:
    """``environments``: a non-empty list, unique names, each with its target chart (with
    ``panels``: ``black_level`` a region per in-frustum type, ``w_avg`` per type)."""
    environments = []
    seen: dict[str, int] = {}
    for i, raw in enumerate(ctx.items(envs, ("environments",))):
        key: tuple[str | int, ...] = ("environments", i)
        env = ctx.mapping(raw, key, ("name", "target_chart"), ("black_level", "w_avg"))
        name = ctx.unique_name(env["name"], key, seen)
        target = _chart(ctx, env["target_chart"], (*key, "target_chart"), where, f"{name}_target")
        if panels:
            environments.append(_panel_environment(ctx, env, key, where, name, target))
            continue
        black = None
        if "black_level" in env:
            black = _region_shot(
                ctx, env["black_level"], (*key, "black_level"), where, f"{name}_black", None
            )
        w_avg = ctx.rgb(env["w_avg"], (*key, "w_avg")) if "w_avg" in env else None
        environments.append(EnvironmentCapture(name, target, black, w_avg))
    return tuple(environments)


def _panel_environment(
    ctx: Validator,
    env: JsonMapping,
    key: tuple[str | int, ...],
    where: _Where,
    name: str,
    target: ChartShot,
) -> EnvironmentCapture:
    black = None
    if "black_level" in env:
        raw = env["black_level"]
        if not isinstance(raw, Mapping):
            raise ctx.error((*key, "black_level"), "with panels, expected a region per panel type")
        for panel in raw:  # a name becomes part of an overlay's file name
            ctx.name(panel, (*key, "black_level", str(panel)[:60]))
        black = {
            panel: _region_shot(ctx, shot, (*key, "black_level", panel), where,
                                f"{name}_{panel}_black", None)
            for panel, shot in raw.items()
        }  # fmt: skip
    w_avg = env.get("w_avg")
    if w_avg is not None and not isinstance(w_avg, Mapping):
        raise ctx.error(
            (*key, "w_avg"), "with panels, expected a mapping of panel type -> [r, g, b]"
        )
    return EnvironmentCapture(name, target, panel_black_level=black, panel_w_avg=w_avg)


def load_capture(path: str | Path) -> Capture:
    """Load and validate a capture file (YAML or JSON)."""
    data, sha256 = read_document(path)
    return capture_from_dict(data, source=str(path), sha256=sha256)


def with_corners(document: JsonMapping, corners: Mapping[tuple[str | int, ...], np.ndarray]):
    """A copy of a capture document with detected corners written in place of ``detect``."""
    import copy

    out = copy.deepcopy(dict(document))
    for key, value in corners.items():
        node: Any = out
        for part in key:
            node = node[part]
        node["corners"] = [[round(float(x), 2), round(float(y), 2)] for x, y in value]
    return out


def save_capture_document(document: JsonMapping, path: str | Path) -> None:
    """Write a capture document as YAML, atomically (comments in the old file are not kept)."""
    from ocio_vp.staging import write_file_atomically

    text = yaml.safe_dump(dict(document), sort_keys=False, default_flow_style=None, width=100)
    write_file_atomically(path, text)
