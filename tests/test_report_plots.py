"""The report's SVG figures read back from the files: swatch fills, bar heights through the
axis scale their own tick labels define, curve points; compared with solution.json and the
plotted inputs (an independent check of what is on the page, not of the drawing code)."""

from __future__ import annotations

import ast
import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from svg_readback import (
    axis_scale,
    bar_base,
    bar_height,
    find,
    load,
    number,
    points,
    rgb,
    text_of,
)

from ocio_vp.report.build import build_report
from ocio_vp.report.data import DISPLAY_WHITE, STAGE_CHARTS
from ocio_vp.report.plots import plot_comparison_charts, plot_delta_e, plot_linearity

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "sample_configs" / "paper_stage"
DPI = 30
CHANNELS = ("R", "G", "B")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    # The committed paper-stage solutions: seven environments, sodium vapour the outlier.
    return build_report([SAMPLE], tmp_path_factory.mktemp("plots") / "r", dpi=DPI)


def _diagnostics(environment: str) -> dict:
    return json.loads((SAMPLE / environment / "solution.json").read_text())["diagnostics"]


def _srgb_encode(v: np.ndarray) -> np.ndarray:
    # IEC 61966-2-1 piecewise encoding, written out (independent of colour-science).
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)


def test_chart_swatches_are_the_solution_colours(report):
    for data in report.environments:
        d = _diagnostics(data.solution.environment)
        charts = {k: np.asarray(v) for k, v in d["charts"].items()}
        charts.update({k: np.asarray(v) for k, v in (d.get("charts_clipped_drive") or {}).items()})
        A, white = data.transform.matrix, data.white_patch
        exposure = DISPLAY_WHITE / np.max(A @ charts["target"][white])
        root = load(report.charts[data.key].path)
        for panel in STAGE_CHARTS:
            scale = exposure * charts["target"][white, 1] / charts[panel][white, 1]
            for cls, camera, k in (
                ("square", charts["target"], exposure),
                ("circle", charts[panel], scale),
            ):
                shapes = find(
                    root, "rect" if cls == "square" else "circle", class_=cls, data_panel=panel
                )
                assert [s.get("data-patch") for s in shapes] == [str(j) for j in range(24)]
                drawn = np.array([rgb(s.get("fill")) for s in shapes])
                # The documented display path from solution.json's camera RGB, then 8 bits.
                expected = _srgb_encode(np.clip(k * camera @ A.T, 0.0, 1.0))
                np.testing.assert_allclose(drawn, expected, atol=0.5 / 255 + 1e-9)


def test_chart_titles_say_the_mean_error(report):
    for data in report.environments:
        plot = report.charts[data.key]
        root = load(plot.path)
        d = _diagnostics(data.solution.environment)
        for panel, key in STAGE_CHARTS.items():
            (title,) = find(root, "text", class_="title", data_axes=panel)
            assert text_of(title) == plot.titles[panel]
            figure = d.get(f"{key}_clipped_drive") if panel.startswith("lit") else None
            error = 100 * np.mean(figure if figure is not None else d[key])
            assert text_of(title).endswith(f"\nmean error {error:.2f}% of white")


def test_error_bars_read_back_are_the_solutions_errors(report):
    keys = {
        "lit": ("lit_chart_error_baseline", "lit_chart_error"),
        "displayed": ("displayed_chart_error_baseline", "displayed_chart_error"),
    }
    for kind, (base, ours) in keys.items():
        plot = report.error_bars[kind]
        root = load(plot.path)
        scale, per_px = axis_scale(root, "errors")
        for name in plot.environments:
            d = _diagnostics(name)
            for series, key in ((f"{kind}_baseline", base), (f"{kind}_corrected", ours)):
                figure = d.get(f"{key}_clipped_drive") if kind == "lit" else None
                expected = np.asarray(figure if figure is not None else d[key])
                for c, channel in enumerate(CHANNELS):
                    (bar,) = find(
                        root,
                        "rect",
                        class_="bar",
                        data_environment=name,
                        data_series=series,
                        data_channel=channel,
                    )
                    assert abs(bar_base(bar, scale)) <= 0.02 * per_px
                    height = bar_height(bar, scale) / 100  # the axis is in percent
                    # 0.01 pt rounding; relative for sodium's clipped bars far above the ticks.
                    assert height == pytest.approx(expected[c], abs=0.03 * per_px / 100, rel=2e-4)
                    hatched = bar.get("fill").startswith("url(#hatch-")
                    assert hatched == series.endswith("corrected")


def test_error_bars_cut_the_outlier_and_label_it(report):
    # Sodium's blue error (~2 of white) would flatten the others: the axis stops below it and
    # every bar it cuts carries its value; the bar keeps its true height under the clip.
    root = load(report.error_bars["lit"].path)
    scale, _ = axis_scale(root, "errors")
    (clip,) = find(root, "clipPath")
    (box,) = clip.iter("{http://www.w3.org/2000/svg}rect")
    axis_top = float(scale(float(box.get("y"))))
    bars = find(root, "rect", class_="bar")
    cut = [b for b in bars if bar_height(b, scale) > axis_top]
    assert cut and {b.get("data-environment") for b in cut} == {"sodium_vapour"}
    labels = sorted(
        number(text_of(t).rstrip("%")) for t in find(root, "text", class_="clipped-value")
    )
    heights = sorted(bar_height(b, scale) for b in cut)
    assert len(labels) == len(heights)
    np.testing.assert_allclose(labels, heights, rtol=5e-3)  # printed to 3 significant digits
    others = [bar_height(b, scale) for b in bars if b.get("data-environment") != "sodium_vapour"]
    assert max(others) < axis_top


def test_delta_e_bars_read_back(report):
    for data in report.environments:
        plot = report.delta_e[data.key]
        root = load(plot.path)
        for metric, label in (("CIE 2000", "ΔE2000"), ("ITP", "ΔE ITP")):
            for kind in ("lit", "displayed"):
                scale, per_px = axis_scale(root, f"{label} {kind}")
                for series in (f"{kind}_baseline", f"{kind}_corrected"):
                    bars = find(root, "rect", class_="bar", data_metric=metric, data_series=series)
                    assert [b.get("data-patch") for b in bars] == [str(j) for j in range(24)]
                    drawn = np.array([bar_height(b, scale) for b in bars])
                    expected = data.delta_e[metric][series]
                    np.testing.assert_allclose(drawn, expected, atol=0.03 * per_px)
                    np.testing.assert_array_equal(plot.values[metric][series], expected)
                # The grey line is at the white patch: between its two bars.
                (line,) = find(root, "line", class_="white-patch", data_axes=f"{label} {kind}")
                pair = find(
                    root, "rect", class_="bar", data_metric=metric, data_patch=str(data.white_patch)
                )
                pair = [b for b in pair if b.get("data-series").startswith(kind)]
                edges = [float(b.get("x")) for b in pair] + [
                    float(pair[1].get("x")) + float(pair[1].get("width"))
                ]
                assert float(line.get("x1")) == pytest.approx((edges[0] + edges[2]) / 2, abs=0.02)


def test_undefined_itp_is_a_red_x_not_a_bar(report, tmp_path):
    data = report.environments[0]
    itp = {k: v.copy() for k, v in data.delta_e["ITP"].items()}
    itp["lit_baseline"][[3, 7]] = np.nan
    broken = dataclasses.replace(data, delta_e={**data.delta_e, "ITP": itp})
    root = load(plot_delta_e(broken, tmp_path / "d.svg", dpi=DPI).path)
    marks = find(root, "path", class_="undefined")
    assert sorted(m.get("data-patch") for m in marks) == ["3", "7"]
    assert {m.get("data-series") for m in marks} == {"lit_baseline"}
    bars = find(root, "rect", class_="bar", data_metric="ITP", data_series="lit_baseline")
    assert len(bars) == 22 and not {"3", "7"} & {b.get("data-patch") for b in bars}
    (title,) = find(root, "text", class_="suptitle")
    assert "red x: ΔE ITP undefined" in text_of(title)


def test_linearity_curves_read_back(tmp_path):
    x = np.linspace(0.0, 1.0, 9)
    x33 = np.linspace(0.0, 1.0, 33)
    curves = {"red before": (x, x**1.15), "red after": (x33, x33), "green before": (x, x)}
    plot = plot_linearity(curves, tmp_path / "l.svg", dpi=DPI)
    root = load(plot.path)
    response = (axis_scale(root, "response", "x")[0], axis_scale(root, "response")[0])
    deviation = (axis_scale(root, "deviation", "x")[0], axis_scale(root, "deviation")[0])
    for label, (cx, cy) in curves.items():
        for axes, (sx, sy), expected in (
            ("response", response, cy),
            ("deviation", deviation, 100 * (cy - cx)),
        ):
            (group,) = find(root, "g", class_="curve", data_curve=label, data_axes=axes)
            (line,) = group.iter("{http://www.w3.org/2000/svg}polyline")
            p = points(line)
            np.testing.assert_allclose(sx(p[:, 0]), cx, atol=2e-4)
            np.testing.assert_allclose(
                sy(p[:, 1]), expected, atol=2e-4 * (1 if axes == "response" else 50)
            )
            assert (line.get("stroke-dasharray") is not None) == label.endswith("after")
            assert line.get("stroke") == {"red": "#c0392b", "green": "#27ae60"}[label.split()[0]]
        np.testing.assert_array_equal(plot.curves[label][1], cy)
    (ideal,) = find(root, "polyline", class_="ideal", data_axes="response")
    np.testing.assert_allclose(response[1](points(ideal)[:, 1]), [0.0, 1.0], atol=2e-4)


def test_same_input_same_bytes_and_short_numbers(report, tmp_path):
    data = report.environments[1]
    for plot, drawn in (
        (plot_comparison_charts, report.charts[data.key]),
        (plot_delta_e, report.delta_e[data.key]),
    ):
        again = plot(data, tmp_path / "again.svg", dpi=DPI).path
        assert again.read_bytes() == drawn.path.read_bytes()
        text = drawn.path.read_text()
        assert not re.search(r"\d\.\d{3}", re.sub(r">[^<]*<", "><", text))  # coordinates: 0.01


def test_no_figure_uses_matplotlib():
    # One way to draw figures: ocio_vp/svg.py, much quicker than matplotlib on the report's
    # figures and the take's contact sheet (measured: docs/report.md, benchmarks/bench_figures.py).
    for source in (ROOT / "ocio_vp").rglob("*.py"):
        for node in ast.walk(ast.parse(source.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            names += [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            assert not [n for n in names if n.split(".")[0] == "matplotlib"], source.name


def test_names_with_markup_are_text(report, tmp_path):
    # An environment name is whatever solution.json says: it must stay text in every figure.
    from ocio_vp.report.plots import plot_error_bars

    name = "<b>sun & \"shade\" 'x'</b>\x01"
    data = report.environments[0]
    odd = dataclasses.replace(data, solution=dataclasses.replace(data.solution, environment=name))
    kept = name.replace("\x01", "")  # not allowed in XML 1.0: dropped
    for path in (
        plot_comparison_charts(odd, tmp_path / "c.svg", dpi=DPI).path,
        plot_delta_e(odd, tmp_path / "d.svg", dpi=DPI).path,
        plot_error_bars([odd, *report.environments[1:]], "lit", tmp_path / "e.svg", dpi=DPI).path,
    ):
        root = load(path)  # well-formed
        assert root.get("aria-label").startswith(kept) or root.get("aria-label").startswith("Fig")
        texts = [text_of(t) for t in root.iter("{http://www.w3.org/2000/svg}text")]
        assert any(kept in t for t in texts), path.name
        assert "<b>" not in path.read_text()
    bars = find(load(tmp_path / "e.svg"), "rect", class_="bar", data_environment=kept)
    assert len(bars) == 6
