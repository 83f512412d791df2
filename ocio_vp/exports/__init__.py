"""Writers for the tools studios already run: Unreal nDisplay, Nuke, DaVinci Resolve.

:func:`export_solutions` reads solved environment folders (``OUT/<environment>/`` from
``ocio-vp solve``), re-validates them and writes each target into a staging folder; the
folders are renamed into place only when every export succeeded.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ocio_vp.errors import InputError
from ocio_vp.exports.escape import inside
from ocio_vp.exports.nuke import write_nuke
from ocio_vp.exports.resolve import DEFAULT_CUBE_RANGE, DEFAULT_CUBE_SIZE, write_resolve
from ocio_vp.exports.source import ExportSource, load_export_source
from ocio_vp.exports.unreal import write_unreal
from ocio_vp.staging import publish_dir, staged_dir

__all__ = ["EXPORT_TARGETS", "ExportResult", "export_solutions"]

#: Target name -> writer(source, folder, *, final_folder, cube_size, cube_range) -> summary.
EXPORT_TARGETS: dict[str, Callable[..., dict[str, Any]]] = {
    "unreal": write_unreal,
    "nuke": write_nuke,
    "resolve": write_resolve,
}

MAX_CUBE_SIZE = 129


@dataclass(frozen=True)
class ExportResult:
    environment: str
    target: str
    folder: Path
    summary: dict[str, Any]


def _final_folder(source: ExportSource, target: str, out: Path | None) -> Path:
    if out is None:
        root = source.directory / "exports"
        return inside(root / target, root, source=source.directory)
    return inside(out / source.solution.environment / target, out, source=out)


def export_solutions(
    solution_dirs: Sequence[str | Path],
    *,
    targets: Sequence[str],
    out: str | Path | None = None,
    cube_size: int = DEFAULT_CUBE_SIZE,
    cube_range: tuple[float, float] = DEFAULT_CUBE_RANGE,
) -> list[ExportResult]:
    """Export every solved environment to every target, all or nothing.

    Output goes to ``SOLUTION_DIR/exports/<target>/``, or ``OUT/<environment>/<target>/``
    when ``out`` is given; an existing folder of that name is replaced.

    Raises
    ------
    InputError
        Unknown target, bad cube size/range, an unreadable or unsafe solution folder, or two
        folders of the same environment exported to the same ``out``.
    """
    unknown = [t for t in targets if t not in EXPORT_TARGETS]
    if unknown or not targets:
        raise InputError(
            f"unknown target(s) {unknown}; choose from {sorted(EXPORT_TARGETS)}", key="--target"
        )
    if not 2 <= int(cube_size) <= MAX_CUBE_SIZE:
        raise InputError(f"expected 2..{MAX_CUBE_SIZE}, got {cube_size}", key="--cube-size")
    lo, hi = (float(v) for v in cube_range)
    if not (lo < hi and abs(lo) < 1e6 and abs(hi) < 1e6):
        raise InputError(f"expected LO < HI (finite), got {lo} {hi}", key="--cube-range")
    sources = [load_export_source(d) for d in solution_dirs]
    out_path = None if out is None else Path(out)
    jobs = []
    seen: dict[Path, Path] = {}
    for source in sources:
        for target in dict.fromkeys(targets):
            final = _final_folder(source, target, out_path)
            key = final.resolve()
            if key in seen:
                raise InputError(
                    f"{source.directory} and {seen[key]} would both write {final}",
                    key="SOLUTION_DIR",
                )
            seen[key] = source.directory
            jobs.append((source, target, final))

    # Folders this call creates; removed again (when left empty) if an export fails.
    created = sorted(
        {
            p
            for _, _, final in jobs
            for p in (final.parent, *final.parent.parents)
            if not p.exists()
        },
        key=lambda p: len(p.parts),
        reverse=True,
    )
    try:
        return _run_jobs(jobs, cube_size=int(cube_size), cube_range=(lo, hi))
    except BaseException:
        for folder in created:
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise


def _run_jobs(jobs, *, cube_size: int, cube_range: tuple[float, float]) -> list[ExportResult]:
    results = []
    with ExitStack() as stack:
        staged = []
        for source, target, final in jobs:
            stage = stack.enter_context(staged_dir(final.parent))
            folder = stage / target
            folder.mkdir()
            summary = EXPORT_TARGETS[target](
                source,
                folder,
                final_folder=final,
                cube_size=cube_size,
                cube_range=cube_range,
            )
            staged.append((folder, final))
            results.append(ExportResult(source.solution.environment, target, final, summary))
        for folder, final in staged:
            publish_dir(folder, final)
    return results
