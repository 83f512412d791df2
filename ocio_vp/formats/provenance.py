"""Which solution an export or a report was made from, and which ones a re-solve left stale.

Each export folder holds :data:`SOURCE_FILE` (the sha256 of the ``solution.json`` it was made
from, the environment and its model), and a report's ``report.json`` lists the sha256 of each
solution it shows. A second ``solve`` into the same folder keeps an environment's ``exports/``
and ``report/`` (:func:`ocio_vp.staging.publish_dirs` carries nested output folders over, so
the config Unreal points at is still there) and :func:`stale_outputs` names every one made
from a different solution than the one now in the folder.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "SOURCE_FILE",
    "solution_sha256",
    "source_record",
    "stale_outputs",
]

#: In every export folder: the solution it was made from.
SOURCE_FILE = ".ocio-vp-source.json"
SOLUTION_FILE = "solution.json"
REPORT_MANIFEST = "report.json"


def solution_sha256(folder: str | Path) -> str:
    """sha256 of ``folder/solution.json`` (hex; "" when it cannot be read)."""
    try:
        return hashlib.sha256((Path(folder) / SOLUTION_FILE).read_bytes()).hexdigest()
    except OSError:
        return ""


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


def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _model(folder: Path) -> str:
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


def _stale_reports(out: Path, folders: Sequence[Path], current: dict[str, str]) -> list[str]:
    lines = []
    reports = [out / "report", *(f / "report" for f in folders)]
    for report in reports:
        manifest = _read_json(report / REPORT_MANIFEST)
        if manifest is None:
            continue
        shas = manifest.get("solution_sha256") or {}
        names = [
            env
            for env in manifest.get("environments", [])
            if env in current and shas.get(env) != current[env]
        ]
        if names:
            lines.append(
                f"stale: the report {report} shows an earlier solution of {', '.join(names)} "
                f"(another model or values): run ocio-vp report again"
            )
    return lines


def stale_outputs(out: str | Path, environments: Sequence[str]) -> list[str]:
    """One line per export or report in the solve folder ``out`` made from another solution
    of ``environments`` than the one now written there."""
    out = Path(out)
    folders = [out / env for env in environments]
    current = {folder.name: solution_sha256(folder) for folder in folders}
    lines = []
    for folder in folders:
        lines += _stale_exports(folder, current[folder.name])
    return lines + _stale_reports(out, folders, current)
