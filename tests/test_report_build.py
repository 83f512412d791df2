"""Where ``ocio-vp report`` writes, re-runs on globs, never dropping a larger report; ΔE ITP
where it is undefined; a root-polynomial Q named with its degree, terms and coefficients."""

from __future__ import annotations

import html
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_environment
from ocio_vp.report.build import build_report, default_report_dir
from ocio_vp.report.data import delta_e, environment_data, itp_defined

SAMPLE = Path(__file__).resolve().parent.parent / "sample_configs" / "paper_stage"
ENVIRONMENTS = ("direct_sun", "sodium_vapour", "incandescent")
DPI = "20"  # tiny PNGs: these tests are about folders, not pictures


@pytest.fixture
def calib(tmp_path) -> Path:
    root = tmp_path / "calib"
    for name in ENVIRONMENTS:
        shutil.copytree(SAMPLE / name, root / name)
    return root


def _report(*args: str | Path) -> int:
    return main(["report", *map(str, args), "--dpi", DPI])


def _shown(folder: Path) -> list[str]:
    return json.loads((folder / "report.json").read_text())["environments"]


def test_default_report_dir(calib, tmp_path):
    assert default_report_dir([calib]) == calib.resolve() / "report"
    assert default_report_dir(sorted(calib.iterdir())) == calib.resolve() / "report"
    assert default_report_dir([calib / "direct_sun"]) == calib.resolve() / "direct_sun" / "report"
    some = default_report_dir([calib / "sodium_vapour", calib / "direct_sun"])
    assert some == calib.resolve() / "report-sodium_vapour+direct_sun"
    other = tmp_path / "other"
    shutil.copytree(SAMPLE / "direct_sun", other / "direct_sun")
    with pytest.raises(InputError, match="give --out"):
        default_report_dir([calib / "direct_sun", other / "direct_sun"])


def test_reruns_and_never_drops_a_larger_report(tmp_path, capsys):
    calib = tmp_path / "calib"
    for name in ENVIRONMENTS[:2]:
        shutil.copytree(SAMPLE / name, calib / name)
    assert _report(*sorted(calib.iterdir())) == 0
    assert _shown(calib / "report") == sorted(ENVIRONMENTS[:2])
    index = (calib / "report" / "index.html").read_bytes()
    capsys.readouterr()
    assert _report(calib / "direct_sun", "--out", calib / "report") == 2
    err = capsys.readouterr().err
    assert "would drop sodium_vapour" in err and "--replace" in err
    assert (calib / "report" / "index.html").read_bytes() == index
    # (A re-run of the same glob skips calib/report: tests/test_formats_solution_inputs.py.)


def test_itp_domain():
    """ICtCp's PQ needs non-negative LMS: a colour with negative light is flagged."""
    xyz_to_xyz = np.eye(3)
    # grey, black, a red, and pure Z (no luminance: no light has it; its L cone value is < 0)
    chart = np.array([[0.2, 0.2, 0.2], [0.0, 0.0, 0.0], [0.5, 0.1, 0.05], [0.0, 0.0, 0.5]])
    defined = itp_defined(chart, xyz_to_xyz)
    assert defined.tolist() == [True, True, True, False]


def test_sodium_itp_is_undefined_not_huge():
    """Sodium's eq. 3 lit chart with the drive unclipped (negative blue light; Q is fitted to
    the clipped one, which the report draws), and through the rank-1 Q: negative light, so ΔE
    ITP is NaN exactly there, bounded everywhere else."""
    from ocio_vp.calibration.equations import predict_lit_chart
    from ocio_vp.formats.measurements import load_measurements

    (data,) = environment_data([SAMPLE / "sodium_vapour"])
    solution = data.solution
    measurements = load_measurements(SAMPLE.parent / "paper_stage.yaml")
    lit = predict_lit_chart(measurements.SRL, solution.beta, solution.M, solution.w_avg)
    assert np.min(np.asarray(solution.M) @ np.asarray(solution.w_avg)) < 0  # a negative drive
    charts = solution.diagnostics.charts
    unclipped = {k: np.asarray(v) for k, v in charts.to_dict().items()}
    unclipped |= {"lit_baseline": lit, "lit_corrected": lit @ np.asarray(solution.Q).T}
    itp = delta_e(unclipped, data.transform.camera_to_xyz, data.white_patch)["ITP"]
    assert sum(int(np.isnan(v).sum()) for v in itp.values()) > 0
    target_ok = itp_defined(unclipped["target"], data.transform.camera_to_xyz)
    for chart, values in itp.items():
        assert np.nanmax(values) < 1000, chart  # ICtCp distances are bounded for real light
        ok = target_ok & itp_defined(unclipped[chart], data.transform.camera_to_xyz)
        assert np.array_equal(np.isnan(values), ~ok)
    # What the report shows (the light the wall emits) is physical: every patch defined.
    assert not any(np.isnan(v).any() for v in data.delta_e["ITP"].values())


def test_sodium_draws_the_charts_its_figures_measure():
    """Where the wall clips a negative drive, the lit charts drawn are the clipped ones, so the
    Fig. 11 formula on the drawn chart gives the figure the page prints."""
    from ocio_vp.metrics import error_relative_to_white

    (data,) = environment_data([SAMPLE / "sodium_vapour"])
    clipped = data.solution.diagnostics.charts_clipped_drive
    for chart in ("lit_baseline", "lit_corrected"):
        np.testing.assert_array_equal(data.charts[chart], getattr(clipped, chart))
        drawn = error_relative_to_white(data.charts[chart], data.charts["target"], 18)
        np.testing.assert_allclose(drawn, data.errors[chart], rtol=1e-9)


def test_report_shows_the_root_polynomial_model(tmp_path):
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("indoor_daylight",))
    write_solutions([solve_environment(m, m.environments[0], method="root-polynomial")], tmp_path)
    report = build_report([tmp_path], tmp_path / "report", dpi=20)
    text = html.unescape(report.index.read_text(encoding="utf-8"))
    model = json.loads((tmp_path / "indoor_daylight" / "solution.json").read_text())[
        "post_correction"
    ]["parameters"]
    assert model["terms"] == ["r", "g", "b", "√(rg)", "√(gb)", "√(rb)"]
    assert "root-polynomial degree 2, inside the chart's domain" in text
    assert "Q(x) = C (r, g, b, √(rg), √(gb), √(rb))" in text
    assert "Q (root-polynomial)" in text and "3x3 fallback of Q" in text
    for value in np.ravel(model["coefficients"]):
        assert f"{value:+.5f}" in text


def test_report_prints_no_non_finite_number_and_a_singular_q_as_the_terminal(calib):
    # Sodium's rank-1 Q: numpy calls it singular; the report said "cond = inf" (and would print
    # the digits of rounding noise for a nearly singular one); the terminal's "> 1e+12" now.
    q = json.loads((calib / "sodium_vapour" / "solution.json").read_text())["Q"]
    assert np.linalg.cond(q) > 1e12
    assert _report(calib) == 0
    page = html.unescape((calib / "report" / "index.html").read_text())
    assert 'class="num">> 1e+12</td>' in page and "cond = > 1e+12" in page
    assert not re.findall(r"(?<![\w.])[-+]?(?:nan|inf|infinity)(?![\w(])", page, re.IGNORECASE)


def test_report_skin_panel_shows_solution_json_figures(tmp_path):
    """The skin panel reads each band's expectation and least squares' from solution.json."""
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("incandescent",))
    write_solutions([solve_environment(m, m.environments[0], priority="skin")], tmp_path)
    report = build_report([tmp_path], tmp_path / "report", dpi=20)
    text = html.unescape(report.index.read_text(encoding="utf-8"))
    skin = json.loads((tmp_path / "incandescent" / "solution.json").read_text())["diagnostics"][
        "skin"
    ]
    start = text.index('<h2 id="skin">')
    panel = text[start : text.index("</table>", start)]
    assert "<td>incandescent</td><td>skin</td>" in panel
    for band in skin["bands"]:
        assert f"<th>{band['band']}</th>" in panel
        assert f"{band['expected']:.2f} ({band['least_squares']:.2f})" in panel
    ratio = skin["expected"] / skin["least_squares"]
    assert f"{ratio:.2f}x" in panel and ratio < 1
    assert f"the default ({skin['default']['model']}) expects skin" in text
