"""The per-environment solution and its ``solution.json`` (format ``ocio-vp/solution`` v1).

``solution.json`` is for pipeline TDs and for ocio_vp's own later steps (export, apply,
report): matrices as 3x3 row-major lists, ``N`` null when it was not solved (the reason is in
``diagnostics``), and ``ocio`` naming the colorspaces of the config written beside it.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.documents import read_document
from ocio_vp.formats.measurements import check_safe_name
from ocio_vp.formats.panel_solution import (
    PanelSolution,
    panel_solutions_from_dict,
    panel_solutions_to_dict,
)
from ocio_vp.formats.skin import SkinFigures, skin_figures_from_dict, skin_figures_to_dict
from ocio_vp.model.correction import (
    MatrixCorrection,
    PostCorrection,
    RootPolynomialCorrection,
    correction_from_dict,
    correction_to_dict,
)

__all__ = ["SOLUTION_FORMAT", "Diagnostics", "Solution", "load_solution", "solution_to_json"]

SOLUTION_FORMAT = "ocio-vp/solution"
#: Largest magnitude a number in a solution.json may have (far beyond any solved stage).
MAX_SOLUTION_VALUE = 1e30


@dataclass(frozen=True)
class Diagnostics(Mapping[str, Any]):
    """What a solve measured about itself: ``solution.json``'s ``diagnostics`` block.

    Errors are the paper's Fig. 11 metric, per channel, relative to the target white patch
    (:func:`ocio_vp.metrics.error_relative_to_white`), over the patches the fit used. Arrays are
    float64 after a solve; after :func:`load_solution` they are the file's JSON values. The
    object reads like the ``dict`` it is written as (``diagnostics["cond_Q"]``, ``.get``,
    iteration in file order), so code that reads ``solution.json`` reads a fresh solve alike.

    Attributes
    ----------
    white_patch
        Index of the chart's white patch.
    cond_SL, cond_Q
        2-norm condition numbers of [SL] and Q.
    rank_Q
        Numerical rank of Q.
    N_solved, N_reason
        Whether N = M Q^-1 was solved (eq. 8), and why not when it was not.
    max_condition_q_for_N
        The cond(Q) above which N is not solved.
    lit_chart_error_baseline, lit_chart_error
        (3,) the lit chart (eq. 3) against the target: through M alone, and after Q.
    residual_rms
        RMS of the lit chart after Q minus the target, in camera units.
    displayed_chart_error_baseline, displayed_chart_error
        (3,) the chart shown on the wall in-frustum as the camera records it, against the
        target: through M (no Q), and through N and the black-level offset, then Q.
    out_of_frustum_drive
        (3,) the lighting drive M w_avg.
    method_notes
        What the Q method reported about itself, for people (method specific). The model
        itself is the solution's ``post_correction``; no module reads it from here.
    warnings
        Sentences for the stage engineer (also printed by ``ocio-vp solve``).
    charts
        Per-patch (n, 3) camera RGB for the report: ``target``, ``lit_baseline``,
        ``lit_corrected``, ``displayed_baseline``, ``displayed_corrected``.
    model, model_reason
        The Q model fitted (``auto`` chooses one) and why.
    rank_target
        The target chart's rank as the method saw it (rank-aware methods), else None.
    cross_validated_error
        (3,) leave-one-patch-out lit-chart error, None for an iterative method that does not
        report its own (re-solving once per patch would multiply the solve time by n).
    residuals_per_patch
        (n, 3) signed residuals after Q, relative to the target white.
    out_of_frustum_negative_channels
        Channels of M w_avg below zero (the light is outside the LED gamut; the wall clips).
    lit_chart_error_clipped_drive, lit_chart_error_baseline_clipped_drive
        (3,) the lit-chart error after Q, and through M alone, when the wall clips a negative
        drive, else None.
    charts_clipped_drive
        ``lit_baseline`` and ``lit_corrected`` (n, 3) as the wall lights the chart when it clips
        a negative drive, else None (the report draws these then, like the figures it shows).
    in_frustum_drive_range
        How many chart colours the in-frustum matrix drives outside [0, 1] (``below_zero``,
        ``above_max``, ``patches_outside``, ``max_drive``, ``content_scale``,
        ``below_zero_with_M``, ``above_max_with_M``); see
        :func:`ocio_vp.calibration.diagnostics.in_frustum_drive_range`.
    black_level_bounce
        (3,) the panels' bounced light relative to the wall's white (Section 3.4), or None.
    clipped_patches
        Chart patches left out of the fit because they reach the clip level.
    N_equals_M
        True when N is exactly M (Q is the identity).
    identity_check
        ``max_abs_error`` of eq. 7 (``Q [SL] N = I``) and its rounding ``bound``, or None.
    fixtures
        The practical fixtures' drive solve (:func:`ocio_vp.fixtures.fixtures_diagnostics`):
        whether they are used and why, the error Q cannot remove with and without them, the
        active limits; only written when the measurements have a ``fixtures`` section.
    patch_screening
        Whether patches inconsistent with the rest of the chart were looked for (False with
        ``--keep-all-patches``).
    excluded_patches
        The patches excluded as inconsistent: ``index``, ``name``, ``relative`` (how far off,
        relative to the patch itself), ``z`` (robust standard deviations), ``influence`` (mean
        ΔE2000 by which it moves the fit's colours of the other patches), ``deletion`` (how many
        times better the other patches are predicted without it than without a typical patch)
        and ``residual`` (the held-out prediction minus the target, per channel, relative to
        white); for two neighbours that look swapped also ``swapped_with`` (the other's
        index), ``swapped_name`` and ``swap_residuals`` (the pair's held-out residuals as read
        and exchanged, fitted without both, relative to white; both patches are listed),
        otherwise those three are null; when the data cannot tell which of two patches is the
        bad one (both excluded), ``ambiguous_with`` and ``ambiguous_name`` name the other and
        ``ambiguous_deletion`` is its ``deletion``, otherwise null; see
        :mod:`ocio_vp.correction.outliers`.
    model_description
        The post-correction in words (kind, bounds, protection).
    extrapolation
        How the post-correction behaves beyond the chart
        (:class:`ocio_vp.correction.extrapolation.Extrapolation`): ``led_damage`` and
        ``led_damage_least_squares`` (p95 ΔE2000 of the wall's own LEDs in frame, through it
        and through least squares), ``kept`` and ``negative`` (bright saturated inputs: least
        share of the dominant channel kept, lowest channel relative to it; null where a
        dominant output is at or below zero, older files say "-inf"), ``folds`` (share
        of the reflective solid where it maps two colours to one).
    synthesized_target
        How a synthesized target chart was made (``ocio-vp target-chart``); only written for
        an environment whose chart was synthesized.
    panels
        Only for a stage of several panel types (``panels`` in the measurements file):
        ``primary`` (the first in-frustum type, whose M and N are the top-level ones),
        ``shares`` (each type's part of the light on the white patch, by luminance),
        ``lit_white_error`` (3,) (the lit white against the target's, per channel relative to
        it, before Q) and ``lit_white_error_primary_M`` (the same with every type driven by
        the primary's M, as a calibration of that type alone would), and
        ``in_frustum_match`` (how the in-frustum types match in camera on the chart:
        :func:`ocio_vp.calibration.panels.in_frustum_match`, None for one in-frustum type).
    post_correction_ocio
        How the config carries a non-linear post-correction (:mod:`ocio_vp.ocio.bake`):
        ``files`` (its LUT chains' sidecars), ``lut_size``, ``chains`` (each one's design),
        ``agreement`` (ΔE2000 of the Q chain against the exact model, ``p99`` and ``worst`` per
        set of the camera range and over ``all``, and the ``worst_input``) and
        ``inverse_agreement`` (the same for the content through the Q^-1 chain and back through
        the model; null without Q^-1); only written for a non-linear post-correction.
    skin
        What the solve expects of skin (:class:`ocio_vp.formats.skin.SkinFigures`): mean
        ΔE2000 on its skin samples for the post-correction and least squares, per lightness
        band, the chart's beside them, and with skin first the default's; only written where
        the chart gives skin samples (docs/skin.md).
    extra
        Keys of a loaded file that this version does not know, kept so they round-trip.
    """

    white_patch: int | None = None
    cond_SL: float | None = None
    cond_Q: float | None = None
    rank_Q: int | None = None
    N_solved: bool | None = None
    N_reason: str | None = None
    max_condition_q_for_N: float | None = None
    lit_chart_error_baseline: Any = None
    lit_chart_error: Any = None
    residual_rms: float | None = None
    displayed_chart_error_baseline: Any = None
    displayed_chart_error: Any = None
    out_of_frustum_drive: Any = None
    method_notes: dict[str, Any] | None = None
    warnings: list[str] | None = None
    charts: dict[str, Any] | None = None
    model: str | None = None
    model_reason: str | None = None
    rank_target: int | None = None
    cross_validated_error: Any = None
    residuals_per_patch: Any = None
    out_of_frustum_negative_channels: list[int] | None = None
    lit_chart_error_clipped_drive: Any = None
    lit_chart_error_baseline_clipped_drive: Any = None
    charts_clipped_drive: dict[str, Any] | None = None
    in_frustum_drive_range: dict[str, Any] | None = None
    black_level_bounce: Any = None
    clipped_patches: list[int] | None = None
    N_equals_M: bool | None = None
    identity_check: dict[str, float] | None = None
    patch_screening: bool | None = None
    excluded_patches: list[dict[str, Any]] | None = None
    model_description: str | None = None
    extrapolation: dict[str, float] | None = None
    synthesized_target: dict[str, Any] | None = None
    fixtures: dict[str, Any] | None = None
    panels: dict[str, Any] | None = None
    post_correction_ocio: dict[str, Any] | None = None
    skin: SkinFigures | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    #: The keys a loaded file had (None: every field, as after a solve).
    present: tuple[str, ...] | None = field(default=None, repr=False, compare=False)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Diagnostics:
        """The block as read from ``solution.json``; missing keys stay missing, unknown kept."""
        known = {f.name for f in dataclasses.fields(cls)} - {"extra", "present"}
        values = {k: v for k, v in data.items() if k in known}
        if values.get("skin") is not None:
            values["skin"] = skin_figures_from_dict(values["skin"])
        extra = {k: v for k, v in data.items() if k not in known}
        return cls(**values, extra=extra, present=tuple(data))

    #: Fields written only when set.
    OPTIONAL: ClassVar[tuple[str, ...]] = (
        "synthesized_target",
        "fixtures",
        "panels",
        "post_correction_ocio",
        "skin",
    )

    def _keys(self) -> tuple[str, ...]:
        if self.present is not None:
            return self.present
        names = [f.name for f in dataclasses.fields(self)[:-2]]
        names = [n for n in names if n not in self.OPTIONAL or getattr(self, n) is not None]
        return (*names, *self.extra)

    def __getitem__(self, key: str) -> Any:
        if key not in self._keys():
            raise KeyError(key)
        return self.extra[key] if key in self.extra else getattr(self, key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys())

    def __len__(self) -> int:
        return len(self._keys())


@dataclass(frozen=True)
class Solution:
    """Everything solved for one environment; all arrays float64.

    ``black_level_offset`` is added to the in-frustum drive after N (``drive = N c + offset``),
    ``None`` when the environment has no black-level measurement. ``ocio`` maps the roles
    ``config``, ``reference``, ``out_of_frustum``, ``in_frustum``, ``post_correction`` (and
    ``post_correction_colorspace``) to names in the config; filled in when the config is written.
    ``fixtures`` maps each practical fixture to its ``channels`` and ``drive`` per channel (units
    of its ``reference_drive``), ``None`` without a ``fixtures`` section; ``M`` is then the
    matrix to light with while the fixtures are on.

    ``post_correction`` is the post-correction itself (:mod:`ocio_vp.model`), which every
    consumer applies; ``Q`` is its 3x3 (the matrix, or a non-linear model's 3x3 fallback, for
    readers that want one). Left out, it is ``Q`` as a matrix.

    ``panels`` (a stage of several panel types: :mod:`ocio_vp.formats.panel_solution`) holds
    every type's solve by name, None otherwise; the top-level ``SL``, ``M``, ``N``, ``beta``,
    ``w_avg``, ``black_level_offset`` and ``linearity`` are then the first in-frustum type's.
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
    diagnostics: Mapping[str, Any] = field(default_factory=dict)
    measurements_file: str | None = None
    measurements_sha256: str | None = None
    camera_colorspace: str | None = None
    ocio: dict[str, str] = field(default_factory=dict)
    linearity: dict[str, Any] | None = None
    fixtures: dict[str, Any] | None = None
    post_correction: PostCorrection | None = None
    panels: Mapping[str, PanelSolution] | None = None

    def __post_init__(self) -> None:
        if self.post_correction is None:
            object.__setattr__(self, "post_correction", MatrixCorrection(self.Q))

    @property
    def correction(self) -> PostCorrection:
        """The post-correction (never None; :attr:`post_correction` typed for checkers)."""
        assert self.post_correction is not None
        return self.post_correction

    @property
    def in_frustum_matrix(self) -> np.ndarray:
        """N where it was solved, else M (the background then stays exact without Q)."""
        return self.M if self.N is None else self.N

    @property
    def in_frustum_offset(self) -> np.ndarray:
        return np.zeros(3) if self.black_level_offset is None else self.black_level_offset


def _plain(value: Any) -> Any:
    """Convert numpy values to JSON types. A non-finite float is written as null (NaN) or the
    string "inf"/"-inf": only cond_Q of a singular Q should ever be one (docs/stability.md;
    tests/test_pipeline.py and benchmarks/sweep.py look for any other)."""
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, SkinFigures):
        return _plain(skin_figures_to_dict(value))
    if isinstance(value, Mapping):
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


def _matrix(data: dict[str, Any], key: str, source: str, optional: bool = False) -> Any:
    value = data.get(key)
    if value is None and optional:
        return None
    array = _finite_array(value, (3, 3))
    if array is None:
        raise InputError("expected a finite 3x3 matrix", source=source, key=key)
    return array


def _fixtures(data: dict[str, Any], source: str) -> dict[str, Any] | None:
    block = data.get("fixtures")
    if block is None:
        return None
    if not isinstance(block, dict):
        raise InputError("expected a mapping", source=source, key="fixtures")
    for name, entry in block.items():
        ok = isinstance(entry, dict) and isinstance(entry.get("channels"), list)
        drive = entry.get("drive") if ok else None
        if not (ok and isinstance(drive, dict) and set(drive) == set(entry["channels"])):
            raise InputError(
                "expected channels and a drive for each", source=source, key=f"fixtures.{name}"
            )
        if not all(isinstance(v, (int, float)) and np.isfinite(v) for v in drive.values()):
            raise InputError("expected finite drives", source=source, key=f"fixtures.{name}")
        dmx = entry.get("dmx")
        if dmx is not None and not (
            isinstance(dmx, dict)
            and all(type(dmx.get(k)) is int for k in ("universe", "address"))
            and dmx.get("mode") in ("8-bit", "16-bit")
        ):
            raise InputError(
                "expected universe, address (integers) and mode (8-bit or 16-bit)",
                source=source,
                key=f"fixtures.{name}.dmx",
            )
    return block


def _finite_array(value: Any, shape: tuple[int, ...]) -> np.ndarray | None:
    """``value`` as a finite float64 array of ``shape``, or None when it is not one."""
    if not isinstance(value, list):
        return None
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        return None
    if array.shape != shape or not np.all(np.isfinite(array)):
        return None
    if np.any(np.abs(array) > MAX_SOLUTION_VALUE):
        return None
    return array


def _rgb(data: dict[str, Any], key: str, source: str, optional: bool = False) -> Any:
    value = data.get(key)
    if value is None and optional:
        return None
    array = _finite_array(value, (3,))
    if array is None:
        raise InputError("expected a finite [r, g, b]", source=source, key=key)
    return array


def _text(data: dict[str, Any], key: str, source: str, *, name: bool = False) -> str | None:
    """An optional string field; ``name`` ones must also be safe folder/OCIO names."""
    value = data.get(key)
    if value is None and not name:
        return None
    if name:
        return check_safe_name(value, source=source, key=key)
    if not isinstance(value, str) or len(value) > 200 or not value.isprintable():
        raise InputError(
            f"expected a short line of text, got {excerpt(value)}", source=source, key=key
        )
    return value


def _mapping(data: dict[str, Any], key: str, source: str) -> dict[str, Any]:
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputError(f"expected a mapping, got {excerpt(value)}", source=source, key=key)
    return value


def _read(path: Path) -> dict[str, Any]:
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
    source = str(path)
    data = _read(path)
    beta = data["beta"]
    if isinstance(beta, bool) or not isinstance(beta, (int, float)) or not 0 < beta <= 1:
        raise InputError(
            f"expected a number in (0, 1], got {excerpt(beta)}", source=source, key="beta"
        )
    measurements = _mapping(data, "measurements", source)
    linearity = data.get("linearity")
    if linearity is not None and not isinstance(linearity, dict):
        raise InputError(
            f"expected a mapping, got {excerpt(linearity)}", source=source, key="linearity"
        )
    ocio = _mapping(data, "ocio", source)
    if not all(isinstance(k, str) and isinstance(v, str) for k, v in ocio.items()):
        raise InputError("expected names (text) only", source=source, key="ocio")
    Q = _matrix(data, "Q", source)
    diagnostics = Diagnostics.from_dict(_mapping(data, "diagnostics", source))
    return Solution(
        stage=_text(data, "stage", source, name=True),
        environment=_text(data, "environment", source, name=True),
        method=_text(data, "method", source) or "",
        beta=float(beta),
        w_avg=_rgb(data, "w_avg", source),
        SL=_matrix(data, "SL", source),
        M=_matrix(data, "M", source),
        Q=Q,
        N=_matrix(data, "N", source, optional=True),
        black_level_offset=_rgb(data, "black_level_offset", source, optional=True),
        black_level_method=_text(data, "black_level_method", source),
        diagnostics=diagnostics,
        measurements_file=_text(measurements, "file", source),
        measurements_sha256=_text(measurements, "sha256", source),
        camera_colorspace=_text(data, "camera_colorspace", source),
        ocio=ocio,
        linearity=linearity,
        fixtures=_fixtures(data, source),
        post_correction=_post_correction(data, Q, diagnostics, source),
        panels=panel_solutions_from_dict(data.get("panels"), source),
    )


def _post_correction(
    data: dict[str, Any], Q: np.ndarray, diagnostics: Diagnostics, source: str
) -> PostCorrection:
    """The ``post_correction`` block; a file written before it existed gets its model back from
    where those versions kept it (a root-polynomial's coefficients in
    ``diagnostics.method_notes``, applied unbounded as they were), otherwise Q as a matrix."""
    block = data.get("post_correction")
    try:
        if block is not None:
            return correction_from_dict(block)
        old = (diagnostics.get("method_notes") or {}).get("root_polynomial")
        if old is None:
            return MatrixCorrection(Q)
        return RootPolynomialCorrection(old["coefficients"], Q)
    except InputError as error:
        raise InputError(error.problem, source=source, key=error.key) from None
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(
            f"malformed root-polynomial model ({error})",
            source=source,
            key="diagnostics.method_notes.root_polynomial",
        ) from None
