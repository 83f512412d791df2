"""From a measurements file to one :class:`~ocio_vp.formats.solution.Solution` per environment.

The paper's method (Section 3): beta and w_avg, M = [SL]^-1, Q by the chosen method (eq. 5),
N = M Q^-1 (eq. 8) and the black-level offset (Section 3.4), with the diagnostics.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.calibration.diagnostics import (
    clipped_patches,
    stability_diagnostics,
)
from ocio_vp.calibration.equations import (
    BLACK_LEVEL_METHODS,
    MAX_CONDITION_Q_FOR_N,
    black_level_offset,
    condition_number,
    predict_displayed_chart,
    solve_M,
    solve_N,
)
from ocio_vp.calibration.geometry import environment_panel_w_avg, environment_w_avg, stage_beta
from ocio_vp.calibration.panels import (
    InFrustumDrive,
    in_frustum_drive_for,
    in_frustum_match,
    light_shares,
    lit_white_errors,
    other_panels_light,
    panel_lights,
    panel_solutions,
)
from ocio_vp.choices import (
    DEFAULT_BLACK_LEVEL,
    DEFAULT_METHOD,
    DEFAULT_PRIORITY,
    PRIORITIES,
    BlackLevelMethod,
)
from ocio_vp.correction.extrapolation import Extrapolation, extrapolation
from ocio_vp.correction.guards import check_problem, singular_q_cause
from ocio_vp.correction.outliers import Inconsistency, inconsistent_patches
from ocio_vp.correction.problem import fit_least_squares
from ocio_vp.correction.registry import QFit, QProblem, solve_post_correction
from ocio_vp.correction.skin import chart_skin_samples, joined, patch_skin_samples
from ocio_vp.correction.skin_figures import skin_figures
from ocio_vp.correction.skin_priority import q_skin_priority
from ocio_vp.correction.skin_spectra import StageSpectra, spectral_skin_samples
from ocio_vp.correction.validation import CLOSED_FORM_METHODS, cross_validated_error
from ocio_vp.errors import InputError
from ocio_vp.fixtures.lighting import (
    FixtureLighting,
    fixtures_block,
    fixtures_diagnostics,
    light_with_fixtures,
)
from ocio_vp.formats.diagnostics import Charts, Diagnostics, PanelsNotes
from ocio_vp.formats.linearity import Linearity
from ocio_vp.formats.measurements import Environment, Measurements
from ocio_vp.formats.panel_solution import PanelSolution
from ocio_vp.formats.panels import primary_panel
from ocio_vp.formats.records import json_object
from ocio_vp.formats.skin import SkinFigures
from ocio_vp.formats.solution import Solution
from ocio_vp.formats.synthesis import synthesis_to_dict, synthesis_warnings
from ocio_vp.metrics import error_relative_to_white, sample_camera_to_xyz
from ocio_vp.model.correction import DEFAULT_DARK, PostCorrection, ProtectedCorrection

__all__ = [
    "DEFAULT_METHOD",
    "SolveOptions",
    "post_correction_problem",
    "solve_environment",
    "solve_measurements",
]


@dataclass(frozen=True)
class SolveOptions:
    """How an environment is solved: the options of ``solve``, ``demo`` and the library.

    ``method``: a name of :data:`ocio_vp.correction.registry.Q_SOLVE_METHODS`;
    ``black_level``: ``"exact"`` (``-M b_camera`` in drive space) or ``"paper"``
    (``b / w_camera``); ``max_condition_q``: N is not solved when cond(Q) is above it;
    ``fixtures``: drive the measurements' practical fixtures with the wall
    (:mod:`ocio_vp.fixtures`; no effect without a ``fixtures`` section); ``keep_all_patches``:
    fit every unclipped patch, even those inconsistent with the rest of the chart
    (:func:`ocio_vp.correction.outliers.inconsistent_patches`; otherwise excluded and named);
    ``protect_emitters``: the post-correction fades to the identity where no reflective surface
    lit by the stage can be (:class:`ocio_vp.model.ProtectedCorrection`); ``priority``:
    ``"skin"`` fits the default post-correction with faces first
    (:mod:`ocio_vp.correction.skin_priority`; only with ``method="auto"``), ``"general"`` is
    the default's own choice; an environment's ``priority`` in the measurements file wins;
    ``spectra``: the panel's LED spectra and the camera's sensitivities (and location lights),
    from which skin samples are computed too (:mod:`ocio_vp.correction.skin_spectra`).
    """

    method: str = DEFAULT_METHOD
    black_level: BlackLevelMethod = DEFAULT_BLACK_LEVEL
    max_condition_q: float = MAX_CONDITION_Q_FOR_N
    fixtures: bool = True
    keep_all_patches: bool = False
    protect_emitters: bool = False
    priority: str = DEFAULT_PRIORITY
    spectra: StageSpectra | None = None

    def __post_init__(self) -> None:
        if self.priority not in PRIORITIES:
            raise ValueError(f"priority must be one of {PRIORITIES}, got {self.priority!r}")
        if self.black_level not in BLACK_LEVEL_METHODS:
            raise ValueError(
                f"black_level must be one of {BLACK_LEVEL_METHODS}, got {self.black_level!r}"
            )


def _assumed(measurements: Measurements, environment: Environment) -> list[str]:
    """What the solve assumes for optional measurements the file does not give."""
    from ocio_vp.correction.outliers import patch_name

    out = []
    stage = measurements.stage
    if not stage.white_patch_stated:
        name = patch_name(stage.white_patch, measurements.n_patches).partition(" (")[2][:-1]
        out.append(
            f"no stage.white_patch: patch {stage.white_patch + 1} {name} (index "
            f"{stage.white_patch}) assumed to be the chart's white; state it if the chart is "
            "another one or turned"
        )
    if environment.black_level is None:
        out.append(
            "no black_level: no in-frustum black-level offset, so the stage's light bounced "
            "off the dark panels is not cancelled (the wall's black reads lifted in camera); "
            "shoot the black-level plate (docs/capture.md)"
        )
    return out


def solve_environment(
    measurements: Measurements,
    environment: Environment,
    options: SolveOptions | None = None,
    **changes: Any,
) -> Solution:
    """Solve M, Q, N and the black-level offset for one environment, with ``options`` (default
    :class:`SolveOptions`) and ``changes`` to its fields (another name is a TypeError)."""
    options = dataclasses.replace(options or SolveOptions(), **changes)
    environment = _primary_environment(measurements, environment)
    clipped = _clipped_patches(measurements, environment)
    problem = post_correction_problem(measurements, environment, clipped)
    lighting = _lighting(measurements, problem, options.method) if options.fixtures else None
    if lighting is not None and lighting.result.applied:
        problem = dataclasses.replace(problem, extra_light=lighting.extra_light)
    problem, excluded = _screen(problem, measurements, environment, options.keep_all_patches)
    problem = with_skin(problem, measurements.stage.skin_patches, options.spectra, environment.name)
    priority = environment.priority or options.priority
    guard = functools.partial(_protected, problem=problem, options=options)
    fit = _fit(problem, options.method, measurements, environment, priority, guard)
    correction = _protected(fit.correction, problem, options)
    skin = _skin_figures(problem, fit, correction, priority, options)
    SL, M_calibrated = problem.SL, problem.M
    M = M_calibrated if fit.M is None else np.asarray(fit.M, dtype=np.float64)
    if lighting is not None:
        M = lighting.M
    Q = correction.matrix
    # N inverts Q for the calibrated wall (paper eq. 7: Q [SL] N = I), whatever M lights with.
    N, n_reason = solve_N(M_calibrated, Q, max_condition=options.max_condition_q, SL=SL)
    if n_reason:
        n_reason = f"{singular_q_cause(problem, fit.model)}; {n_reason}"
    offset = None
    if environment.black_level is not None:
        offset = black_level_offset(
            environment.black_level, M=M_calibrated, SL=SL, method=options.black_level
        )
    charts = _charts(problem, fit, correction, M=M, N=N, offset=offset, environment=environment)
    diagnostics = _diagnostics(
        problem, fit, correction, charts, options=options, M=M, N=N, n_reason=n_reason,
        offset=offset, environment=environment, clipped=clipped, lighting=lighting,
        excluded=None if options.keep_all_patches else excluded,
    )  # fmt: skip
    diagnostics = dataclasses.replace(diagnostics, skin=skin)
    assumed = _assumed(measurements, environment)
    if assumed:
        diagnostics = dataclasses.replace(diagnostics, assumed=assumed)
    linearity, panels = _panel_linearity(measurements), None
    if measurements.panels:
        panels, block, notes = _solve_panels(
            measurements, environment, correction, options, M=M, N=N, n_reason=n_reason,
            offset=offset, linearity=linearity,
        )  # fmt: skip
        warnings = [*diagnostics.warnings, *notes]
        diagnostics = dataclasses.replace(diagnostics, panels=block, warnings=warnings)
    return Solution(
        stage=measurements.stage.name,
        environment=environment.name,
        method=options.method,
        beta=problem.beta,
        w_avg=problem.w_avg,
        SL=SL,
        M=M,
        post_correction=correction,
        N=N,
        black_level_offset=offset,
        black_level_method=None if offset is None else options.black_level,
        diagnostics=diagnostics,
        measurements_file=Path(measurements.source).name if measurements.source else None,
        measurements_sha256=measurements.sha256,
        camera_colorspace=measurements.stage.camera_colorspace,
        linearity=linearity,
        fixtures=None if lighting is None else fixtures_block(lighting),
        panels=panels,
    )


def _protected(
    correction: PostCorrection, problem: QProblem, options: SolveOptions
) -> PostCorrection:
    """``correction``, fading to the identity beyond the reflective solid with
    ``protect_emitters``."""
    if not options.protect_emitters or isinstance(correction, ProtectedCorrection):
        return correction
    return ProtectedCorrection(correction, problem.domain, problem.M, dark=DEFAULT_DARK)


def _skin_figures(
    problem: QProblem, fit: QFit, correction: PostCorrection, priority: str, options: SolveOptions
) -> SkinFigures | None:
    """What the solve expects of skin; with skin first, beside the default's (the fit skin
    first compared with, protected alike)."""
    default = None
    if priority == "skin" and fit.default is not None:
        default = (fit.default.model, _protected(fit.default.correction, problem, options))
    return skin_figures(problem, correction, priority, default)


def _lighting(measurements: Measurements, problem: QProblem, method: str) -> FixtureLighting | None:
    """The fixtures' drives with the wall's (None without a ``fixtures`` section)."""
    if not measurements.fixtures:
        return None
    if method == "joint":
        raise InputError(
            "--method joint re-solves the wall's light itself and cannot share it with "
            "fixtures: use another method, or solve --no-fixtures",
            source=measurements.source,
            key="fixtures",
        )
    return light_with_fixtures(measurements.fixtures, problem, camera_to_xyz=sample_camera_to_xyz())


def _environment_key(measurements: Measurements, environment: Environment, key: str) -> str:
    index = [e.name for e in measurements.environments].index(environment.name)
    return f"environments[{index}].{key}"


def _clipped_patches(measurements: Measurements, environment: Environment) -> list[int]:
    """The chart patches at the clip level; an error when a primary or needed white clips."""
    source = measurements.source
    white = measurements.stage.white_patch
    clip_level = measurements.stage.clip_level
    types = [("", measurements.SL, measurements.SRL)]
    if measurements.panels:
        types = [(f"panels[{i}].", p.SL, p.SRL) for i, p in enumerate(measurements.panels)]
    clipped: list[int] = []
    for where, SL, SRL in types:
        if clip_level is not None and np.any(SL >= clip_level):
            raise InputError(
                f"a primary is clipped (>= clip_level {clip_level:g}): [SL] and M would be "
                "wrong; re-shoot the primaries with less exposure",
                source=source,
                key=f"{where}primaries",
            )
        found = clipped_patches(SRL, environment.target_chart, clip_level)
        clipped = sorted(set(clipped) | set(found)) if measurements.panels else found
    if white in clipped and environment.w_avg is None:
        raise InputError(
            f"the white patch {white} is clipped, so w_avg cannot come from it: give w_avg",
            source=source,
            key=_environment_key(measurements, environment, "w_avg"),
        )
    return clipped


def post_correction_problem(
    measurements: Measurements, environment: Environment, clipped: Sequence[int] = ()
) -> QProblem:
    """The post-correction problem of ``environment`` as the solve poses it: M = [SL]^-1,
    beta, w_avg, the target; the ``clipped`` patches weigh 0. With ``panels``: the first
    in-frustum type's eq. 3, every other type's light as ``extra_light``."""
    weights = np.ones(measurements.n_patches)
    weights[list(clipped)] = 0.0
    extra = None
    if measurements.panels:
        lights = panel_lights(measurements, environment_panel_w_avg(measurements, environment))
        primary = next(light for light in lights if light.panel.in_frustum)
        SL, SRL, beta, M = primary.panel.SL, primary.panel.SRL, primary.beta, primary.M
        w_avg, extra = primary.w_avg, other_panels_light(lights, primary.name)
    else:
        SL, SRL, beta = measurements.SL, measurements.SRL, stage_beta(measurements)
        M = solve_M(measurements.SL, source=measurements.source)
        w_avg = environment_w_avg(measurements, environment)
    return QProblem(
        SL=SL,
        SRL=SRL,
        beta=beta,
        M=M,
        w_avg=w_avg,
        target=environment.target_chart,
        white_patch=measurements.stage.white_patch,
        weights=weights,
        white_reflectance=measurements.stage.white_reflectance,
        extra_light=extra,
        black_level=environment.black_level,
    )


def _primary_environment(measurements: Measurements, environment: Environment) -> Environment:
    """With ``panels``: the environment as its first in-frustum type sees it (its w_avg and
    black level), so the single-wall steps apply."""
    if not measurements.panels:
        return environment
    primary = primary_panel(measurements.panels).name
    w_avg = None if environment.panel_w_avg is None else environment.panel_w_avg[primary]
    black = (environment.panel_black_level or {}).get(primary)
    return dataclasses.replace(environment, w_avg=w_avg, black_level=black)


def _solve_panels(
    measurements: Measurements,
    environment: Environment,
    correction: PostCorrection,
    options: SolveOptions,
    *,
    M: np.ndarray,
    N: np.ndarray | None,
    n_reason: str | None,
    offset: np.ndarray | None,
    linearity: Linearity | None,
) -> tuple[dict[str, PanelSolution], PanelsNotes, list[str]]:
    """solution.json's ``panels`` block (every type's M; N and offset in frustum), the
    diagnostics' (shares of the light, in-camera match) and the warnings."""
    primary = primary_panel(measurements.panels).name
    lights = panel_lights(measurements, environment_panel_w_avg(measurements, environment))
    blacks = dict(environment.panel_black_level or {})
    white, camera = measurements.stage.white_patch, sample_camera_to_xyz()
    drives: dict[str, InFrustumDrive] = {primary: InFrustumDrive(N, n_reason, offset)}
    for light in lights:
        if light.panel.in_frustum and light.name != primary:
            drives[light.name] = in_frustum_drive_for(
                light, correction.matrix, black_level=blacks.get(light.name),
                method=options.black_level, max_condition=options.max_condition_q,
            )  # fmt: skip
    match, warnings = in_frustum_match(
        lights, drives, primary=primary, target=environment.target_chart,
        correction=correction, black_levels=blacks, white_patch=white, camera_to_xyz=camera,
    )  # fmt: skip
    shares = light_shares(lights, white, camera)
    fitted = {
        p.name: linearity if p.name == primary else _type_linearity(measurements, i)
        for i, p in enumerate(measurements.panels)
    }
    panels = panel_solutions(lights, drives, shares, fitted)
    first = panels[primary]
    panels[primary] = dataclasses.replace(first, M=M, drive=M @ first.w_avg)
    for light in lights:
        if light.name != primary and np.any(light.drive < 0):
            warnings.append(
                f"panel type {light.name}: its drive M w_avg has a negative channel: this light "
                "is outside its LED gamut and the panels clip it"
            )
    own_M, primary_M = lit_white_errors(lights, environment.target_chart, white, primary)
    block = PanelsNotes(
        primary=primary,
        shares=shares,
        lit_white_error=own_M,
        lit_white_error_primary_M=primary_M,
        in_frustum_match=match,
    )
    return panels, block, warnings


def _type_linearity(measurements: Measurements, index: int) -> Linearity | None:
    """A panel type's ``linearity`` from its own ramps and ``encoding`` (None without either)."""
    from ocio_vp.wall.linearity import fit_linearity

    panel = measurements.panels[index]
    linearity = None
    if panel.ramps is not None:
        try:
            linearity = fit_linearity(panel.ramps, panel.SL, source=measurements.source)
        except InputError as error:
            key = f"panels[{index}].{error.key}" if error.key else f"panels[{index}].ramps"
            raise InputError(error.problem, source=error.source, key=key) from None
    if panel.encoding is None:
        return linearity
    from ocio_vp.formats.linearity import assumed_linearity
    from ocio_vp.wall.encoding import WallEncoding

    wall = WallEncoding(panel.encoding, panel.peak_nits).block()
    return (linearity or assumed_linearity()).updated(wall_encoding=wall)


def _located(error: InputError, measurements: Measurements, environment: Environment):
    """A Q-solve error placed in the measurements file (``environments[i].target_chart``...)."""
    if error.source is not None or error.key not in ("target_chart", "lit_chart", "w_avg"):
        return error
    key = error.key
    if key != "lit_chart":
        key = _environment_key(measurements, environment, key)
    return InputError(error.problem, source=measurements.source, key=key)


def _screen(
    problem: QProblem, measurements: Measurements, environment: Environment, keep_all: bool
) -> tuple[QProblem, list[Inconsistency]]:
    """Check the chart, then exclude the patches inconsistent with the rest unless ``keep_all``
    (a white patch that sets w_avg is refused instead)."""
    try:
        check_problem(problem)
        if keep_all:
            return problem, []
        w = problem.fit_weights
        excluded = inconsistent_patches(problem.predicted, problem.target, w, problem.white_patch)
        white = [f for f in excluded if f.index == problem.white_patch]
        if white and environment.w_avg is None:
            raise InputError(
                f"the white patch is inconsistent with the rest of the chart "
                f"({white[0].describe()}) and w_avg is derived from it: give w_avg, or "
                "re-measure the white patch",
                key="w_avg",
            )
    except InputError as error:
        raise _located(error, measurements, environment) from None
    if not excluded:
        return problem, []
    weights = w.copy()
    weights[[f.index for f in excluded]] = 0.0
    return dataclasses.replace(problem, weights=weights), excluded


def with_skin(
    problem: QProblem,
    named: tuple[int, ...] = (),
    spectra: StageSpectra | None = None,
    environment: str = "",
) -> QProblem:
    """``problem`` with its skin samples (:mod:`ocio_vp.correction.skin`): the ``named`` skin
    patches, else virtual skin on a ColorChecker 24 (and from the stage's ``spectra``), else
    the patches of skin colour."""
    active = problem.fit_weights > 0
    target = np.asarray(problem.target, dtype=np.float64)
    skin = None
    if not named:
        skin = chart_skin_samples(problem.SRL, target, active)
    if skin is not None and spectra is not None and problem.extra_light is None:
        exact = spectral_skin_samples(problem.SRL, target, active, spectra, environment)
        skin = joined(skin, exact)
    if skin is None:
        skin = patch_skin_samples(problem.SRL, target, problem.white_patch, active, named)
    return dataclasses.replace(problem, skin=skin)


def _fit(
    problem: QProblem,
    method: str,
    measurements: Measurements,
    environment: Environment,
    priority: str = DEFAULT_PRIORITY,
    guard: Callable[[PostCorrection], PostCorrection] | None = None,
) -> QFit:
    """Q by ``method`` (skin first with ``priority="skin"``, judged through the emitter
    ``guard``); a bad chart is reported at its place in the measurements file."""
    if priority == "skin" and method != "auto":
        in_file = environment.priority is not None
        raise InputError(
            f"skin priority fits the default post-correction itself and cannot be combined "
            f"with --method {method}: drop --method (or the priority)",
            source=measurements.source if in_file else None,
            key=_environment_key(measurements, environment, "priority")
            if in_file
            else "--priority",
        )
    try:
        if priority == "skin":
            return q_skin_priority(problem, guard)
        return solve_post_correction(problem, method=method)
    except InputError as error:
        raise _located(error, measurements, environment) from None


def _charts(
    problem: QProblem,
    fit: QFit,
    correction: PostCorrection,
    *,
    M: np.ndarray,
    N: np.ndarray | None,
    offset: np.ndarray | None,
    environment: Environment,
) -> Charts:
    """Per-patch camera RGB: the target, the lit chart under M (baseline) and after Q, and the
    chart shown in frustum (baseline: through M; ours: N and the offset, or ``M Q^-1(c)`` for a
    non-linear Q as the config does, then Q)."""
    baseline = problem.predicted
    lit = baseline if fit.M is None else dataclasses.replace(problem, M=M).predicted
    content, matrix = environment.target_chart, problem.M if N is None else N
    if N is not None and not correction.linear:
        content, matrix = correction.inverse(content), problem.M
    displayed = predict_displayed_chart(
        content,
        SL=problem.SL,
        matrix=matrix,
        offset=offset,
        black_level=environment.black_level,
    )
    displayed_baseline = predict_displayed_chart(
        environment.target_chart,
        SL=problem.SL,
        matrix=problem.M,
        black_level=environment.black_level,
    )
    return Charts(
        target=environment.target_chart,
        lit_baseline=baseline,
        lit_corrected=correction.apply(lit),
        displayed_baseline=displayed_baseline,
        displayed_corrected=displayed if N is None else correction.apply(displayed),
    )


def _extrapolation(problem: QProblem, fit: QFit, correction: PostCorrection) -> Extrapolation:
    """The post-correction beyond the chart against least squares on the same patches (its fold
    fraction as the fit measured it, where it did)."""
    X, P, w = problem.predicted, np.asarray(problem.target, dtype=np.float64), problem.fit_weights
    return extrapolation(
        correction,
        fit_least_squares(X, P, w),
        SL=problem.SL,
        white=P[problem.white_patch],
        lit_white=X[problem.white_patch],
        camera_to_xyz=sample_camera_to_xyz(),
        domain=problem.domain,
        folds=None if fit.folds is None else fit.folds.of(correction, problem.domain),
    )


def _diagnostics(
    problem: QProblem,
    fit: QFit,
    correction: PostCorrection,
    charts: Charts,
    *,
    options: SolveOptions,
    M: np.ndarray,
    N: np.ndarray | None,
    n_reason: str | None,
    offset: np.ndarray | None,
    environment: Environment,
    clipped: list[int],
    lighting: FixtureLighting | None = None,
    excluded: list[Inconsistency] | None = None,
) -> Diagnostics:
    """Errors, conditioning, warnings and the stability block (calibration.diagnostics)."""
    target, white, weights = problem.target, problem.white_patch, problem.weights
    Q = correction.matrix

    def error(chart: np.ndarray) -> np.ndarray:
        return error_relative_to_white(chart, target, white, weights)

    drive = M @ problem.w_avg
    warnings = [
        f"chart patch excluded from the fit, inconsistent with the rest: {f.describe()}"
        for f in excluded or []
    ]
    if n_reason:
        warnings.append(f"N not solved: {n_reason}")
    method = options.method
    stability, stability_warnings = stability_diagnostics(
        problem,
        fit,
        method=method,
        M=M,
        Q=Q,
        N=N,
        offset=offset,
        black_level=environment.black_level,
        corrected=charts.lit_corrected,
        clipped=clipped,
        cross_validated=cross_validated_error(problem, method)
        if fit.cross_validated_error is None and method in CLOSED_FORM_METHODS
        else None,
    )
    synthesized = environment.synthesized
    synthesized_warnings = [] if synthesized is None else synthesis_warnings(synthesized)
    return Diagnostics(
        white_patch=white,
        cond_SL=condition_number(problem.SL),
        cond_Q=condition_number(Q),
        rank_Q=int(np.linalg.matrix_rank(Q)),
        N_solved=N is not None,
        N_reason=n_reason,
        max_condition_q_for_N=options.max_condition_q,
        lit_chart_error_baseline=error(charts.lit_baseline),
        lit_chart_error=error(charts.lit_corrected),
        residual_rms=float(np.sqrt(np.mean((charts.lit_corrected - target) ** 2))),
        displayed_chart_error_baseline=error(charts.displayed_baseline),
        displayed_chart_error=error(charts.displayed_corrected),
        out_of_frustum_drive=drive,
        method_notes=json_object(fit.notes),
        warnings=warnings + stability_warnings + synthesized_warnings,
        charts=charts,
        **stability,
        synthesized_target=None if synthesized is None else synthesis_to_dict(synthesized),
        fixtures=None if lighting is None else fixtures_diagnostics(lighting),
        patch_screening=excluded is not None,
        excluded_patches=list(excluded or []),
        model_description=correction.describe(),
        extrapolation=_extrapolation(problem, fit, correction),
    )


def _panel_linearity(measurements: Measurements) -> Linearity | None:
    """The ``linearity`` block from the ``ramps`` section (None when there is none)."""
    if measurements.panels:
        first = primary_panel(measurements.panels)
        return _type_linearity(measurements, measurements.panels.index(first))
    if measurements.ramps is None:
        return None
    from ocio_vp.wall.linearity import fit_linearity

    return fit_linearity(measurements.ramps, measurements.SL, source=measurements.source)


def solve_measurements(
    measurements: Measurements, options: SolveOptions | None = None, **changes: Any
) -> list[Solution]:
    """:func:`solve_environment` for every environment, in file order."""
    options = dataclasses.replace(options or SolveOptions(), **changes)
    return [solve_environment(measurements, env, options) for env in measurements.environments]
