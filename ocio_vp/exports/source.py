"""What every export starts from: a solved environment folder, re-validated.

``ocio-vp solve`` writes ``OUT/<environment>/solution.json`` and ``config.ocio`` (plus, with the
panel-linearity work, a ``luts/`` sidecar folder named in the config's search path). A
``solution.json`` can be edited by hand, so names are validated again here and the config is
loaded and checked before anything is exported.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import PyOpenColorIO as OCIO

from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import check_safe_name
from ocio_vp.formats.solution import Solution, load_solution

__all__ = ["ExportSource", "copy_config", "load_export_source", "sidecar_dirs"]


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
