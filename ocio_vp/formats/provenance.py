"""Which solution an export, a report or a validation was made from, and which ones a re-solve
left stale.

Each records the sha256 of the ``solution.json`` it was made from (an export in
:data:`SOURCE_FILE`, a report per solution in ``report.json``, a validation in
``validation.json``). A second ``solve`` into the same folder keeps an environment's
``exports/``, ``report/`` and ``validation/`` (:func:`ocio_vp.staging.publish_dirs`), and
:func:`stale_outputs` names each one made from another solution than the one now there.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.formats.solution_inputs import SOLUTION_FILE

if TYPE_CHECKING:
    from ocio_vp.formats.solution import Solution

__all__ = [
    "SOURCE_FILE",
    "SolutionIdentity",
    "solution_identity",
    "solution_sha256",
    "source_record",
    "stale_outputs",
]

#: In every export folder: the solution it was made from.
SOURCE_FILE = ".ocio-vp-source.json"
REPORT_MANIFEST = "report.json"
VALIDATION_FILE = "validation.json"


def solution_sha256(folder: str | Path) -> str:
    """sha256 of ``folder/solution.json`` (hex; "" when it cannot be read)."""
    try:
        return hashlib.sha256((Path(folder) / SOLUTION_FILE).read_bytes()).hexdigest()
    except OSError:
        return ""


@dataclass(frozen=True)
class SolutionIdentity:
    """What names a solution to a person: its environment, model and when it was written."""

    environment: str
    model: str
    solved: str

    def differences(self, other: SolutionIdentity) -> str:
        """``"environment 'a' (here 'b'), model x (here y)"``: what differs between
        ``self`` (recorded earlier) and ``other`` (now), or what is left when only the values do.

        >>> a = SolutionIdentity("direct_sun", "least-squares", "2026-12-07T08:40:00Z")
        >>> b = SolutionIdentity("incandescent", "diagonal", "2026-12-07T09:05:00Z")
        >>> a.differences(b)
        "environment 'direct_sun' (here 'incandescent'), model least-squares (here diagonal), solved 2026-12-07T08:40:00Z (here 2026-12-07T09:05:00Z)"
        >>> a.differences(a)
        'same environment, model and time, other values (another measurements file?)'
        """
        parts = [
            f"{name} {mine} (here {theirs})"
            for name, mine, theirs in (
                ("environment", repr(self.environment), repr(other.environment)),
                ("model", self.model, other.model),
                ("solved", self.solved, other.solved),
            )
            if mine != theirs and "?" not in (mine, theirs)
        ]
        return ", ".join(parts) or (
            "same environment, model and time, other values (another measurements file?)"
        )


def solution_identity(folder: str | Path, solution: Solution) -> SolutionIdentity:
    """The :class:`SolutionIdentity` of ``solution``, loaded from ``folder/solution.json``; the
    time is the file's modification time, UTC to the second ("?" where unreadable)."""
    from datetime import datetime, timezone

    path = Path(folder) / SOLUTION_FILE
    try:
        stamp = datetime.fromtimestamp(path.stat().st_mtime, tz=timezone.utc)
        solved = stamp.strftime("%Y-%m-%dT%H:%M:%SZ")
    except OSError:
        solved = "?"
    return SolutionIdentity(solution.environment, solution.model or "?", solved)


def source_record(folder: str | Path, environment: str, model: str) -> str:
    """The :data:`SOURCE_FILE` text for an export of the solution in ``folder``."""
    record = {
        "format": "ocio-vp/export-source",
        "version": 1,
        "environment": environment,
        "model": model,
        "solution_sha256": solution_sha256(folder),
    }
    return json.dumps(record, indent=2) + "\n"


def _read_json(path: Path) -> JsonObject | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _model(folder: Path) -> str:
    """The model of the solution now in ``folder``; where it does not load (an edited Q), what
    its raw ``diagnostics.model`` (or ``method``) says, "?" without either."""
    from ocio_vp.errors import InputError
    from ocio_vp.formats.solution import load_solution

    try:
        return load_solution(folder).model or "?"
    except InputError:
        data = _read_json(folder / SOLUTION_FILE) or {}
        diagnostics = data.get("diagnostics")
        model = diagnostics.get("model") if isinstance(diagnostics, dict) else None
        return str(model or data.get("method") or "?")


def _stale_exports(folder: Path, current: str) -> list[str]:
    lines = []
    for record_path in sorted(folder.glob(f"exports/*/{SOURCE_FILE}")):
        record = _read_json(record_path) or {}
        if record.get("solution_sha256") != current:
            lines.append(
                f"stale: {record_path.parent} was exported from an earlier solution of "
                f"{folder.name} (model {record.get('model', '?')}, now {_model(folder)}): run "
                f"ocio-vp export {folder} again"
            )
    return lines


def _stale_validations(folder: Path, current: str) -> list[str]:
    """Validations inside an environment folder (``calib/<env>/validation``, any depth but
    the exports') judged against another solution than the one now there."""
    lines = []
    for path in sorted(folder.rglob(VALIDATION_FILE)):
        record = _read_json(path) or {}
        if (
            record.get("format") != "ocio-vp/validation"
            or "exports" in path.relative_to(folder).parts
        ):
            continue
        if record.get("solution_sha256") != current:
            lines.append(
                f"stale: {path.parent} validated an earlier solution of {folder.name} (now "
                f"model {_model(folder)}): its verdict says nothing about this one; write the "
                f"validation patterns again (ocio-vp patterns --validate {folder}), film them "
                "and run ocio-vp validate"
            )
    return lines


def _stale_reports(out: Path, folders: Sequence[Path], current: dict[str, str]) -> list[str]:
    lines = []
    reports = [out / "report", *(f / "report" for f in folders)]
    for report in reports:
        manifest = _read_json(report / REPORT_MANIFEST)
        if manifest is None:
            continue
        shas = manifest.get("solution_sha256")
        shown = manifest.get("environments")
        names = [
            env
            for env in (shown if isinstance(shown, list) else [])
            if isinstance(env, str)
            and env in current
            and (shas.get(env) if isinstance(shas, dict) else None) != current[env]
        ]
        if names:
            lines.append(
                f"stale: the report {report} shows an earlier solution of {', '.join(names)} "
                f"(another model or values): run ocio-vp report again"
            )
    return lines


def stale_outputs(out: str | Path, environments: Sequence[str]) -> list[str]:
    """One line per export, report or validation in the solve folder ``out`` made from
    another solution of ``environments`` than the one now written there."""
    out = Path(out)
    folders = [out / env for env in environments]
    current = {folder.name: solution_sha256(folder) for folder in folders}
    lines = []
    for folder in folders:
        lines += _stale_exports(folder, current[folder.name])
        lines += _stale_validations(folder, current[folder.name])
    return lines + _stale_reports(out, folders, current)
