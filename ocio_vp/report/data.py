"""The numbers behind the report, from ``solution.json`` only: the charts of
``diagnostics.charts`` made display-referred through one camera-to-display matrix per camera
(:func:`camera_to_display`; docs/report.md, *Colours on screen*), the solve's own Fig. 11 errors
(camera RGB) and ΔE through the matching camera-to-XYZ matrix.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.calibration.diagnostics import summary_errors
from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.errors import InputError
from ocio_vp.formats.diagnostics import Diagnostics
from ocio_vp.formats.solution import Solution, load_solution
from ocio_vp.formats.solution_inputs import solution_folders
from ocio_vp.metrics import COLORCHECKER_NAMES, error_relative_to_white

__all__ = [
    "CHART_KEYS",
    "COLORCHECKER",
    "DISPLAY_WHITE",
    "STAGE_CHARTS",
    "DisplayTransform",
    "EnvironmentData",
    "camera_to_display",
    "colorchecker_srgb",
    "delta_e",
    "display_charts",
    "environment_data",
    "find_solutions",
    "fit_display_matrix",
    "infer_white_patch",
    "itp_defined",
    "patch_names",
]

#: The stage charts and the error keys of ``diagnostics`` that belong to them (paper Fig. 11).
STAGE_CHARTS = {
    "lit_baseline": "lit_chart_error_baseline",
    "lit_corrected": "lit_chart_error",
    "displayed_baseline": "displayed_chart_error_baseline",
    "displayed_corrected": "displayed_chart_error",
}
#: The chart arrays every solution carries in ``diagnostics.charts``.
CHART_KEYS = ("target", *STAGE_CHARTS)
COLORCHECKER = "ColorChecker24 - After November 2014"
#: Display-linear value of the target white patch's largest channel.
DISPLAY_WHITE = 0.9


@dataclass(frozen=True)
class DisplayTransform:
    """Camera RGB -> linear sRGB (``display = matrix @ camera``) and -> CIE XYZ (for ΔE), and
    where they come from."""

    matrix: np.ndarray
    camera_to_xyz: np.ndarray
    description: str
    residual: float | None = None


@dataclass(frozen=True)
class EnvironmentData:
    """One environment's numbers for the report (all camera RGB unless said otherwise).

    ``errors`` maps each stage chart to the solve's per-channel error relative to white;
    ``display`` maps every chart to sRGB-encoded values in [0, 1]; ``delta_e`` maps
    ``"CIE 2000"`` and ``"ITP"`` to per-patch ΔE of each stage chart against the target.
    """

    solution: Solution
    path: Path
    key: str
    white_patch: int
    charts: dict[str, np.ndarray]
    errors: dict[str, np.ndarray]
    display: dict[str, np.ndarray]
    delta_e: dict[str, dict[str, np.ndarray]]
    transform: DisplayTransform


def find_solutions(paths: Sequence[str | Path]) -> list[Path]:
    """Every ``solution.json`` named, in the vocabulary of
    :func:`ocio_vp.formats.solution_inputs.solution_folders` (environment folders, their
    ``solution.json``, ``solve`` output folders, several of these; generated folders skipped).

    Raises
    ------
    InputError
        When a path does not exist or holds no solution.
    """
    return [folder / "solution.json" for folder in solution_folders(paths).folders]


def _charts(solution: Solution, source: Path) -> dict[str, np.ndarray]:
    """The charts of ``diagnostics.charts``; the lit ones as the wall really lights them
    (``diagnostics.charts_clipped_drive``) where it clips a negative drive, like the figures."""
    charts = solution.diagnostics.charts
    if charts is None:
        raise InputError(
            "missing (re-run `ocio-vp solve`)", source=source, key="diagnostics.charts"
        )
    out = {name: getattr(charts, name) for name in CHART_KEYS}
    clipped = solution.diagnostics.charts_clipped_drive
    if clipped is not None:
        out["lit_baseline"], out["lit_corrected"] = clipped.lit_baseline, clipped.lit_corrected
    for name, array in out.items():  # the target first
        key = f"diagnostics.charts.{name}"
        if array.ndim != 2 or array.shape[1] != 3 or not np.all(np.isfinite(array)):
            raise InputError("expected a finite (n, 3) chart", source=source, key=key)
        if array.shape[0] != (n := len(out["target"])):
            raise InputError(f"expected {n} patches, got {array.shape[0]}", source=source, key=key)
    return out


def infer_white_patch(solution: Solution, charts: dict[str, np.ndarray]) -> int:
    """The chart's white patch index: ``diagnostics.white_patch`` when recorded, else the one
    that reproduces the solve's ``lit_chart_error_baseline``, else the ColorChecker's or the
    brightest target patch."""
    d = solution.diagnostics
    n = charts["target"].shape[0]
    if d.recorded("white_patch") and 0 <= d.white_patch < n:
        return d.white_patch
    stored = d.lit_chart_error_baseline
    if stored is not None and np.shape(stored) == (3,):
        for index in [DEFAULT_WHITE_PATCH, *range(n)] if n > DEFAULT_WHITE_PATCH else range(n):
            if np.min(charts["target"][index]) <= 0:
                continue
            redone = error_relative_to_white(charts["lit_baseline"], charts["target"], index)
            if np.allclose(redone, stored, rtol=1e-9, atol=1e-12):
                return index
    return DEFAULT_WHITE_PATCH if n == 24 else int(np.argmax(charts["target"].sum(axis=1)))


def colorchecker_srgb() -> np.ndarray:
    """Linear sRGB (D65, CAT02) of colour-science's ColorChecker24 reference, (24, 3)."""
    import colour

    checker = colour.CCS_COLOURCHECKERS[COLORCHECKER]
    XYZ = colour.xyY_to_XYZ(np.array(list(checker.data.values())))
    return colour.XYZ_to_RGB(XYZ, "sRGB", illuminant=checker.illuminant)


def patch_names(n: int) -> list[str]:
    """Axis labels: patches numbered from 1 (:func:`ocio_vp.metrics.patch_label`), with their
    ColorChecker 24 names (densities dropped) on a 24-patch chart."""
    if n != len(COLORCHECKER_NAMES):
        return [str(j + 1) for j in range(n)]
    return [f"{j + 1} {name.split(' (')[0]}" for j, name in enumerate(COLORCHECKER_NAMES)]


def fit_display_matrix(target: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares 3x3 ``A`` with ``A @ target_j ~ colorchecker_srgb()_j`` over 24 patches,
    and its relative residual ``|A p - s| / |s|`` (Frobenius)."""
    reference = colorchecker_srgb()
    solution, *_ = np.linalg.lstsq(np.asarray(target, dtype=np.float64), reference, rcond=None)
    A = solution.T
    residual = np.linalg.norm(target @ A.T - reference) / np.linalg.norm(reference)
    return A, float(residual)


def camera_to_display(
    solutions: Sequence[Solution],
    targets: Sequence[np.ndarray],
    *,
    camera_to_xyz: np.ndarray | None = None,
) -> DisplayTransform:
    """One camera-to-display (and camera-to-XYZ) matrix for solutions from the same camera.

    In order of preference: ``camera_to_xyz`` (a caller that knows the camera), then XYZ ->
    linear sRGB; the solutions' ``camera_colorspace`` (colour-science, CAT02); a least-squares
    fit of the best-fitting target chart to the ColorChecker24 in linear sRGB (the most
    broadband light, so a tungsten environment still looks warm); identity for another chart.
    """
    import colour

    srgb = colour.RGB_COLOURSPACES["sRGB"]
    if camera_to_xyz is not None:
        camera_to_xyz = np.asarray(camera_to_xyz, dtype=np.float64)
        return DisplayTransform(
            srgb.matrix_XYZ_to_RGB @ camera_to_xyz,
            camera_to_xyz,
            "the camera's own camera-to-XYZ matrix (fitted on its spectral sensitivities), "
            "then XYZ to linear sRGB",
        )
    named = {s.camera_colorspace for s in solutions if s.camera_colorspace}
    if len(named) == 1:
        name = named.pop()
        space = colour.RGB_COLOURSPACES[name]
        return DisplayTransform(
            colour.matrix_RGB_to_RGB(space, srgb),
            np.asarray(space.matrix_RGB_to_XYZ, dtype=np.float64),
            f"colour-science matrix from {name} to linear sRGB (CAT02 white adaptation)",
        )
    best = None
    for solution, target in zip(solutions, targets, strict=True):
        if target.shape[0] != 24:
            continue
        A, residual = fit_display_matrix(target)
        if (
            np.isfinite(residual)
            and np.linalg.cond(A) < 1e6
            and (best is None or residual < best[1])
        ):
            best = (A, residual, solution.environment)
    if best is None:
        return DisplayTransform(
            np.eye(3),
            np.asarray(srgb.matrix_RGB_to_XYZ, dtype=np.float64),
            "identity: the chart is not a ColorChecker 24, camera RGB shown as sRGB",
        )
    A, residual, environment = best
    return DisplayTransform(
        A,
        srgb.matrix_RGB_to_XYZ @ A,
        f"least-squares fit of {environment!r}'s target chart to the {COLORCHECKER} reference "
        f"values in linear sRGB (colour-science), relative residual {residual:.1%}",
        residual,
    )


def display_charts(
    charts: dict[str, np.ndarray], matrix: np.ndarray, white_patch: int, *, match_white: bool = True
) -> dict[str, np.ndarray]:
    """sRGB-encoded display values of every chart, in [0, 1], the target white's largest
    channel at :data:`DISPLAY_WHITE`; with ``match_white`` each stage chart's white green is
    first scaled to the target's (the paper's comparison charts, Section 4)."""
    import colour

    target = charts["target"]
    white = matrix @ target[white_patch]
    exposure = DISPLAY_WHITE / max(float(np.max(white)), 1e-12)
    linear = []
    for name, chart in charts.items():
        scale = exposure
        if match_white and name != "target" and chart[white_patch, 1] > 0:
            scale *= target[white_patch, 1] / chart[white_patch, 1]
        linear.append(np.clip(scale * chart @ matrix.T, 0.0, 1.0))
    encoded = np.asarray(colour.cctf_encoding(np.concatenate(linear), "sRGB"), dtype=np.float64)
    ends = np.cumsum([len(chart) for chart in linear])[:-1]
    return dict(zip(charts, np.split(encoded, ends), strict=True))


def delta_e(
    charts: dict[str, np.ndarray], camera_to_xyz: np.ndarray, white_patch: int
) -> dict[str, dict[str, np.ndarray]]:
    """Per-patch CIE ΔE2000 and ΔE ITP of every stage chart against the target, by
    :func:`ocio_vp.metrics.chart_errors` through ``camera_to_xyz`` (stage charts are not
    re-exposed: an exposure error is a real error here)."""
    from ocio_vp.metrics import chart_errors

    if not (np.asarray(camera_to_xyz) @ charts["target"][white_patch])[1] > 0:
        raise InputError("the target white patch has no luminance; ΔE is undefined")
    # one call for the four stage charts (the normalisation uses the first copy's white patch)
    n, stages = len(charts["target"]), list(STAGE_CHARTS)
    errors = chart_errors(
        np.concatenate([charts[chart] for chart in stages]),
        np.tile(charts["target"], (len(stages), 1)),
        camera_to_xyz=camera_to_xyz,
        white_patch=white_patch,
    )
    defined = itp_defined(
        np.concatenate([charts["target"], *(charts[c] for c in stages)]), camera_to_xyz
    ).reshape(len(stages) + 1, n)
    de2000 = np.asarray(errors.delta_E_2000, dtype=np.float64).reshape(len(stages), n)
    itp = np.asarray(errors.delta_E_ITP, dtype=np.float64).reshape(len(stages), n)
    out: dict[str, dict[str, np.ndarray]] = {"CIE 2000": {}, "ITP": {}}
    for k, chart in enumerate(stages):
        out["CIE 2000"][chart] = de2000[k]
        out["ITP"][chart] = np.where(defined[0] & defined[k + 1], itp[k], np.nan)
    return out


def itp_defined(chart: np.ndarray, camera_to_xyz: np.ndarray) -> np.ndarray:
    """(n,) bool: where ΔE ITP means something for these camera RGB colours: ICtCp's PQ curve
    is defined for non-negative BT.2100 LMS only (beyond its pole ΔE ITP takes arbitrary
    values), so a colour with a negative LMS component is undefined, not a number."""
    import colour
    from colour.models.rgb.ictcp import MATRIX_ICTCP_RGB_TO_LMS

    xyz = np.asarray(chart, dtype=np.float64) @ np.asarray(camera_to_xyz, dtype=np.float64).T
    rgb = colour.XYZ_to_RGB(
        xyz, colour.RGB_COLOURSPACES["ITU-R BT.2020"], chromatic_adaptation_transform="CAT02"
    )
    lms = rgb @ MATRIX_ICTCP_RGB_TO_LMS.T
    scale = max(float(np.max(np.abs(lms))), 1e-300)
    return np.all(lms >= -1e-9 * scale, axis=-1)


def _errors(
    diagnostics: Diagnostics, charts: dict[str, np.ndarray], white_patch: int
) -> dict[str, np.ndarray]:
    """The solve's Fig. 11 errors (:func:`ocio_vp.calibration.diagnostics.summary_errors`),
    recomputed from the charts where an old file lacks them."""
    figures = summary_errors(diagnostics)
    stored_by_chart = {
        "lit_baseline": figures.lit_baseline,
        "lit_corrected": figures.lit,
        "displayed_baseline": figures.shown_baseline,
        "displayed_corrected": figures.shown,
    }
    out = {}
    for chart, stored in stored_by_chart.items():
        if stored is not None and np.shape(stored) == (3,):
            out[chart] = stored
        else:
            out[chart] = error_relative_to_white(charts[chart], charts["target"], white_patch)
    return out


def environment_data(
    paths: Sequence[str | Path],
    *,
    match_white: bool = True,
    camera_to_xyz: np.ndarray | None = None,
) -> list[EnvironmentData]:
    """Load every solution and compute what the report shows; one display matrix per stage
    (``camera_to_xyz``, when the caller knows the camera, for every solution)."""
    loaded = []
    for path in find_solutions(paths):
        solution = load_solution(path)
        camera = (solution.stage, solution.measurements_sha256, solution.camera_colorspace)
        loaded.append((path, solution, _charts(solution, path), camera))
    groups: dict[tuple, list] = {}
    for _, solution, charts, camera in loaded:
        groups.setdefault(camera, []).append((solution, charts["target"]))
    transforms = {
        camera: camera_to_display(
            [s for s, _ in items], [t for _, t in items], camera_to_xyz=camera_to_xyz
        )
        for camera, items in groups.items()
    }
    out = []
    for index, (path, solution, charts, camera) in enumerate(loaded):
        transform = transforms[camera]
        white = infer_white_patch(solution, charts)
        out.append(
            EnvironmentData(
                solution=solution,
                path=path,
                key=f"{index + 1:02d}-{solution.environment}",
                white_patch=white,
                charts=charts,
                errors=_errors(solution.diagnostics, charts, white),
                display=display_charts(charts, transform.matrix, white, match_white=match_white),
                delta_e=delta_e(charts, transform.camera_to_xyz, white),
                transform=transform,
            )
        )
    return out
