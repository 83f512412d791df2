"""The measurements file (format ``ocio-vp/measurements``, version 1): load, validate, save.

Other tools, scripts and people write this file, so it is a contract; ``docs/measurements.md``
documents every key. Validation is strict: unknown keys are errors (typos are caught), and every
error names the file, the key path and the problem.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ocio_vp.choices import DEFAULT_WHITE_PATCH, PRIORITIES
from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.checker import (
    CHANNELS,
    MAX_CAMERA_VALUE,
    MIN_BETA,
    MIN_SIGNAL,
    PANEL_RANGE,
    SAFE_NAME,
    Validator,
    check_safe_name,
)
from ocio_vp.formats.documents import read_document
from ocio_vp.formats.fixtures import Fixture, fixtures_to_dict, parse_fixtures
from ocio_vp.formats.geometry import PanelGeometry
from ocio_vp.formats.jsontypes import JsonMapping, JsonObject, JsonValue
from ocio_vp.formats.panels import (
    PanelType,
    lit_dicts,
    panel_values_to_dict,
    panels_to_dict,
    parse_panel_values,
    parse_panels,
    primary_panel,
)
from ocio_vp.formats.records import floats
from ocio_vp.formats.synthesis import SynthesisRecord, parse_synthesis, synthesis_to_dict
from ocio_vp.formats.wall_state import WALL_STATE_KEYS, WallState, parse_wall_state
from ocio_vp.wall.linearity import parse_ramps, ramps_to_dict

__all__ = [
    "CHANNELS",
    "FORMAT",
    "MAX_CAMERA_VALUE",
    "MIN_BETA",
    "MIN_SIGNAL",
    "PANEL_RANGE",
    "REQUIRED_SECTIONS",
    "SAFE_NAME",
    "SECTIONS",
    "VERSION",
    "Environment",
    "Measurements",
    "PanelGeometry",
    "PanelType",
    "Stage",
    "Validator",
    "check_measurements_part",
    "check_safe_name",
    "load_measurements",
    "measurements_from_dict",
    "measurements_to_dict",
    "parse_stage",
    "read_document",
    "save_measurements",
    "save_measurements_document",
    "with_camera_colorspace",
]

FORMAT = "ocio-vp/measurements"
VERSION = 1
#: The sections of the file that hold measurements; :data:`REQUIRED_SECTIONS` are needed to
#: solve (a file holding only some of them is merged with others, docs/measurements.md).
SECTIONS = ("primaries", "lit_chart", "environments", "ramps", "fixtures")
REQUIRED_SECTIONS = ("primaries", "lit_chart", "environments")


@dataclass(frozen=True)
class Stage:
    """The stage section: name, how to get beta, the chart's white patch, camera colour space.

    ``beta`` is ``None`` when the file gives panel geometry instead; use
    :func:`ocio_vp.calibration.geometry.stage_beta` to resolve it.
    """

    name: str
    panel: PanelGeometry | None = None
    beta: float | None = None
    white_patch: int = DEFAULT_WHITE_PATCH
    white_reflectance: float = 0.9
    camera_colorspace: str | None = None
    #: Camera value at or above which a sample is clipped (optional; docs/stability.md).
    clip_level: float | None = None
    #: Indices of the chart patches that stand for skin (optional; docs/skin.md): on a chart
    #: other than the ColorChecker 24 they are the skin samples, found by colour otherwise.
    skin_patches: tuple[int, ...] = ()
    #: The wall's encoding, peak and pattern size while it was measured (``sequence.yaml``
    #: through ``measure``; :mod:`ocio_vp.formats.wall_state`): what ``solve`` uses.
    wall: WallState = field(default_factory=WallState)
    #: False when the file gives no ``white_patch`` (patch 18 assumed; solve says so).
    white_patch_stated: bool = True


@dataclass(frozen=True)
class Environment:
    """One real lighting environment: the target chart ``p_j`` and optional extras."""

    name: str
    target_chart: np.ndarray  # (n, 3)
    w_avg: np.ndarray | None = None  # (3,)
    black_level: np.ndarray | None = None  # (3,) b_camera
    #: Set when the target chart was computed (``ocio-vp target-chart``), not photographed.
    synthesized: SynthesisRecord | None = None
    #: ``general`` or ``skin`` (docs/skin.md): what this environment's default post-correction
    #: puts first; None: as the command line says.
    priority: str | None = None
    #: With ``panels``: the diffuse light each panel type delivers, ``{name: (3,)}`` (None: not
    #: given, e.g. to come from an HDRI), and each in-frustum type's b_camera.
    panel_w_avg: Mapping[str, np.ndarray] | None = None
    panel_black_level: Mapping[str, np.ndarray] | None = None


@dataclass(frozen=True)
class Measurements:
    """Everything the solver needs, as float64 arrays.

    ``SL`` is the 3x3 matrix [SL] of the paper (camera channels along rows, LED channels along
    columns: column k is the camera RGB of primary k). ``SRL`` has shape (n, 3, 3): ``SRL[j]`` is
    [SRL]_j, column k the camera RGB of patch j lit by LED channel k from the calibration panel,
    *as photographed* (not yet divided by beta).

    ``panels`` holds every panel type of a file with a ``panels`` section
    (:mod:`ocio_vp.formats.panels`), empty otherwise; ``SL``, ``SRL`` and ``ramps`` are then
    the first in-frustum type's (:func:`~ocio_vp.formats.panels.primary_panel`), the one whose
    M and N are solution.json's top-level ones.
    """

    stage: Stage
    SL: np.ndarray
    SRL: np.ndarray
    environments: tuple[Environment, ...]
    ramps: Mapping[str, Any] | None = None
    fixtures: tuple[Fixture, ...] = ()
    panels: tuple[PanelType, ...] = ()
    source: str | None = None
    sha256: str | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @property
    def n_patches(self) -> int:
        return int(self.SRL.shape[0])

    def environment(self, name: str) -> Environment:
        for environment in self.environments:
            if environment.name == name:
                return environment
        names = ", ".join(e.name for e in self.environments)
        raise InputError(
            f"no environment named {excerpt(name)} (have: {names})", source=self.source
        )


def measurements_from_dict(
    data: JsonValue, *, source: str = "<measurements>", sha256: str | None = None
) -> Measurements:
    """Validate a parsed measurements document and return :class:`Measurements`.

    Raises
    ------
    InputError
        Naming ``source``, the key path and the problem, for any deviation from the format.
    """
    parsed = _parse_sections(Validator(source), data, partial=False)
    return Measurements(**parsed, source=source, sha256=sha256)


def check_measurements_part(data: JsonValue, *, source: str = "<measurements>") -> tuple[str, ...]:
    """Validate a measurements document that may hold only some sections: a wall file
    (``primaries``, ``ramps``) or a charts file (``lit_chart``, ``environments``), which
    ``ocio-vp solve`` merges (:mod:`ocio_vp.formats.merge`). Returns the sections it holds.

    Raises
    ------
    InputError
        As :func:`measurements_from_dict`, for every section present; or no section at all.
    """
    parsed = _parse_sections(Validator(source), data, partial=True)
    # A stage of several panel types comes whole: its panels replace primaries and lit_chart.
    given = tuple(name for name in SECTIONS if isinstance(data, dict) and name in data)
    return (*given, "primaries", "lit_chart") if "panels" in parsed else given


def _parse_sections(ctx: Validator, data: JsonValue, *, partial: bool) -> dict[str, Any]:
    """Every section present, validated, as :class:`Measurements` fields: all of
    :data:`REQUIRED_SECTIONS` unless ``partial``; a file with ``panels`` (several panel types,
    :mod:`ocio_vp.formats.panels`) comes whole, with the first in-frustum type's [SL], [SRL]
    and ramps."""
    with_panels = isinstance(data, Mapping) and "panels" in data
    required: tuple[str, ...] = ("format", "version", "stage", "panels", "environments")
    optional: tuple[str, ...] = ("primaries", "lit_chart", "ramps", "fixtures")
    if not with_panels:
        required = ("format", "version", "stage") + (() if partial else REQUIRED_SECTIONS)
        optional = (REQUIRED_SECTIONS if partial else ()) + ("ramps", "fixtures")
    top = ctx.mapping(data, (), required=required, optional=optional)
    ctx.header(top, FORMAT, VERSION)
    for key in ("primaries", "lit_chart", "ramps") if with_panels else ():
        if key in top:
            raise ctx.error(
                (key,),
                "a file with panels gives each panel type its own primaries, lit_chart and "
                "ramps: remove the top-level one (or the panels section)",
            )
    if not any(name in top for name in SECTIONS):
        raise ctx.error((), f"holds no measurements: give at least one of {', '.join(SECTIONS)}")
    out: dict[str, Any] = {"stage": parse_stage(ctx, top["stage"], calibration=not with_panels)}
    panels: tuple[PanelType, ...] = ()
    if with_panels:
        panels = parse_panels(ctx, top["panels"])
        primary = primary_panel(panels)
        out |= {"SL": primary.SL, "SRL": primary.SRL, "ramps": primary.ramps, "panels": panels}
    if "primaries" in top:
        out["SL"] = ctx.primaries(top["primaries"], ("primaries",))
    if "lit_chart" in top:
        out["SRL"] = ctx.lit_chart(top["lit_chart"], ("lit_chart",), None)
    n = len(out["SRL"]) if "SRL" in out else None
    if n is not None:
        _check_white_patch(ctx, out["stage"], n)
    if "environments" in top:
        seen: dict[str, int] = {}
        listed = ctx.items(top["environments"], ("environments",))
        out["environments"] = tuple(
            _environment(ctx, raw, ("environments", i), n, panels, seen)
            for i, raw in enumerate(listed)
        )
    if "ramps" in top:
        out["ramps"] = parse_ramps(top["ramps"], source=ctx.source)
    if "fixtures" in top:
        if n is None:
            raise ctx.error(("fixtures",), "fixtures need lit_chart in the same file")
        out["fixtures"] = parse_fixtures(ctx, top["fixtures"], n)
    return out


def _check_white_patch(ctx: Validator, stage: Stage, n: int) -> None:
    if not 0 <= stage.white_patch < n:
        raise ctx.error(
            ("stage", "white_patch"),
            f"index {excerpt(stage.white_patch)} is outside the {n} chart patches",
        )
    for i, index in enumerate(stage.skin_patches):
        if index >= n:
            raise ctx.error(
                ("stage", "skin_patches", i), f"index {index} is outside the {n} chart patches"
            )


def parse_stage(ctx: Validator, value: JsonValue, *, calibration: bool = True) -> Stage:
    """Validate a ``stage`` section (also used by the capture file, which copies it).

    ``calibration=False`` (a file with ``panels``): the stage gives no ``calibration_panel`` or
    ``beta``, each panel type does.
    """
    key: tuple[str | int, ...] = ("stage",)
    stage = ctx.mapping(
        value,
        key,
        required=("name",),
        optional=(
            "calibration_panel",
            "beta",
            "white_patch",
            "white_reflectance",
            "camera_colorspace",
            "clip_level",
            "skin_patches",
            *WALL_STATE_KEYS,
        ),
    )
    name = ctx.name(stage["name"], (*key, "name"))
    panel, beta = None, None
    if calibration:
        panel, beta = ctx.calibration(stage, key)
    else:
        for field_name in ("calibration_panel", "beta"):
            if field_name in stage:
                raise ctx.error(
                    (*key, field_name),
                    "with panels, each panel type gives its own calibration_panel or beta",
                )
    white_patch = ctx.whole(
        stage.get("white_patch", DEFAULT_WHITE_PATCH), (*key, "white_patch"), None
    )
    # A "white" patch reflecting under 1% is a mistake (and would blow w_avg up).
    reflectance = ctx.number(
        stage.get("white_reflectance", 0.9),
        (*key, "white_reflectance"),
        minimum=0.01,
        maximum=1.0,
        at_most="at most 1",
    )
    camera = stage.get("camera_colorspace")
    if camera is not None:
        camera, problem = _colourspace_problem(camera)
        if camera is None:
            raise ctx.error((*key, "camera_colorspace"), problem)
    clip_level = None
    if "clip_level" in stage:
        clip_level = ctx.number(
            stage["clip_level"], (*key, "clip_level"), strict=True, maximum=MAX_CAMERA_VALUE
        )
    return Stage(
        name=name,
        panel=panel,
        beta=beta,
        white_patch=white_patch,
        white_reflectance=reflectance,
        camera_colorspace=camera,
        clip_level=clip_level,
        skin_patches=_skin_patches(ctx, stage.get("skin_patches", []), (*key, "skin_patches")),
        wall=parse_wall_state(ctx, stage, key),
        white_patch_stated="white_patch" in stage,
    )


def _skin_patches(ctx: Validator, value: JsonValue, key: tuple[str | int, ...]) -> tuple[int, ...]:
    """``stage.skin_patches``: distinct patch indices (checked against the chart later)."""
    raw = ctx.items(value, key, "patch indices", empty=True)
    indices = [ctx.whole(index, (*key, i)) for i, index in enumerate(raw)]
    if len(set(indices)) != len(indices):
        raise ctx.error(key, "names a patch twice")
    return tuple(indices)


def _colourspace_problem(value: JsonValue) -> tuple[str | None, str]:
    """(colour-science's name of ``value``, or None and what is wrong with it)."""
    import colour

    names = sorted(colour.RGB_COLOURSPACES.keys())
    if isinstance(value, str) and value in colour.RGB_COLOURSPACES:
        return colour.RGB_COLOURSPACES[value].name, ""
    close = difflib.get_close_matches(str(value)[:100], names, n=3, cutoff=0.5)
    hint = f"; close matches: {', '.join(close)}" if close else ""
    return None, f"unknown colour space {excerpt(value)} (colour.RGB_COLOURSPACES){hint}"


def with_camera_colorspace(measurements: Measurements, value: str, *, key: str) -> Measurements:
    """``measurements`` with ``stage.camera_colorspace`` set to ``value`` (a
    ``colour.RGB_COLOURSPACES`` name; an unknown one raises, listing close matches)."""
    name, problem = _colourspace_problem(value)
    if name is None:
        raise InputError(problem, key=key)
    stage = dataclasses.replace(measurements.stage, camera_colorspace=name)
    return dataclasses.replace(measurements, stage=stage)


def _environment(
    ctx: Validator,
    raw: JsonValue,
    key: tuple[str | int, ...],
    n: int | None,
    panels: tuple[PanelType, ...],
    seen: dict[str, int],
) -> Environment:
    """One environment; its ``w_avg`` and ``black_level`` an [r, g, b] each or, with
    ``panels``, one per panel type."""
    env = ctx.mapping(
        raw,
        key,
        required=("name", "target_chart"),
        optional=("w_avg", "black_level", "synthesized", "priority"),
    )
    name = ctx.unique_name(env["name"], key, seen)
    target = ctx.signal(
        ctx.chart(env["target_chart"], (*key, "target_chart"), n), (*key, "target_chart")
    )
    priority = env.get("priority")
    if priority is not None:
        priority = ctx.choice(priority, (*key, "priority"), PRIORITIES)
    w_avg = black = None
    panel_w_avg = panel_black = None
    if panels and "w_avg" in env:
        panel_w_avg = parse_panel_values(ctx, env["w_avg"], (*key, "w_avg"), panels)
    if panels and "black_level" in env:
        black_key = (*key, "black_level")
        panel_black = parse_panel_values(
            ctx, env["black_level"], black_key, panels, in_frustum_only=True
        )
    if not panels and "w_avg" in env:
        w_avg = ctx.rgb(env["w_avg"], (*key, "w_avg"))
        if not np.any(w_avg > 0):
            raise ctx.error((*key, "w_avg"), "is black: the environment gives no light")
    if not panels and "black_level" in env:
        black = ctx.rgb(env["black_level"], (*key, "black_level"))
    synthesized = None
    if "synthesized" in env:
        synthesized = parse_synthesis(ctx, env["synthesized"], (*key, "synthesized"))
    return Environment(name, target, w_avg, black, synthesized, priority, panel_w_avg, panel_black)


def load_measurements(path: str | Path) -> Measurements:
    """Load and validate a measurements file (``.yaml``/``.yml`` or ``.json``).

    Raises
    ------
    InputError
        When the file is missing, unreadable, not YAML/JSON, or not a valid measurements file.
    """
    data, sha256 = read_document(path)
    return measurements_from_dict(data, source=str(path), sha256=sha256)


def measurements_to_dict(measurements: Measurements) -> JsonObject:
    """The inverse of :func:`measurements_from_dict` (plain Python types, file key order)."""
    stage = measurements.stage
    stage_dict: JsonObject = {"name": stage.name}
    if stage.panel is not None:
        stage_dict["calibration_panel"] = stage.panel.to_dict()
    if stage.beta is not None:
        stage_dict["beta"] = stage.beta
    if stage.white_patch_stated:
        stage_dict["white_patch"] = stage.white_patch
    stage_dict["white_reflectance"] = stage.white_reflectance
    if stage.camera_colorspace is not None:
        stage_dict["camera_colorspace"] = stage.camera_colorspace
    if stage.clip_level is not None:
        stage_dict["clip_level"] = stage.clip_level
    if stage.skin_patches:
        stage_dict["skin_patches"] = list(stage.skin_patches)
    stage_dict |= stage.wall.to_dict()

    data: JsonObject = {"format": FORMAT, "version": VERSION, "stage": stage_dict}
    if measurements.panels:
        data["panels"] = panels_to_dict(measurements.panels)
    else:
        data |= lit_dicts(measurements.SL, measurements.SRL)
    environments: list[JsonValue] = []
    for env in measurements.environments:
        entry: JsonObject = {"name": env.name, "target_chart": floats(env.target_chart)}
        if env.w_avg is not None:
            entry["w_avg"] = floats(env.w_avg)
        if env.panel_w_avg is not None:
            entry["w_avg"] = panel_values_to_dict(env.panel_w_avg)
        if env.black_level is not None:
            entry["black_level"] = floats(env.black_level)
        if env.panel_black_level:
            entry["black_level"] = panel_values_to_dict(env.panel_black_level)
        if env.synthesized is not None:
            entry["synthesized"] = synthesis_to_dict(env.synthesized)
        if env.priority is not None:
            entry["priority"] = env.priority
        environments.append(entry)
    data["environments"] = environments
    if measurements.ramps is not None and not measurements.panels:
        data["ramps"] = ramps_to_dict(measurements.ramps)
    if measurements.fixtures:
        data["fixtures"] = fixtures_to_dict(measurements.fixtures)
    return data


def save_measurements(
    measurements: Measurements, path: str | Path, *, replace: bool = False
) -> None:
    """Write a measurements file; YAML unless ``path`` ends in ``.json``. Floats round-trip.

    An existing file is replaced only if ocio-vp wrote it (YAML: its first line is the
    ``# Written by ocio-vp`` comment), it already holds the same bytes, or ``replace`` (the
    user asked for it, e.g. ``--force``).
    """
    save_measurements_document(measurements_to_dict(measurements), path, replace=replace)


def save_measurements_document(
    data: JsonMapping, path: str | Path, *, replace: bool = False
) -> None:
    """Write a measurements document (complete or a part, already validated) like
    :func:`save_measurements`."""
    from ocio_vp.staging import FILE_SIGNATURE, write_output_file

    path = Path(path)
    if path.suffix.lower() == ".json":
        text = json.dumps(data, indent=2) + "\n"
    else:
        header = f"{FILE_SIGNATURE.decode()} ({FORMAT} v{VERSION}, docs/measurements.md)\n"
        text = header + yaml.safe_dump(
            dict(data), sort_keys=False, default_flow_style=None, width=100
        )
    write_output_file(path, text, replace=replace)
