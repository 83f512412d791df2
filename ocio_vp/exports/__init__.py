"""Writers for the tools studios already run: Unreal nDisplay, Nuke, DaVinci Resolve, and the
fixture drives for the lighting desk (``lights``, only for solutions with fixtures), run by
:func:`export_solutions` on solved environment folders, each environment all or nothing.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass, field
from pathlib import Path

import PyOpenColorIO as OCIO

from ocio_vp.choices import SHOW_TARGETS
from ocio_vp.errors import InputError
from ocio_vp.exports.escape import inside
from ocio_vp.exports.source import (
    DEFAULT_CUBE_RANGE,
    DEFAULT_CUBE_SIZE,
    CubeOptions,
    ExportSource,
    ExportSummary,
    load_export_source,
)
from ocio_vp.formats.provenance import SOURCE_FILE, source_record
from ocio_vp.staging import publish_dirs, staged_dir

__all__ = [
    "EXPORT_TARGETS",
    "SHOW_TARGETS",
    "ExportFailure",
    "ExportReport",
    "ExportResult",
    "export_solutions",
]

Writer = Callable[[ExportSource, Path, CubeOptions], ExportSummary]


def _writer(module: str, name: str) -> Writer:
    """The writer ``name`` of ``ocio_vp.exports.<module>``, imported when first called: an
    export loads its own targets' modules only (``lights`` alone loads the fixture solver,
    ``resolve`` and ``dit`` the cube baker)."""

    def write(source: ExportSource, folder: Path, cubes: CubeOptions) -> ExportSummary:
        function: Writer = getattr(importlib.import_module(f"ocio_vp.exports.{module}"), name)
        return function(source, folder, cubes)

    write.__name__ = write.__qualname__ = name
    return write


#: Target name -> writer(source, folder, cubes) -> summary (cubes: what a writer that bakes a
#: .cube uses; the others take it and ignore it).
EXPORT_TARGETS: dict[str, Writer] = {
    target: _writer(target, f"write_{target}")
    for target in ("unreal", "nuke", "resolve", "lights", "dit")
}


MAX_CUBE_SIZE = 129


@dataclass(frozen=True)
class ExportResult:
    environment: str
    target: str
    folder: Path
    summary: ExportSummary


@dataclass(frozen=True)
class ExportFailure:
    """An environment (or a folder that could not be read) that was not exported, and why."""

    source: str
    reason: str


@dataclass(frozen=True)
class ExportReport:
    """What :func:`export_solutions` wrote (``results``, iterable as the report itself) and
    what it could not (``failures``: one per environment, whose folders were left untouched)."""

    results: list[ExportResult] = field(default_factory=list)
    failures: list[ExportFailure] = field(default_factory=list)

    def __iter__(self) -> Iterator[ExportResult]:
        return iter(self.results)

    def __len__(self) -> int:
        return len(self.results)

    def __getitem__(self, index: int) -> ExportResult:
        return self.results[index]


#: Failures that concern one environment (bad input, OCIO refusing it, a file system error):
#: they are reported and the other environments are still exported. Anything else is a bug.
ENVIRONMENT_ERRORS = (InputError, OCIO.Exception, ValueError, OSError)


#: Why a target that applies only to some solutions wrote nothing for one.
NOTHING_FOR = {
    "lights": ": no fixtures in this solution",
    "dit": ": no camera log encoding (solve with --camera-colorspace)",
}


def _final_folder(source: ExportSource, target: str, out: Path | None) -> Path:
    if out is None:
        root = source.directory / "exports"
        return inside(root / target, root, source=source.directory)
    return inside(out / source.solution.environment / target, out, source=out)


def _check_options(targets, cube_size, cube_range) -> tuple[float, float]:
    unknown = [t for t in targets if t not in EXPORT_TARGETS and t not in SHOW_TARGETS]
    if unknown or not targets:
        raise InputError(
            f"unknown target(s) {unknown}; choose from {sorted([*EXPORT_TARGETS, *SHOW_TARGETS])}",
            key="--target",
        )
    if not 2 <= int(cube_size) <= MAX_CUBE_SIZE:
        raise InputError(f"expected 2..{MAX_CUBE_SIZE}, got {cube_size}", key="--cube-size")
    lo, hi = (float(v) for v in cube_range)
    if not (hi - lo >= 1e-3 and abs(lo) < 1e6 and abs(hi) < 1e6):
        raise InputError(
            f"expected LO < HI (finite, at least 0.001 apart), got {lo:g} {hi:g}",
            key="--cube-range",
        )
    return lo, hi


def _has_camera_log(source: ExportSource) -> bool:
    from ocio_vp.exports.dit import has_camera_log  # loads the cube baker: only for dit

    return has_camera_log(source)


def _plan(sources, targets, out_path) -> list[tuple[ExportSource, list[tuple[str, Path]]]]:
    """Each source with its (target, final folder) jobs; refuses two sources writing one
    folder (a usage error: nothing is exported)."""
    plan = []
    seen: dict[Path, Path] = {}
    for source in sources:
        jobs = []
        for target in dict.fromkeys(targets):
            if target == "lights" and not source.solution.fixtures:
                continue  # nothing for the lighting desk without fixtures
            if target == "dit" and not _has_camera_log(source):
                continue  # no log footage without a camera gamut
            final = _final_folder(source, target, out_path)
            key = final.resolve()
            if key in seen:
                raise InputError(
                    f"{source.directory} and {seen[key]} would both write {final}",
                    key="SOLUTION_DIR",
                )
            seen[key] = source.directory
            jobs.append((target, final))
        plan.append((source, jobs))
    return plan


def export_solutions(
    solution_dirs: Sequence[str | Path],
    *,
    targets: Sequence[str],
    out: str | Path | None = None,
    cube_size: int = DEFAULT_CUBE_SIZE,
    cube_range: tuple[float, float] = DEFAULT_CUBE_RANGE,
    base_config: str | None = None,
) -> ExportReport:
    """Export every solved environment to every target; each environment all or nothing.

    The ``show`` target is one config for all of them (``OUT/show/``, ``out`` required, on
    ``base_config``: :mod:`ocio_vp.exports.show`); it needs every given folder to load.

    Output goes to ``SOLUTION_DIR/exports/<target>/``, or ``OUT/<environment>/<target>/``
    when ``out`` is given; an existing folder of that name is replaced. An environment that
    cannot be exported (unreadable folder, a config OCIO refuses, ...) is listed in the
    report's ``failures`` with the reason, its folders untouched, and the others go on.

    Raises
    ------
    InputError
        Unknown target, bad cube size/range, two folders of the same environment exported to
        the same ``out``, or nothing could be exported (the message names every reason).
    """
    lo, hi = _check_options(targets, cube_size, cube_range)
    report = ExportReport()
    sources = []
    for directory in solution_dirs:
        try:
            sources.append(load_export_source(directory))
        except InputError as error:
            report.failures.append(ExportFailure(str(directory), str(error)))
    if "show" in targets:
        report.results.append(_export_show(sources, report, out, base_config))
    targets = [t for t in targets if t not in SHOW_TARGETS]
    if not targets:
        return report
    plan = _plan(sources, targets, None if out is None else Path(out))
    for source, jobs in plan:
        if not jobs:
            why = "".join(NOTHING_FOR[t] for t in NOTHING_FOR if t in targets)
            reason = f"{source.directory}: nothing for --target {'/'.join(targets)}{why}"
            report.failures.append(ExportFailure(str(source.directory), reason))
            continue
        try:
            report.results.extend(
                _export_environment(source, jobs, cube_size=int(cube_size), cube_range=(lo, hi))
            )
        except ENVIRONMENT_ERRORS as error:
            reason = str(error) if isinstance(error, InputError) else f"{source.directory}: {error}"
            report.failures.append(ExportFailure(str(source.directory), " ".join(reason.split())))
    if not report.results:
        raise InputError("nothing exported: " + "; ".join(f.reason for f in report.failures))
    return report


def _export_show(sources, report: ExportReport, out, base_config) -> ExportResult:
    """The show config of every loaded source (refused when one could not be loaded)."""
    from ocio_vp.exports.show import SHOW_FOLDER, write_show

    if out is None:
        raise InputError("--target show writes OUT/show/: give --out OUT", key="--out")
    if report.failures:
        raise InputError(
            "a show config needs every environment given: " + report.failures[0].reason,
            key="SOLUTION",
        )
    summary = write_show(sources, Path(out), base_config=base_config)
    environments = ", ".join(s.solution.environment for s in sources)
    return ExportResult(environments, "show", Path(out) / SHOW_FOLDER, summary)


def _export_environment(
    source: ExportSource, jobs, *, cube_size: int, cube_range: tuple[float, float]
) -> list[ExportResult]:
    """All targets of one environment into staging folders, published only when all succeed.

    Folders this creates (``OUT/<environment>/``...) are removed again, when left empty, if an
    export fails."""
    created = sorted(
        {p for _, final in jobs for p in (final.parent, *final.parent.parents) if not p.exists()},
        key=lambda p: len(p.parts),
        reverse=True,
    )
    solution = source.solution
    record = source_record(source.directory, solution.environment, solution.model)
    results = []
    try:
        with ExitStack() as stack:
            staged = []
            for target, final in jobs:
                stage = stack.enter_context(staged_dir(final.parent))
                folder = stage / target
                folder.mkdir()
                summary = EXPORT_TARGETS[target](source, folder, CubeOptions(cube_size, cube_range))
                (folder / SOURCE_FILE).write_text(record, encoding="utf-8")
                staged.append((folder, final))
                results.append(ExportResult(source.solution.environment, target, final, summary))
            publish_dirs(staged)  # every destination checked before any is replaced
    except BaseException:
        for folder in created:
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    return results
