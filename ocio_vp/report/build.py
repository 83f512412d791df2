"""``ocio-vp report``: a self-contained HTML page and its SVG figures for one or more solutions
(what it shows: docs/report.md), published all or nothing; the numbers come from
``solution.json`` only (:mod:`ocio_vp.report.data`).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.calibration.equations import condition_number, condition_text
from ocio_vp.calibration.headroom import content_scale
from ocio_vp.errors import InputError
from ocio_vp.formats.diagnostics import lowest_channel_words
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.linearity import Linearity
from ocio_vp.formats.provenance import solution_sha256
from ocio_vp.formats.records import json_object
from ocio_vp.formats.solution import Solution
from ocio_vp.formats.solution_inputs import solution_folders
from ocio_vp.model.correction import (
    ProtectedCorrection,
    RootPolynomialCorrection,
    unprotected,
)
from ocio_vp.model.expansion import root_polynomial_terms
from ocio_vp.report.data import (
    STAGE_CHARTS,
    EnvironmentData,
    environment_data,
)
from ocio_vp.report.panels import panel_facts
from ocio_vp.report.plots import (
    ChartPlot,
    DeltaEPlot,
    ErrorBarsPlot,
    LinearityPlot,
    plot_comparison_charts,
    plot_delta_e,
    plot_error_bars,
    plot_linearity,
)
from ocio_vp.report.skin import skin_facts, skin_panel
from ocio_vp.staging import publish_dir, staged_dir
from ocio_vp.wall.softclip import soft_clip_knee

__all__ = [
    "Report",
    "build_report",
    "default_report_dir",
    "linearity_curves",
    "panel_description",
]

TEMPLATE = "report.html.j2"


@dataclass
class Report:
    """What :func:`build_report` wrote: the page and the numbers behind every figure (their
    paths in the final folder)."""

    index: Path
    environments: list[EnvironmentData]
    error_bars: dict[str, ErrorBarsPlot] = field(default_factory=dict)
    charts: dict[str, ChartPlot] = field(default_factory=dict)
    delta_e: dict[str, DeltaEPlot] = field(default_factory=dict)
    linearity: dict[str, LinearityPlot] = field(default_factory=dict)


def default_report_dir(paths: Sequence[str | Path]) -> Path:
    """Where a report goes without ``--out``: ``SOLVE/report`` for all environments of one
    ``solve`` output folder, ``SOLVE/<environment>/report`` for one, ``SOLVE/report-<env>+...``
    for some; an InputError for solutions from several solve folders."""
    chosen = solution_folders(paths)
    if len(chosen.solve_folders) != 1:
        raise InputError(
            "these solutions come from several solve output folders: give --out", key="--out"
        )
    if chosen.complete:
        return chosen.solve_folders[0] / "report"
    if len(chosen.folders) == 1:
        return chosen.folders[0].resolve() / "report"
    name = "report-" + "+".join(chosen.environments)
    if len(name) > 120:
        digest = hashlib.sha256("+".join(chosen.environments).encode()).hexdigest()[:10]
        name = f"report-{len(chosen.folders)}-environments-{digest}"
    return chosen.solve_folders[0] / name


def linearity_curves(linearity: Linearity | None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Panel response curves from a solution's ``linearity``: every channel's measured knots
    ("before") and, for a corrected one, the response after its LUT ``r(r^-1(x))`` ("after")."""
    curves: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if linearity is None or not linearity.channels:
        return curves
    for channel, entry in linearity.channels.items():
        drive, response = entry.drive, entry.response
        if drive.shape != response.shape or not np.all(np.isfinite(response)):
            continue
        curves[f"{channel} before"] = (drive, response)
        if entry.corrected:
            from ocio_vp.wall.linearity import inverse_response, response_model

            x = np.linspace(0.0, 1.0, 33)
            after = response_model(drive, response)(inverse_response(drive, response, x))
            curves[f"{channel} after"] = (x, np.asarray(after, dtype=np.float64))
    return curves


def panel_description(solution: Solution, path: Path) -> str | None:
    """The calibration panel's geometry from the measurements file the solution names, found in
    the solve output folder with the SHA-256 it records (None otherwise)."""
    name = solution.measurements_file
    if not name or not solution.measurements_sha256:
        return None
    candidate = Path(path).parent.parent / Path(name).name
    try:
        raw = candidate.read_bytes()
    except OSError:
        return None
    if hashlib.sha256(raw).hexdigest() != solution.measurements_sha256:
        return None
    return _panel_text(str(candidate), solution.measurements_sha256)


@functools.lru_cache(maxsize=16)
def _panel_text(candidate: str, sha256: str) -> str:
    """Parse the measurements file once per content (every environment of a solve names it)."""
    from ocio_vp.formats.measurements import load_measurements

    path = Path(candidate)
    panel = load_measurements(path).stage.panel
    if panel is None:
        return f"beta given directly in {path.name}"
    text = f"{panel.width:g} m x {panel.height:g} m at {panel.distance:g} m"
    if panel.offset_x or panel.offset_y:
        text += f", centre offset ({panel.offset_x:g}, {panel.offset_y:g}) m"
    return f"{text} (from {path.name})"


def _matrix_rows(name: str, matrix: np.ndarray | None, meaning: str) -> JsonObject:
    if matrix is None:
        return {"name": name, "meaning": meaning, "rows": None, "cond": None}
    return {
        "name": name,
        "meaning": meaning,
        "rows": [[f"{v:+.5f}" for v in row] for row in np.asarray(matrix)],
        "cond": condition_text(condition_number(matrix)),  # a singular one as the terminal
    }


def _percent(values: np.ndarray) -> str:
    return f"{100 * float(np.mean(values)):.2f}%"


def _context(data: EnvironmentData, images: dict[str, str]) -> dict[str, Any]:
    s = data.solution
    d = s.diagnostics
    matrices = [
        _matrix_rows("[SL]", s.SL, "camera RGB of the LED primaries (columns)"),
        _matrix_rows("M", s.M, "out-of-frustum pre-correction, [SL]^-1 (eq. 2)"),
        *_q_rows(s),
        _matrix_rows("N", s.N, "in-frustum pre-correction, M Q^-1 (eq. 8)"),
    ]
    facts = [
        ("stage", s.stage),
        ("Q method", _method(s)),
        ("why this model", d.model_reason or "the method asked for"),
        ("beyond the chart", _beyond_the_chart(s)),
        ("beta (panel form factor)", f"{s.beta:.5f}"),
        ("w_avg (camera RGB)", ", ".join(f"{v:.5g}" for v in s.w_avg)),
        ("out-of-frustum drive M w_avg", _triple(d.out_of_frustum_drive)),
        ("N", "solved" if s.N is not None else f"not solved: {d.N_reason}"),
        (
            "black level offset",
            "none (no black-level measurement)"
            if s.black_level_offset is None
            else f"{_triple(s.black_level_offset)} ({s.black_level_method})",
        ),
        ("rank Q", d.rank_Q),
        ("camera colour space", s.camera_colorspace or "camera native (as measured)"),
        ("measurements", f"{s.measurements_file} (sha256 {str(s.measurements_sha256)[:12]}…)"),
        ("solution file", Path(*Path(data.path).parts[-2:]).as_posix()),  # no absolute paths
        ("white patch (index)", data.white_patch),
    ]
    panel = panel_description(s, data.path)
    facts.insert(3, ("calibration panel", panel or "not recorded in solution.json (beta only)"))
    facts += _fixture_facts(s)
    facts += panel_facts(s)  # a stage of several panel types
    facts += skin_facts(s)
    facts += _soft_clip_facts(s)
    notes = d.method_notes or {}
    rows = [
        {
            "chart": chart.replace("_", " "),
            "error": [f"{100 * v:.2f}%" for v in data.errors[chart]],
            "mean": _percent(data.errors[chart]),
            "de2000": f"{float(np.mean(data.delta_e['CIE 2000'][chart])):.2f}",
            "deitp": mean_defined(data.delta_e["ITP"][chart]),
        }
        for chart in STAGE_CHARTS
    ]
    return {
        "name": s.environment,
        "key": data.key,
        "images": images,
        "matrices": matrices,
        "facts": facts,
        "notes": sorted((str(k), _short(v)) for k, v in notes.items()),
        "warnings": [str(w) for w in d.warnings],
        "errors": rows,
        "transform": data.transform.description,
        "linearity": _linearity_facts(s.linearity),
    }


def _soft_clip_facts(solution: Solution) -> list[tuple[str, str]]:
    """The wall's soft clip (solve --soft-clip) and what content it starts at; none when off."""
    if soft_clip_knee(solution.linearity) is None:
        return []
    scale = content_scale(solution)
    if scale.soft_clip is None:
        return []
    return [
        (
            "wall soft clip",
            f"each channel's drive compressed from {100 * scale.soft_clip:.0f}% of full drive "
            f"towards full drive (content {scale.knee_content:.3g} on; hard clip at content "
            f"{scale.peak_content:.3g} without it)",
        )
    ]


def _fixture_facts(solution: Solution) -> list[tuple[str, str]]:
    """Practical fixtures: each one's drives, and what they did to the error Q cannot remove."""
    if not solution.fixtures:
        return []
    notes = solution.diagnostics.fixtures
    facts = [
        (
            f"fixture {name}",
            ", ".join(f"{c} {block.drive[c]:.3f}" for c in block.channels)
            + f" (of max {block.max_drive:g})",
        )
        for name, block in solution.fixtures.items()
    ]
    if notes is not None and notes.applied:
        limits = ", ".join(notes.active_limits) or "none"
        change = (
            f"{notes.error_wall_only:.3g} with the wall alone -> {notes.error_with_fixtures:.3g} "
            f"with the fixtures ({100 * notes.error_reduction:.0f}% lower); active limits: {limits}"
        )
    else:
        change = f"fixtures off: {'not solved' if notes is None else notes.reason}"
    return [*facts, ("error Q cannot remove (eq. 5 residual)", change)]


def _method(solution: Solution) -> str:
    """The Q method, the model an automatic method chose, and the post-correction in words."""
    model = solution.model
    text = solution.method
    if model != solution.method:
        text = f"{solution.method} → {model}"
    return f"{text} ({solution.correction.describe()})"


def _share(value: float | str, sign: str = "") -> str:
    """A share in %; JSON keeps an infinite one as text ("-inf")."""
    number = float(value)
    return f"{number:{sign}.0%}" if np.isfinite(number) else f"{number:{sign}}"


def _beyond_the_chart(solution: Solution) -> str:
    """The extrapolation figures (docs/stability.md, *Beyond the chart*) and the emitter guard."""
    figures = solution.diagnostics.extrapolation
    text = "not measured (a solution written before these figures)"
    if figures is not None:
        folds = figures.folds
        text = (
            f"the wall's LEDs seen in frame: p95 ΔE2000 {figures.led_damage:.3g} "
            f"(least squares {figures.led_damage_least_squares:.3g}); bright saturated "
            f"inputs keep >= {_share(figures.kept)} of their channel, "
            f"{lowest_channel_words(figures.negative)}; "
            + ("no inverse" if folds is None else f"folds in {folds:.1%} of reflective colours")
        )
    if isinstance(solution.correction, ProtectedCorrection):
        text += f"; emitter guard: {solution.correction.protection()}"
    return text


def _q_rows(solution: Solution) -> list[JsonObject]:
    """Q's matrix; for a root-polynomial Q, its coefficients too (what the config's LUTs and
    ``ocio-vp apply`` use) and the matrix named as the model's 3x3 fallback."""
    polynomial = unprotected(solution.correction)
    if not isinstance(polynomial, RootPolynomialCorrection):
        return [_matrix_rows("Q", solution.Q, "post-correction of the footage (eq. 5)")]
    terms = root_polynomial_terms(polynomial.degree)
    model = _matrix_rows(
        "Q (root-polynomial)",
        polynomial.coefficients,
        f"Q(x) = C ({', '.join(terms)}) inside the chart's domain: the footage's "
        "post-correction (config LUTs, apply)",
    )
    model["cond"] = None  # not square
    fallback = "3x3 fallback of Q outside the chart's domain (solution.json's Q; N = M Q^-1 there)"
    return [model, _matrix_rows("Q (3x3)", solution.Q, fallback)]


def _short(value: JsonValue) -> str:
    """Notes as a person reads them: floats to 4 significant digits, inside lists and dicts."""

    def walk(v: JsonValue) -> JsonValue:
        if isinstance(v, float):
            return float(f"{v:.4g}")
        if isinstance(v, dict):
            return {k: walk(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [walk(x) for x in v]
        return v

    value = walk(value)
    if isinstance(value, dict):
        return ", ".join(f"{k}: {v}" for k, v in value.items())
    return str(value)


def _triple(values: ArrayLike | None) -> str:
    if values is None:
        return "—"
    return ", ".join(f"{float(v):.5g}" for v in np.ravel(values))


def _linearity_facts(linearity: Linearity | None) -> list[tuple[str, str]]:
    if linearity is None:
        return []
    block = json_object(linearity.to_dict())
    return [(k, str(v)) for k, v in block.items() if not isinstance(v, (dict, list))]


def _summary(environments: Sequence[EnvironmentData]) -> list[dict[str, str]]:
    rows = []
    for e in environments:
        d = e.solution.diagnostics
        rows.append(
            {
                "name": e.solution.environment,
                "key": e.key,
                "method": _method(e.solution),
                "cond_q": "-" if d.cond_Q is None else condition_text(d.cond_Q),
                "n": "solved" if e.solution.N is not None else "not solved",
                **{chart: _percent(e.errors[chart]) for chart in STAGE_CHARTS},
                "warnings": str(len(d.warnings)),
            }
        )
    return rows


#: Beside index.html: which solutions the report shows (read before a report is replaced).
MANIFEST = "report.json"


def _solutions(environments: Sequence[EnvironmentData], out_dir: Path) -> list[str]:
    """The solutions, named relative to the report folder: no absolute path in any output."""
    return [
        Path(os.path.relpath(data.path.resolve(), out_dir.resolve())).as_posix()
        for data in environments
    ]


def _manifest(environments: Sequence[EnvironmentData], out_dir: Path) -> JsonObject:
    return {
        "format": "ocio-vp/report",
        "version": 1,
        "environments": [data.solution.environment for data in environments],
        "solutions": _solutions(environments, out_dir),
        # which solution each environment's figures come from (a re-solve flags the report)
        "solution_sha256": {
            data.solution.environment: solution_sha256(data.path.parent) for data in environments
        },
    }


def mean_defined(values: np.ndarray) -> str:
    """Mean of the defined (non-NaN) values, saying how many were undefined."""
    values = np.asarray(values, dtype=np.float64)
    undefined = int(np.count_nonzero(np.isnan(values)))
    if undefined == values.size:
        return "undefined"
    mean = f"{float(np.nanmean(values)):.2f}"
    return mean if not undefined else f"{mean} ({undefined} of {values.size} undefined)"


def _check_replaceable(
    out_dir: Path, environments: Sequence[EnvironmentData], *, replace: bool = False
) -> None:
    """The report folder is replaced as a whole: never let that be anything but a report, and
    never a report on solutions this one leaves out (unless ``replace``)."""
    for data in environments:
        if data.path.resolve().is_relative_to(out_dir):
            raise InputError(
                "the report folder would replace the solutions it reports on; choose another --out",
                source=out_dir,
            )
    if out_dir.is_file() or (
        out_dir.is_dir() and any(out_dir.iterdir()) and not (out_dir / "index.html").is_file()
    ):
        raise InputError(
            "exists and is not an ocio-vp report (no index.html); refusing to replace it",
            source=out_dir,
        )
    try:
        old = json.loads((out_dir / MANIFEST).read_text(encoding="utf-8"))
        old_solutions = dict(zip(old["solutions"], old["environments"], strict=True))
    except (OSError, ValueError, KeyError, TypeError):
        return  # no report there, or one written before manifests: nothing to compare
    dropped = [
        env for path, env in old_solutions.items() if path not in _solutions(environments, out_dir)
    ]
    if dropped and not replace:
        raise InputError(
            f"holds a report on {len(old_solutions)} environment(s); this one would drop "
            f"{', '.join(dropped)}: choose another --out, or pass --replace",
            source=out_dir,
        )


def build_report(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    *,
    dpi: float = 110,
    match_white: bool = True,
    camera_to_xyz: np.ndarray | None = None,
    replace: bool = False,
    on_step: Callable[[], None] | None = None,
) -> Report:
    """Write ``out_dir/index.html`` and its SVGs for every solution in ``paths``, all or nothing.

    Parameters
    ----------
    paths
        ``solution.json`` files, environment folders, or ``ocio-vp solve`` output folders.
    out_dir
        The report folder; replaced as a whole if it exists.
    dpi
        Pixels per inch of the figures' displayed size (vectors: only their size on the page).
    match_white
        Scale each stage chart so its white's green matches the target's (paper, Section 4).
    camera_to_xyz
        (3, 3) camera RGB -> XYZ when the caller knows the camera
        (:func:`ocio_vp.report.data.camera_to_display`).
    """
    from ocio_vp.exports.templating import html_template

    out_dir = Path(out_dir).resolve()
    environments = environment_data(paths, match_white=match_white, camera_to_xyz=camera_to_xyz)
    _check_replaceable(out_dir, environments, replace=replace)
    report = Report(index=out_dir / "index.html", environments=environments)
    with staged_dir(out_dir.parent) as stage:
        folder = stage / "report"
        (folder / "img").mkdir(parents=True)

        def image(name: str) -> tuple[Path, str]:
            return folder / "img" / name, f"img/{name}"

        summary_images = {}
        for kind in ("lit", "displayed"):
            path, link = image(f"error_{kind}.svg")
            report.error_bars[kind] = plot_error_bars(environments, kind, path, dpi=dpi)
            summary_images[kind] = link
        sections = []
        for data in environments:
            images = {}
            path, images["charts"] = image(f"{data.key}-charts.svg")
            report.charts[data.key] = plot_comparison_charts(data, path, dpi=dpi)
            path, images["delta_e"] = image(f"{data.key}-delta_e.svg")
            report.delta_e[data.key] = plot_delta_e(data, path, dpi=dpi)
            curves = linearity_curves(data.solution.linearity)
            if curves:
                path, images["linearity"] = image(f"{data.key}-linearity.svg")
                report.linearity[data.key] = plot_linearity(curves, path, dpi=dpi)
            sections.append(_context(data, images))
            if on_step is not None:
                on_step()
        html = html_template(TEMPLATE).render(
            summary=_summary(environments),
            summary_images=summary_images,
            sections=sections,
            skin=skin_panel([e.solution for e in environments]),
            transforms=sorted({e.transform.description for e in environments}),
        )
        (folder / "index.html").write_text(html, encoding="utf-8")
        manifest = json.dumps(_manifest(environments, out_dir), indent=2) + "\n"
        (folder / MANIFEST).write_text(manifest, encoding="utf-8")
        publish_dir(folder, out_dir)
    _relocate(report, folder, out_dir)
    return report


def _relocate(report: Report, staged: Path, final: Path) -> None:
    """Point the plot records at the published folder instead of the staging one."""

    plots: tuple[dict[str, Any], ...] = (
        report.error_bars,
        report.charts,
        report.delta_e,
        report.linearity,
    )
    for records in plots:
        for key, plot in records.items():
            records[key] = dataclasses.replace(plot, path=final / plot.path.relative_to(staged))
