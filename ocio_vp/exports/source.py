"""What every export starts from: a solved environment folder, re-validated.

``ocio-vp solve`` writes ``OUT/<environment>/solution.json`` and ``config.ocio`` (plus, with the
panel-linearity work, a ``luts/`` sidecar folder named in the config's search path). A
``solution.json`` can be edited by hand, so names are validated again here and the config is
loaded and checked before anything is exported.
"""

from __future__ import annotations

import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import PyOpenColorIO as OCIO

from ocio_vp.errors import InputError
from ocio_vp.exports.cube import CubeAccuracy
from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.formats.measurements import check_safe_name
from ocio_vp.formats.solution import Solution, load_solution
from ocio_vp.model.footage_range import Agreement

#: Cube lattice size and input range (camera RGB) of every exported .cube.
DEFAULT_CUBE_SIZE = 33
DEFAULT_CUBE_RANGE = (-0.25, 16.0)


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
    "CubeOptions",
    "ExportSource",
    "ExportSummary",
    "copy_config",
    "load_export_source",
    "post_correction_carriage",
    "sidecar_dirs",
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
class ExportSource:
    """One solved environment ready to export."""

    directory: Path
    solution: Solution
    config_path: Path
    config: OCIO.Config

    @property
    def names(self) -> dict[str, str]:
        """Colorspace roles -> names in the config (the ``ocio`` block of solution.json)."""
        return dict(self.solution.ocio)


def _check_names_in_config(config: OCIO.Config, names: dict[str, str], source: str) -> None:
    for role in ("reference", "out_of_frustum", "in_frustum", "post_correction_colorspace"):
        name = names.get(role)
        if not isinstance(name, str) or config.getColorSpace(name) is None:
            raise InputError(
                f"colorspace {name!r} is not in the config", source=source, key=f"ocio.{role}"
            )
    named = names.get("post_correction")
    if not isinstance(named, str) or config.getNamedTransform(named) is None:
        raise InputError(
            f"named transform {named!r} is not in the config",
            source=source,
            key="ocio.post_correction",
        )


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
    if not isinstance(solution.ocio, dict):
        raise InputError("expected a mapping", source=json_path, key="ocio")
    check_safe_name(solution.environment, source=json_path, key="environment")
    check_safe_name(solution.stage, source=json_path, key="stage")
    config_name = solution.ocio.get("config", "config.ocio")
    if not isinstance(config_name, str) or Path(config_name).name != config_name:
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
    _check_names_in_config(config, solution.ocio, str(json_path))
    return ExportSource(directory, solution, config_path, config)


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
    ``beyond``: the sets where it exceeds :data:`ocio_vp.ocio.bake.AGREEMENT_P99` (p99) or
    :data:`~ocio_vp.ocio.bake.AGREEMENT_WORST` (worst); ``exact``: where the model is computed
    exactly; ``note``: all of it in one sentence, for labels and descriptions.
    """
    from ocio_vp.ocio.bake import AGREEMENT_P99, AGREEMENT_WORST

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
