"""What every export starts from: a solved environment folder, re-validated.

``ocio-vp solve`` writes ``OUT/<environment>/solution.json``, ``config.ocio`` and, where the
config names one in its search path, a ``luts/`` sidecar folder. A ``solution.json`` can be
edited by hand, so names are validated again here and the config is loaded and checked before
anything is exported.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING

import PyOpenColorIO as OCIO

from ocio_vp.choices import DEFAULT_CUBE_RANGE, DEFAULT_CUBE_SIZE
from ocio_vp.errors import InputError
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.solution import OcioNames, Solution, load_solution
from ocio_vp.model.footage_range import AGREEMENT_P99, AGREEMENT_WORST, Agreement

if TYPE_CHECKING:  # the cube baker (numpy, OCIO's processors) is loaded by the targets baking one
    from ocio_vp.exports.cube import CubeAccuracy


@dataclass(frozen=True)
class CubeOptions:
    """What every writer that bakes a .cube is given (``export --cube-size/--cube-range``)."""

    size: int = DEFAULT_CUBE_SIZE
    input_range: tuple[float, float] = DEFAULT_CUBE_RANGE


DEFAULT_CUBES = CubeOptions()


__all__ = [
    "DEFAULT_CUBES",
    "DEFAULT_CUBE_RANGE",
    "DEFAULT_CUBE_SIZE",
    "Carriage",
    "ConfigNames",
    "CubeOptions",
    "ExportSource",
    "ExportSummary",
    "copy_config",
    "load_export_source",
    "post_correction_carriage",
    "sidecar_dirs",
    "write_json",
]


@dataclass(frozen=True)
class ExportSummary:
    """What an export target wrote, for its line on the terminal (every file, accuracy and
    reason not written is in the target's folder, in its manifest)."""

    #: The files to name on the line.
    files: tuple[str, ...] = ()
    #: The whole line, when the target says it itself.
    line: str | None = None
    cubes: Mapping[str, CubeAccuracy] = field(default_factory=dict)
    not_written: Mapping[str, str] = field(default_factory=dict)

    def to_dict(self) -> JsonObject:
        return {"files": list(self.files), "line": self.line,
                "cubes": {k: v.to_dict() for k, v in self.cubes.items()},
                "not_written": dict(self.not_written)}  # fmt: skip


@dataclass(frozen=True)
class ConfigNames:
    """The names of solution.json's ``ocio`` block every export uses, each found in the
    config: four colour spaces and the post-correction's named transform."""

    reference: str
    out_of_frustum: str
    in_frustum: str
    post_correction_colorspace: str
    post_correction: str


@dataclass(frozen=True)
class ExportSource:
    """One solved environment ready to export."""

    directory: Path
    solution: Solution
    config_path: Path
    config: OCIO.Config
    names: ConfigNames


def _checked_names(config: OCIO.Config, names: OcioNames, source: str) -> ConfigNames:
    found: dict[str, str] = {}
    for role in (f.name for f in fields(ConfigNames)):
        name = getattr(names, role)
        transform = role == "post_correction"
        lookup = config.getNamedTransform if transform else config.getColorSpace
        if name is None or lookup(name) is None:
            kind = "named transform" if transform else "colorspace"
            raise InputError(
                f"{kind} {name!r} is not in the config", source=source, key=f"ocio.{role}"
            )
        found[role] = name
    return ConfigNames(**found)


def load_export_source(directory: str | Path) -> ExportSource:
    """Load ``directory/solution.json`` and its config; validate names and files.

    Raises
    ------
    InputError
        Missing or unreadable files, unsafe stage/environment names, a config that does not
        load or lacks the colorspaces ``solution.json`` names.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise InputError("not a solution folder (expected OUT/<environment>/)", source=directory)
    json_path = directory / "solution.json"
    try:
        solution = load_solution(directory)
    except (KeyError, TypeError, ValueError, AttributeError) as error:
        if isinstance(error, InputError):
            raise
        raise InputError(f"malformed solution: {error!r}", source=json_path) from None
    config_name = solution.ocio.config_file
    if Path(config_name).name != config_name:
        raise InputError(
            f"config must be a file name beside solution.json, got {config_name!r}",
            source=json_path,
            key="ocio.config",
        )
    config_path = directory / config_name
    try:
        config = OCIO.Config.CreateFromFile(str(config_path))
        config.validate()
    except (OCIO.Exception, OCIO.ExceptionMissingFile) as error:
        raise InputError(f"cannot load the OCIO config: {error}", source=config_path) from None
    names = _checked_names(config, solution.ocio, str(json_path))
    return ExportSource(directory, solution, config_path, config, names)


def write_json(path: Path, document: JsonValue) -> None:
    """Write ``document`` as indented JSON (finite numbers only) with a final newline."""
    path.write_text(json.dumps(document, indent=2, allow_nan=False) + "\n", encoding="utf-8")


def sidecar_dirs(source: ExportSource) -> list[Path]:
    """Relative search-path folders of the config (e.g. ``luts``) that exist beside it."""
    folders = []
    for entry in source.config.getSearchPaths():
        if not entry:
            continue
        path = Path(entry)
        if path.is_absolute() or ".." in path.parts or "$" in entry:
            raise InputError(
                f"search path {entry!r} must be a plain relative folder to be exported",
                source=source.config_path,
                key="search_path",
            )
        if entry != "." and (source.directory / path).is_dir():
            folders.append(path)
    return folders


def copy_config(source: ExportSource, destination: Path) -> Path:
    """Copy ``config.ocio`` and its sidecar LUT folders into ``destination``; returns the
    copied config's path."""
    destination.mkdir(parents=True, exist_ok=True)
    target = destination / source.config_path.name
    shutil.copyfile(source.config_path, target)
    for folder in sidecar_dirs(source):
        shutil.copytree(source.directory / folder, destination / folder)
    return target


@dataclass(frozen=True)
class Carriage:
    """How the config carries a non-linear post-correction (:func:`post_correction_carriage`)."""

    kind: str
    agreement: Agreement | None
    beyond: list[str] | None
    exact: list[str]
    note: str

    def to_dict(self) -> JsonObject:
        """The ``post_correction_carriage`` block of the exports' JSON files."""
        agreement = None if self.agreement is None else self.agreement.to_dict()
        return {"kind": self.kind, "agreement": agreement, "beyond": self.beyond,
                "exact": self.exact, "note": self.note}  # fmt: skip


def post_correction_carriage(solution: Solution) -> Carriage | None:
    """How the config, and every file made from it, carries a non-linear post-correction; None
    for a matrix (carried exactly everywhere).

    ``agreement``: ΔE2000 of the config's LUT chain against the exact model over the camera
    range, measured when the config was written (``diagnostics.post_correction_ocio``);
    ``beyond``: the sets where it exceeds
    :data:`~ocio_vp.model.footage_range.AGREEMENT_P99` (p99) or
    :data:`~ocio_vp.model.footage_range.AGREEMENT_WORST` (worst); ``exact``: where the model
    is computed exactly; ``note``: all of it in one sentence, for labels and descriptions.
    """
    correction = solution.correction
    if correction.linear:
        return None
    block = solution.diagnostics.post_correction_ocio
    measured = None if block is None else block.agreement
    exact = ["post_correction_Q.dctl (Resolve export)", "ocio-vp apply"]
    head = f"The {correction.kind} Q is carried by the OCIO config and its CLFs as a LUT chain"
    if measured is None:
        note = f"{head} whose agreement with the model was not measured (an older solve)"
        return Carriage(correction.kind, None, None, exact, f"{note}; exact: {', '.join(exact)}.")
    p99, worst = measured.p99, measured.worst
    beyond = [
        k for k in p99 if k != "all" and (p99[k] > AGREEMENT_P99 or worst[k] > AGREEMENT_WORST)
    ]
    note = (
        f"{head}, within {p99['all']:.2g} ΔE2000 (p99) and {worst['all']:.2g} (worst) of the "
        "exact model over the camera range"
    )
    if beyond:
        note += (
            f"; beyond {AGREEMENT_P99:g} (p99) or {AGREEMENT_WORST:g} (worst) on "
            f"{', '.join(s.replace('_', ' ') for s in beyond)}, where the model bends faster "
            f"than the LUT's nodes: for exact results use {' or '.join(exact)}"
        )
    else:
        note += f"; exact: {', '.join(exact)}"
    return Carriage(correction.kind, measured, beyond, exact, note + ".")
