"""``--target show``: one config for all the given environments, on a base config.

Writes ``OUT/show/config.ocio`` (:func:`ocio_vp.ocio.show.build_show_config`: the base config
written out whole, so the file loads on its own, plus every environment's wall and footage
spaces, chosen by the context variable ``VP_ENVIRONMENT``) and ``OUT/show/luts/`` (the
environments' LUT sidecars, copied as their configs name them), all or nothing.
"""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from pathlib import Path

from ocio_vp.errors import InputError
from ocio_vp.exports.source import ExportSource, ExportSummary, sidecar_dirs
from ocio_vp.ocio.show import (
    DEFAULT_BASE_CONFIG,
    ShowEnvironment,
    build_show_config,
)
from ocio_vp.staging import publish_dirs, staged_dir
from ocio_vp.wall.encoding import LUT_DIR

__all__ = ["SHOW_FOLDER", "write_show"]

SHOW_FOLDER = "show"


def _copy_sidecars(sources: Sequence[ExportSource], folder: Path) -> list[str]:
    """Every environment's sidecar files into ``folder``; the same name must hold the same
    bytes (the writers name sidecars by their content)."""
    copied: dict[str, Path] = {}
    for source in sources:
        for sub in sidecar_dirs(source):
            for path in sorted((source.directory / sub).rglob("*")):
                if not path.is_file():
                    continue
                name = path.relative_to(source.directory / sub).as_posix()
                if name in copied:
                    if copied[name].read_bytes() != path.read_bytes():
                        raise InputError(
                            f"two environments have different files named {name!r}; export "
                            "them into separate show configs",
                            source=path,
                        )
                    continue
                target = folder / name
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(path, target)
                copied[name] = path
    return sorted(copied)


def write_show(
    sources: Sequence[ExportSource], out: Path, *, base_config: str | None = None
) -> ExportSummary:
    """Write ``out/show/`` for ``sources``."""
    base = base_config or DEFAULT_BASE_CONFIG
    environments = [ShowEnvironment(s.solution.environment, s.config) for s in sources]
    config = build_show_config(environments, base)
    with staged_dir(out) as stage:
        folder = stage / SHOW_FOLDER
        folder.mkdir()
        _copy_sidecars(sources, folder / LUT_DIR)
        (folder / "config.ocio").write_text(config.serialize(), encoding="utf-8")
        publish_dirs([(folder, out / SHOW_FOLDER)])
    return ExportSummary(files=(f"{SHOW_FOLDER}/config.ocio",))
