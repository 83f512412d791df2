"""The per-environment solution and its ``solution.json`` (format ``ocio-vp/solution`` v1; keys:
docs/solution.md), for pipeline TDs and for ocio_vp's own later steps (export, apply, report).
"""

from __future__ import annotations

import functools
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.deprecation import warn_deprecated
from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.checker import Validator, check_safe_name
from ocio_vp.formats.diagnostics import Diagnostics
from ocio_vp.formats.documents import read_document
from ocio_vp.formats.fixtures import DMX_MODES, DmxPatch
from ocio_vp.formats.jsontypes import JsonMapping, JsonObject
from ocio_vp.formats.linearity import Linearity, read_linearity
from ocio_vp.formats.panel_solution import (
    CONFIG_FILENAME,
    OcioNames,
    PanelSolution,
    panel_solutions_from_dict,
    panel_solutions_to_dict,
    read_ocio_names,
)
from ocio_vp.formats.records import Record, finite_array, json_object, optional_array, read_record
from ocio_vp.model.correction import (
    MatrixCorrection,
    PostCorrection,
    RootPolynomialCorrection,
    correction_from_dict,
    correction_to_dict,
)

__all__ = [
    "CONFIG_FILENAME",
    "SOLUTION_FORMAT",
    "Diagnostics",
    "OcioNames",
    "Solution",
    "load_solution",
    "solution_to_json",
]

SOLUTION_FORMAT = "ocio-vp/solution"


@dataclass(frozen=True)
class FixtureDrive(Record):
    """One practical fixture's block of ``solution.json`` (``fixtures.<name>``): its channels,
    the drive of each (units of its ``reference_drive``; DMX level = drive / ``max_drive``),
    whether it is pixel-mapped and its DMX patch."""

    OMIT_NONE = ("dmx",)

    channels: tuple[str, ...]
    drive: Mapping[str, float]
    reference_drive: float | None = None
    max_drive: float = 1.0
    pixel_mapped: bool = False
    dmx: DmxPatch | None = None

    @property
    def drives(self) -> list[float]:
        """The drives in channel order."""
        return [self.drive[c] for c in self.channels]


@dataclass(frozen=True)
class Solution:
    """Everything solved for one environment; all arrays float64 (keys: docs/solution.md).

    ``black_level_offset`` is added to the in-frustum drive after N (``drive = N c + offset``),
    None without a black-level measurement. ``ocio`` is filled in when the config is written.
    ``fixtures`` (None without a ``fixtures`` section) gives each practical fixture's drive per
    channel, ``M`` then being the matrix to light with while they are on. ``post_correction``
    is what every consumer applies; :attr:`Q` is derived from it. With ``panels`` (every panel
    type's solve by name), the top-level arrays and ``linearity`` are the first in-frustum
    type's.
    """

    stage: str
    environment: str
    method: str
    beta: float
    w_avg: np.ndarray
    SL: np.ndarray
    M: np.ndarray
    post_correction: PostCorrection
    N: np.ndarray | None
    black_level_offset: np.ndarray | None
    black_level_method: str | None
    diagnostics: Diagnostics = field(default_factory=Diagnostics)
    measurements_file: str | None = None
    measurements_sha256: str | None = None
    camera_colorspace: str | None = None
    ocio: OcioNames = field(default_factory=OcioNames)
    linearity: Linearity | None = None
    fixtures: Mapping[str, FixtureDrive] | None = None
    panels: Mapping[str, PanelSolution] | None = None

    @property
    def correction(self) -> PostCorrection:
        """The post-correction (:attr:`post_correction`)."""
        return self.post_correction

    @property
    def model(self) -> str:
        """The Q model fitted (``auto`` chooses one); the method for a file that does not say."""
        return self.diagnostics.model or self.method

    @property
    def Q(self) -> np.ndarray:
        """The post-correction's 3x3 (``solution.json``'s ``Q``), derived from it."""
        return self.post_correction.matrix

    @property
    def in_frustum_matrix(self) -> np.ndarray:
        """N where it was solved, else M (the background then stays exact without Q)."""
        return self.M if self.N is None else self.N

    @property
    def in_frustum_offset(self) -> np.ndarray:
        return np.zeros(3) if self.black_level_offset is None else self.black_level_offset


_dataclass_init = Solution.__init__


@functools.wraps(_dataclass_init)
def _init(self: Solution, *args: Any, Q: Any = None, **kwargs: Any) -> None:
    """Solution's constructor, still taking the deprecated ``Q`` (keyword, or positional where
    ``post_correction`` now is): the post-correction's matrix, now derived from it. A ``Q``
    alone becomes a matrix correction; beside ``post_correction`` it must be its matrix."""
    given = list(args)
    if len(given) > 7 and not isinstance(given[7], PostCorrection):
        Q, given[7] = given[7], None
    if Q is not None:
        warn_deprecated("Solution(Q=...)", "Solution(post_correction=MatrixCorrection(Q))")
        Q = np.asarray(Q, dtype=np.float64)
        correction = given[7] if len(given) > 7 else kwargs.get("post_correction")
        if correction is None:
            correction = MatrixCorrection(Q)
        elif problem := q_mismatch(Q, correction.matrix):
            raise ValueError(f"Q {problem}: leave Q out")
        if len(given) > 7:
            given[7] = correction
        else:
            kwargs["post_correction"] = correction
    _dataclass_init(self, *given, **kwargs)


Solution.__init__ = _init  # type: ignore[method-assign]


def solution_to_dict(solution: Solution) -> JsonObject:
    return json_object(
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
            "post_correction": correction_to_dict(solution.correction),
            "N": solution.N,
            "black_level_offset": solution.black_level_offset,
            "black_level_method": solution.black_level_method,
            "linearity": solution.linearity,
            "diagnostics": solution.diagnostics,
            "ocio": solution.ocio,
        }
        | ({} if solution.fixtures is None else {"fixtures": solution.fixtures})
        | ({} if solution.panels is None else {"panels": panel_solutions_to_dict(solution.panels)})
    )


def solution_to_json(solution: Solution) -> str:
    """Deterministic JSON text (same solution, same bytes)."""
    return json.dumps(solution_to_dict(solution), indent=2, allow_nan=False) + "\n"


def _fixtures(data: JsonMapping) -> dict[str, FixtureDrive] | None:
    """The ``fixtures`` block; each entry's shape is refused in the words solution.json's errors
    have always had."""
    block = data.get("fixtures")
    if block is None:
        return None
    if not isinstance(block, dict):
        raise InputError("expected a mapping", key="fixtures")
    fixtures = {}
    for name, entry in block.items():
        key = f"fixtures.{name}"
        fields = entry if isinstance(entry, dict) else {}
        channels, drive, dmx = fields.get("channels"), fields.get("drive"), fields.get("dmx")
        if not (
            isinstance(channels, list)
            and all(isinstance(c, str) for c in channels)
            and isinstance(drive, dict)
            and set(drive) == set(channels)
        ):
            raise InputError("expected channels and a drive for each", key=key)
        if not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
            for v in drive.values()
        ):
            raise InputError("expected finite drives", key=key)
        if dmx is not None and not (
            isinstance(dmx, dict)
            and all(type(dmx.get(k)) is int for k in ("universe", "address"))
            and dmx.get("mode") in DMX_MODES
        ):
            raise InputError(
                "expected universe, address (integers) and mode (8-bit or 16-bit)",
                key=f"{key}.dmx",
            )
        fixtures[name] = read_record(FixtureDrive, entry, key)
    return fixtures


def _text(data: JsonMapping, key: str) -> str | None:
    """An optional short line of text."""
    value = data.get(key)
    if value is not None and (
        not isinstance(value, str) or len(value) > 200 or not value.isprintable()
    ):
        raise InputError(f"expected a short line of text, got {excerpt(value)}", key=key)
    return value


def _mapping(data: JsonMapping, key: str) -> JsonMapping:
    value = data.get(key)
    if value is not None and not isinstance(value, dict):
        raise InputError(f"expected a mapping, got {excerpt(value)}", key=key)
    return value or {}


def _read(path: Path) -> JsonMapping:
    source = str(path)
    if not os.path.lexists(path):
        raise InputError("no solution.json here; run `ocio-vp solve` first", source=source)
    data, _ = read_document(path) if path.suffix == ".json" else (None, None)
    if not isinstance(data, dict) or data.get("format") != SOLUTION_FORMAT:
        raise InputError(f"not an {SOLUTION_FORMAT} file", source=source, key="format")
    missing = [k for k in ("stage", "environment", "method", "beta", "w_avg") if k not in data]
    if missing:
        raise InputError(f"missing required key {missing[0]!r}", source=source)
    return data


def load_solution(path: str | Path) -> Solution:
    """Read ``solution.json`` (or a folder holding one) back into a :class:`Solution`.

    Hand-edited files are validated like measurements files: names must be safe, numbers
    finite (|value| <= 1e30), matrices 3x3; any deviation is an :class:`InputError`.
    """
    path = Path(path)
    if path.is_dir():
        path = path / "solution.json"
    data = _read(path)
    try:
        return _solution(data)
    except InputError as error:  # every reader below names the key; the file is named here
        raise InputError(error.problem, source=str(path), key=error.key) from None


def _solution(data: JsonMapping) -> Solution:
    beta = Validator().number(data["beta"], ("beta",), strict=True, maximum=1.0)
    measurements = _mapping(data, "measurements")
    linearity = read_linearity(data.get("linearity"))
    Q = finite_array(data, "Q", (3, 3))
    diagnostics = Diagnostics.from_dict(_mapping(data, "diagnostics"))
    return Solution(
        stage=check_safe_name(data.get("stage"), key="stage"),
        environment=check_safe_name(data.get("environment"), key="environment"),
        method=_text(data, "method") or "",
        beta=beta,
        w_avg=finite_array(data, "w_avg", (3,)),
        SL=finite_array(data, "SL", (3, 3)),
        M=finite_array(data, "M", (3, 3)),
        post_correction=_post_correction(data, Q),
        N=optional_array(data, "N", (3, 3)),
        black_level_offset=optional_array(data, "black_level_offset", (3,)),
        black_level_method=_text(data, "black_level_method"),
        diagnostics=diagnostics,
        measurements_file=_text(measurements, "file"),
        measurements_sha256=_text(measurements, "sha256"),
        camera_colorspace=_text(data, "camera_colorspace"),
        ocio=read_ocio_names(data.get("ocio")),
        linearity=linearity,
        fixtures=_fixtures(data),
        panels=panel_solutions_from_dict(data.get("panels")),
    )


def _post_correction(data: JsonMapping, Q: np.ndarray) -> PostCorrection:
    """The ``post_correction`` block; a file written before it existed gets its model back from
    where those versions kept it (a root-polynomial's coefficients in
    ``diagnostics.method_notes``, applied unbounded as they were), otherwise Q as a matrix."""
    block = data.get("post_correction")
    if block is not None:
        correction = correction_from_dict(block)
        if problem := q_mismatch(Q, correction.matrix):
            raise InputError(f"{problem}: edit that block, or restore Q", key="Q")
        return correction
    diagnostics = data.get("diagnostics")
    notes = diagnostics.get("method_notes") if isinstance(diagnostics, dict) else None
    old = notes.get("root_polynomial") if isinstance(notes, dict) else None
    if old is None:
        return MatrixCorrection(Q)
    try:
        if not isinstance(old, dict):
            raise TypeError("expected a mapping")
        return RootPolynomialCorrection(np.asarray(old["coefficients"], dtype=np.float64), Q)
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(
            f"malformed root-polynomial model ({error})",
            key="diagnostics.method_notes.root_polynomial",
        ) from None


#: ``Q`` may differ from its ``post_correction``'s matrix by this much (relative, largest entry)
#: and no more: JSON round-trips a float64 exactly, so more means the file was edited.
Q_TOLERANCE = 1e-9


def q_mismatch(Q: np.ndarray, matrix: np.ndarray) -> str:
    """Why a ``Q`` given beside its post-correction's ``matrix`` is refused ("": it is that
    matrix, to :data:`Q_TOLERANCE` of its largest entry): an edited Q would reach the readers
    of Q but not ``apply`` and ``validate``."""
    scale = max(float(np.max(np.abs(matrix))), np.finfo(np.float64).tiny)
    relative = float(np.max(np.abs(Q - matrix))) / scale
    if not relative > Q_TOLERANCE:
        return ""
    return (
        f"differs from post_correction's matrix by {relative:.2g} relative (more than "
        f"{Q_TOLERANCE:g}); Q is derived from post_correction"
    )
