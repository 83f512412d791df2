"""Tests for the HTML report: it renders, its SVG figures parse, and every plotted number is the
solution's own number (the plot records here; read back from the SVG files in
tests/test_report_plots.py)."""

from __future__ import annotations

import copy
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.formats.linearity import assumed_linearity
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.metrics import error_relative_to_white
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements
from ocio_vp.report.build import build_report, linearity_curves
from ocio_vp.report.data import (
    DISPLAY_WHITE,
    STAGE_CHARTS,
    colorchecker_srgb,
    delta_e,
    fit_display_matrix,
)

TOL = 1e-9
DPI = 30  # the figures' displayed size: figsize (inches) x DPI pixels
SAMPLE = Path(__file__).resolve().parent.parent / "sample_configs"


def _solve(tmp: Path, document: dict) -> Path:
    measurements = measurements_from_dict(document, source=str(tmp / "m.json"))
    out = tmp / "solved"
    write_solutions(solve_measurements(measurements), out)
    return out


@pytest.fixture(scope="module")
def solved(tmp_path_factory) -> Path:
    return _solve(tmp_path_factory.mktemp("report"), make_measurements_dict(environments=3))


@pytest.fixture(scope="module")
def report(solved):
    return build_report([solved], solved / "report", dpi=DPI)


def _json(solved: Path, environment: str) -> dict:
    return json.loads((solved / environment / "solution.json").read_text())


def _srgb_decode(v: np.ndarray) -> np.ndarray:
    # IEC 61966-2-1 piecewise sRGB decoding, written out (independent of colour-science).
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


class TestRender:
    def test_every_image_exists_and_parses(self, report):
        html = report.index.read_text()
        sources = re.findall(r'<img[^>]*\bsrc="([^"]+)"', html)
        # 2 Fig. 11 panels + (charts, ΔE) per environment; no linearity in this data.
        assert len(sources) == 2 + 2 * 3
        assert all(re.fullmatch(r"img/[\w.-]+\.svg", source) for source in sources)
        sizes = {}
        for source in sources:
            root = ET.parse(report.index.parent / source).getroot()
            assert root.tag == "{http://www.w3.org/2000/svg}svg"
            sizes[source] = (float(root.get("width")), float(root.get("height")))
            # The viewBox is the figure in points (72 per inch): the same aspect ratio.
            _, _, w, h = map(float, root.get("viewBox").split())
            assert w / h == pytest.approx(sizes[source][0] / sizes[source][1], rel=1e-3)
        charts = next(iter(report.charts.values())).path.relative_to(report.index.parent)
        assert sizes[charts.as_posix()] == pytest.approx((10.0 * DPI, 7.4 * DPI), abs=0.01)
        bars = report.error_bars["lit"].path.relative_to(report.index.parent)
        assert sizes[bars.as_posix()][1] == pytest.approx(4.2 * DPI, abs=0.01)
        # Element counts: 4 panels x 24 squares and circles; 3 environments x 6 bars per
        # Fig. 11 panel; 4 panels x 2 series x 24 bars per ΔE figure.
        svg = "{http://www.w3.org/2000/svg}"
        charts_root = ET.parse(report.index.parent / charts).getroot()
        assert len([e for e in charts_root.iter(f"{svg}rect") if e.get("class") == "square"]) == 96
        assert (
            len([e for e in charts_root.iter(f"{svg}circle") if e.get("class") == "circle"]) == 96
        )
        bars_root = ET.parse(report.error_bars["lit"].path).getroot()
        assert len([e for e in bars_root.iter(f"{svg}rect") if e.get("class") == "bar"]) == 18
        delta_root = ET.parse(next(iter(report.delta_e.values())).path).getroot()
        assert len([e for e in delta_root.iter(f"{svg}rect") if e.get("class") == "bar"]) == 192

    def test_each_figure_is_the_one_drawn_for_its_environment_alone(self, report, tmp_path):
        # Drawn in one loop over the environments, each SVG must be byte for byte the one a
        # call for that environment alone writes (nothing carried over between figures).
        from ocio_vp.report.plots import plot_comparison_charts, plot_delta_e

        for data in report.environments:
            for plot, drawn in (
                (plot_comparison_charts, report.charts[data.key]),
                (plot_delta_e, report.delta_e[data.key]),
            ):
                fresh = plot(data, tmp_path / "fresh.svg", dpi=DPI).path
                assert fresh.read_bytes() == drawn.path.read_bytes()

    def test_no_external_urls(self, report):
        html = report.index.read_text()
        assert not re.search(r"https?:", html, re.IGNORECASE)
        assert "//" not in re.sub(r"<!--.*?-->", "", html)  # no protocol-relative //host
        assert "@import" not in html and "url(" not in html
        for link in re.findall(r'(?:src|href)="([^"]*)"', html):
            assert link.startswith("#") or (report.index.parent / link).is_file(), link

    def test_svgs_load_nothing_from_outside(self, report):
        # An SVG can reference files and URLs (href, url(...)): ours only name their own
        # patterns and clip paths; the one web address is the SVG namespace's name.
        for plot in [
            *report.charts.values(),
            *report.error_bars.values(),
            *report.delta_e.values(),
        ]:
            text = plot.path.read_text()
            assert text.count("http") == 1 and 'xmlns="http://www.w3.org/2000/svg"' in text
            assert all(u.startswith("#") for u in re.findall(r"url\(([^)]*)\)", text))
            assert "href" not in text and "<script" not in text and "<image" not in text

    def test_every_environment_has_a_section(self, report, solved):
        html = report.index.read_text()
        for environment in ("env_0", "env_1", "env_2"):
            assert f">{environment}</h2>" in html
        assert "cond = " in html and "Q method" in html

    def test_nothing_left_behind(self, report, solved):
        assert not [p for p in solved.iterdir() if p.name.startswith(".")]
        assert sorted(p.name for p in solved.iterdir()) == ["env_0", "env_1", "env_2", "report"]


class TestPlottedNumbers:
    def test_error_bars_are_the_solutions_errors(self, report, solved):
        for kind, (base_key, ours_key) in {
            "lit": ("lit_chart_error_baseline", "lit_chart_error"),
            "displayed": ("displayed_chart_error_baseline", "displayed_chart_error"),
        }.items():
            plot = report.error_bars[kind]
            assert plot.environments == ["env_0", "env_1", "env_2"]
            for i, environment in enumerate(plot.environments):
                d = _json(solved, environment)["diagnostics"]
                np.testing.assert_allclose(plot.baseline[i], d[base_key], rtol=TOL)
                np.testing.assert_allclose(plot.ours[i], d[ours_key], rtol=TOL)
                # And those are the paper's Fig. 11 metric of the charts in the same file.
                charts = {k: np.array(v) for k, v in d["charts"].items()}
                closed_form = np.mean(
                    np.abs(charts[f"{kind}_baseline"] - charts["target"]) / charts["target"][18],
                    axis=0,
                )
                np.testing.assert_allclose(plot.baseline[i], closed_form, rtol=1e-9)

    def test_chart_squares_and_circles_are_the_solution_charts(self, report, solved):
        for data in report.environments:
            plot = report.charts[data.key]
            charts = {
                k: np.array(v)
                for k, v in _json(solved, data.solution.environment)["diagnostics"][
                    "charts"
                ].items()
            }
            A = data.transform.matrix
            target = charts["target"]
            exposure = DISPLAY_WHITE / np.max(A @ target[18])
            for chart in STAGE_CHARTS:
                squares, circles = plot.squares[chart], plot.circles[chart]
                assert squares.shape == circles.shape == (24, 3)
                # Undo the documented display path (sRGB decode, exposure, matrix) on patches
                # that were not clipped: we get back the camera RGB of solution.json.
                for drawn, camera, scale in (
                    (squares, target, exposure),
                    (circles, charts[chart], exposure * target[18, 1] / charts[chart][18, 1]),
                ):
                    linear = _srgb_decode(drawn)
                    inside = np.all((linear > 1e-6) & (linear < 1 - 1e-6), axis=1)
                    assert inside.sum() >= 12
                    back = linear[inside] @ np.linalg.inv(A).T / scale
                    np.testing.assert_allclose(back, camera[inside], rtol=1e-6, atol=1e-9)
            # The target white's brightest channel is DISPLAY_WHITE: sRGB(0.9) = 0.95468.
            assert np.max(plot.squares["lit_baseline"][18]) == pytest.approx(
                1.055 * 0.9 ** (1 / 2.4) - 0.055, abs=1e-12
            )

    def test_delta_e_bars_are_the_delta_e(self, report):
        for data in report.environments:
            plot = report.delta_e[data.key]
            for metric in ("CIE 2000", "ITP"):
                for chart in STAGE_CHARTS:
                    np.testing.assert_allclose(
                        plot.values[metric][chart], data.delta_e[metric][chart], rtol=TOL
                    )
                    assert np.all(np.isfinite(plot.values[metric][chart]))


class TestDisplayMatrix:
    def test_fit_recovers_a_known_matrix(self):
        # Closed form: camera RGB made from the reference by an invertible B -> the fit is B^-1.
        B = np.array([[0.8, 0.15, 0.05], [0.1, 0.85, 0.05], [0.02, 0.1, 0.88]])
        camera = colorchecker_srgb() @ B.T * 0.37
        A, residual = fit_display_matrix(camera)
        np.testing.assert_allclose(A, np.linalg.inv(B) / 0.37, rtol=1e-9)
        assert residual < 1e-12

    def test_named_camera_colourspace(self, tmp_path):
        import colour

        document = make_measurements_dict(environments=1)
        document["stage"]["camera_colorspace"] = "ARRI Wide Gamut 4"
        out = _solve(tmp_path, document)
        result = build_report([out / "env_0"], tmp_path / "r", dpi=DPI)
        A = result.environments[0].transform.matrix
        # AWG4 and sRGB are both D65: the matrix is XYZ->sRGB times AWG4->XYZ (colour's
        # published primaries), and camera white (1,1,1) stays display white.
        awg4 = colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"]
        srgb = colour.RGB_COLOURSPACES["sRGB"]
        np.testing.assert_allclose(
            A, srgb.matrix_XYZ_to_RGB @ awg4.matrix_RGB_to_XYZ, rtol=1e-6, atol=1e-9
        )
        # (to the 4 decimals sRGB's published matrix is rounded to)
        np.testing.assert_allclose(A @ np.ones(3), np.ones(3), atol=5e-4)
        assert "ARRI Wide Gamut 4" in result.index.read_text()


class TestDeltaE:
    def test_identical_charts_give_zero(self):
        rng = np.random.default_rng(3)
        target = rng.uniform(0.05, 0.8, size=(24, 3))
        charts = {"target": target, **{k: target.copy() for k in STAGE_CHARTS}}
        result = delta_e(charts, np.eye(3), 18)
        for metric in ("CIE 2000", "ITP"):
            for chart in STAGE_CHARTS:
                np.testing.assert_allclose(result[metric][chart], 0.0, atol=1e-9)

    def test_half_exposed_white_matches_cie2000_closed_form(self):
        # The stage's white patch at half the target's: a pure lightness difference.
        # CIE 2000 (Sharma et al. 2005): dE = dL / S_L, S_L = 1 + 0.015 (L-50)^2 / sqrt(20 + (L-50)^2).
        target = np.full((24, 3), 0.2)
        target[18] = [0.7, 0.6, 0.5]
        stage = target.copy()
        stage[18] *= 0.5
        charts = {"target": target, **{k: stage for k in STAGE_CHARTS}}
        result = delta_e(charts, np.eye(3), 18)["CIE 2000"]["lit_baseline"]
        L1 = 100.0
        L2 = 116 * 0.5 ** (1 / 3) - 16
        mean = (L1 + L2) / 2
        S_L = 1 + 0.015 * (mean - 50) ** 2 / np.sqrt(20 + (mean - 50) ** 2)
        assert result[18] == pytest.approx((L1 - L2) / S_L, rel=1e-9)
        np.testing.assert_allclose(np.delete(result, 18), 0.0, atol=1e-9)


class TestLinearity:
    def test_measured_ramps_are_plotted_before_and_after(self, tmp_path):
        # A wall whose red channel follows drive^1.15 (the paper saw a non-linear red), green
        # and blue linear: ramps made in closed form from the primaries' columns of [SL].
        document = make_measurements_dict(environments=1)
        drive = np.linspace(0.0, 1.0, 9)
        power = {"red": 1.15, "green": 1.0, "blue": 1.0}
        document["ramps"] = {
            c: {
                "drive": drive.tolist(),
                "camera": np.outer(drive ** power[c], document["primaries"][c]).tolist(),
            }
            for c in ("red", "green", "blue")
        }
        out = _solve(tmp_path, document)
        stored = _json(out, "env_0")["linearity"]["channels"]
        result = build_report([out], tmp_path / "r", dpi=DPI)
        plot = next(iter(result.linearity.values()))
        assert sorted(plot.curves) == ["blue before", "green before", "red after", "red before"]
        for channel in ("red", "green", "blue"):
            x, y = plot.curves[f"{channel} before"]
            np.testing.assert_allclose(x, stored[channel]["drive"], rtol=TOL)
            np.testing.assert_allclose(y, stored[channel]["response"], rtol=TOL)
        np.testing.assert_allclose(plot.curves["red before"][1], drive**1.15, atol=1e-12)
        # Through the LUT the red response is linear: r(r^-1(x)) = x (PCHIP is exactly
        # invertible; bisection to float64).
        x, y = plot.curves["red after"]
        np.testing.assert_allclose(y, x, atol=1e-9)
        assert plot.path.is_file()
        assert "Panel linearity" in result.index.read_text()

    def test_no_linearity_no_curves(self):
        assert linearity_curves(None) == {}
        assert linearity_curves(assumed_linearity()) == {}


class TestCommand:
    def test_default_folder_and_exit_code(self, solved, tmp_path, capsys):
        import shutil

        copy_dir = tmp_path / "solved"
        shutil.copytree(solved, copy_dir, ignore=shutil.ignore_patterns("report"))
        assert main(["report", str(copy_dir), "--dpi", "20"]) == 0
        assert (copy_dir / "report" / "index.html").is_file()
        assert "index.html" in capsys.readouterr().out

    def test_missing_folder_is_an_input_error(self, tmp_path, capsys):
        assert main(["report", str(tmp_path / "nope")]) == 2
        err = capsys.readouterr().err
        assert "nope" in err and "error" in err and "Traceback" not in err

    def test_corrupt_solution_leaves_nothing(self, solved, tmp_path, capsys):
        data = _json(solved, "env_0")
        broken = copy.deepcopy(data)
        broken["diagnostics"]["charts"]["lit_corrected"] = [[1.0, 2.0]] * 24
        folder = tmp_path / "env_0"
        folder.mkdir()
        (folder / "solution.json").write_text(json.dumps(broken))
        assert main(["report", str(folder), "--out", str(tmp_path / "r")]) == 2
        assert "diagnostics.charts.lit_corrected" in capsys.readouterr().err
        assert not (tmp_path / "r").exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == ["env_0"]

    def test_refuses_to_replace_what_is_not_a_report(self, solved, tmp_path, capsys):
        # --out pointing at the solve output (or any other folder) would be replaced whole.
        assert main(["report", str(solved / "env_0"), "--out", str(solved)]) == 2
        assert "would replace the solutions" in capsys.readouterr().err
        other = tmp_path / "photos"
        other.mkdir()
        (other / "keep.txt").write_text("mine")
        assert main(["report", str(solved / "env_0"), "--out", str(other)]) == 2
        assert "not an ocio-vp report" in capsys.readouterr().err
        assert (other / "keep.txt").read_text() == "mine"
        assert sorted(p.name for p in solved.iterdir()) == ["env_0", "env_1", "env_2", "report"]


def test_other_chart_without_black_level(tmp_path):
    # 30 patches (not a ColorChecker 24): identity display matrix; no black level measured.
    document = make_measurements_dict(n=30, environments=1, black_level=False)
    out = _solve(tmp_path, document)
    result = build_report([out], tmp_path / "r", dpi=DPI)
    data = result.environments[0]
    assert data.white_patch == 18
    np.testing.assert_array_equal(data.transform.matrix, np.eye(3))
    plot = result.charts[data.key]
    assert plot.squares["lit_baseline"].shape == (30, 3)
    assert "ours (N, Q)\n" in plot.titles["displayed_corrected"]
    assert "no black-level measurement" in result.index.read_text()
    assert "identity" in result.index.read_text()


def test_panel_geometry_from_the_measurements_file(tmp_path):
    from ocio_vp.formats.measurements import load_measurements

    document = make_measurements_dict(environments=1)
    document["stage"]["calibration_panel"] = {"width": 1.2, "height": 0.5, "distance": 1.5}
    out = tmp_path / "solved"
    out.mkdir()
    (out / "m.json").write_text(json.dumps(document))
    write_solutions(solve_measurements(load_measurements(out / "m.json")), out)
    html = build_report([out], tmp_path / "r", dpi=DPI).index.read_text()
    assert "1.2 m x 0.5 m at 1.5 m (from m.json)" in html
    # A different file of the same name (hash differs from solution.json's) is not trusted.
    (out / "m.json").write_text(json.dumps(document) + "\n")
    html = build_report([out], tmp_path / "r", dpi=DPI).index.read_text()
    assert "1.2 m" not in html and "not recorded in solution.json" in html


def test_white_patch_other_than_18(tmp_path):
    document = make_measurements_dict(environments=1)
    document["stage"]["white_patch"] = 5
    target = np.array(document["environments"][0]["target_chart"])
    target[5] = [0.85, 0.8, 0.75]
    document["environments"][0]["target_chart"] = target.tolist()
    out = _solve(tmp_path, document)
    result = build_report([out], tmp_path / "r", dpi=DPI)
    data = result.environments[0]
    assert data.white_patch == 5
    stored = _json(out, "env_0")["diagnostics"]["lit_chart_error_baseline"]
    np.testing.assert_allclose(
        error_relative_to_white(data.charts["lit_baseline"], data.charts["target"], 5),
        stored,
        rtol=1e-12,
    )


@pytest.mark.skipif(
    not (SAMPLE / "paper_stage").is_dir(), reason="sample_configs/paper_stage not generated"
)
def test_sample_configs_render(tmp_path):
    # The committed sample solutions (issue 3's simulated paper stage, seven environments).
    result = build_report([SAMPLE / "paper_stage"], tmp_path / "r", dpi=DPI)
    assert len(result.environments) == 7
    for i, name in enumerate(result.error_bars["lit"].environments):
        d = json.loads((SAMPLE / "paper_stage" / name / "solution.json").read_text())
        diagnostics = d["diagnostics"]
        # The figures solve and demo print: for sodium, the lit chart with the clipped drive.
        lit = diagnostics["lit_chart_error_clipped_drive"] or diagnostics["lit_chart_error"]
        np.testing.assert_allclose(result.error_bars["lit"].ours[i], lit, rtol=TOL)
        np.testing.assert_allclose(
            result.error_bars["displayed"].baseline[i],
            diagnostics["displayed_chart_error_baseline"],
            rtol=TOL,
        )
    html = result.index.read_text()
    assert "sodium_vapour" in html and "not solved" in html  # the paper: no N for sodium
    for data in result.environments:
        title = result.charts[data.key].titles["displayed_corrected"]
        if data.solution.environment == "sodium_vapour":
            assert "N not solved" in title and "Q" not in title.split(":")[1]
        else:
            assert "(N, black level, Q)" in title


def test_camera_to_xyz_from_the_caller(tmp_path, solved):
    import colour

    # A caller that knows the camera (the demo) passes its camera-to-XYZ matrix; the display
    # matrix is then XYZ -> linear sRGB after it (colour-science's sRGB matrix).
    camera_to_xyz = np.array([[0.5, 0.3, 0.15], [0.25, 0.7, 0.05], [0.02, 0.1, 0.95]])
    result = build_report([solved / "env_0"], tmp_path / "r", dpi=DPI, camera_to_xyz=camera_to_xyz)
    transform = result.environments[0].transform
    np.testing.assert_allclose(transform.camera_to_xyz, camera_to_xyz)
    np.testing.assert_allclose(
        transform.matrix,
        colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB @ camera_to_xyz,
        rtol=1e-12,
    )
