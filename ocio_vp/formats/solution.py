"""The per-environment solution and its ``solution.json`` (format ``ocio-vp/solution`` v1).

``solution.json`` is for pipeline TDs and for ocio_vp's own later steps (export, apply,
report): matrices as 3x3 row-major lists, ``N`` null when it was not solved (the reason is in
``diagnostics``), and ``ocio`` naming the colorspaces of the config written beside it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.errors import InputError

__all__ = ["SOLUTION_FORMAT", "Solution", "load_solution", "solution_to_json"]

SOLUTION_FORMAT = "ocio-vp/solution"


@dataclass(frozen=True)
class Solution:
    """Everything solved for one environment; all arrays float64.

    ``black_level_offset`` is added to the in-frustum drive after N (``drive = N c + offset``),
    ``None`` when the environment has no black-level measurement. ``ocio`` maps the roles
    ``config``, ``reference``, ``out_of_frustum``, ``in_frustum``, ``post_correction`` (and
    ``post_correction_colorspace``) to names in the config; filled in when the config is written.
    """

    stage: str
    environment: str
    method: str
    beta: float
    w_avg: np.ndarray
    SL: np.ndarray
    M: np.ndarray
    Q: np.ndarray
    N: np.ndarray | None
    black_level_offset: np.ndarray | None
    black_level_method: str | None
    diagnostics: dict[str, Any] = field(default_factory=dict)
    measurements_file: str | None = None
    measurements_sha256: str | None = None
    camera_colorspace: str | None = None
    ocio: dict[str, str] = field(default_factory=dict)
    linearity: dict[str, Any] | None = None

    @property
    def in_frustum_matrix(self) -> np.ndarray:
        """N where it was solved, else M (the background then stays exact without Q)."""
        return self.M if self.N is None else self.N

    @property
    def in_frustum_offset(self) -> np.ndarray:
        return np.zeros(3) if self.black_level_offset is None else self.black_level_offset


def _plain(value: Any) -> Any:
    """Convert numpy values to JSON types; non-finite floats become an error (never written)."""
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        number = float(value)
        if not np.isfinite(number):
            return None if np.isnan(number) else ("inf" if number > 0 else "-inf")
        return number
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def solution_to_dict(solution: Solution) -> dict[str, Any]:
    return _plain(
        {
            "format": SOLUTION_FORMAT,
            "version": 1,
            "stage": solution.stage,
            "environment": solution.environment,
            "measurements": {
                "file": solution.measurements_file,
                "sha256": solution.measurements_sha256,
            },
            "camera_colorspace": solution.camera_colorspace,
            "method": solution.method,
            "beta": solution.beta,
            "w_avg": solution.w_avg,
            "SL": solution.SL,
            "M": solution.M,
            "Q": solution.Q,
            "N": solution.N,
            "black_level_offset": solution.black_level_offset,
            "black_level_method": solution.black_level_method,
            "linearity": solution.linearity,
            "diagnostics": solution.diagnostics,
            "ocio": solution.ocio,
        }
    )


def solution_to_json(solution: Solution) -> str:
    """Deterministic JSON text (same solution, same bytes)."""
    return json.dumps(solution_to_dict(solution), indent=2, allow_nan=False) + "\n"


def _matrix(data: dict[str, Any], key: str, source: str, optional: bool = False) -> Any:
    value = data.get(key)
    if value is None and optional:
        return None
    array = np.asarray(value, dtype=np.float64) if value is not None else None
    if array is None or array.shape != (3, 3) or not np.all(np.isfinite(array)):
        raise InputError("expected a finite 3x3 matrix", source=source, key=key)
    return array


def load_solution(path: str | Path) -> Solution:
    """Read ``solution.json`` (or a folder holding one) back into a :class:`Solution`."""
    path = Path(path)
    if path.is_dir():
        path = path / "solution.json"
    source = str(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(
            "no solution.json here; run `ocio-vp solve` first", source=source
        ) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"cannot read solution: {error}", source=source) from None
    if not isinstance(data, dict) or data.get("format") != SOLUTION_FORMAT:
        raise InputError(f"not an {SOLUTION_FORMAT} file", source=source, key="format")
    missing = [k for k in ("stage", "environment", "method", "beta", "w_avg") if k not in data]
    if missing:
        raise InputError(f"missing required key {missing[0]!r}", source=source)
    w_avg = np.asarray(data["w_avg"], dtype=np.float64)
    if w_avg.shape != (3,) or not np.all(np.isfinite(w_avg)):
        raise InputError("expected a finite [r, g, b]", source=source, key="w_avg")
    offset = data.get("black_level_offset")
    if offset is not None:
        offset = np.asarray(offset, dtype=np.float64)
        if offset.shape != (3,) or not np.all(np.isfinite(offset)):
            raise InputError("expected a finite [r, g, b]", source=source, key="black_level_offset")
    return Solution(
        stage=data["stage"],
        environment=data["environment"],
        method=data["method"],
        beta=float(data["beta"]),
        w_avg=w_avg,
        SL=_matrix(data, "SL", source),
        M=_matrix(data, "M", source),
        Q=_matrix(data, "Q", source),
        N=_matrix(data, "N", source, optional=True),
        black_level_offset=offset,
        black_level_method=data.get("black_level_method"),
        diagnostics=data.get("diagnostics", {}),
        measurements_file=data.get("measurements", {}).get("file"),
        measurements_sha256=data.get("measurements", {}).get("sha256"),
        camera_colorspace=data.get("camera_colorspace"),
        ocio=data.get("ocio", {}),
        linearity=data.get("linearity"),
    )
