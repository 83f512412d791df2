"""The SVG writer under the report's figures: nice ticks, escaping, numbers, layout."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ocio_vp.svg import (
    Axes,
    Canvas,
    escape,
    hex_colour,
    nice_ticks,
    num,
    subplot_boxes,
    tick_labels,
)


class TestNiceTicks:
    def test_steps_are_1_2_5_and_cover_the_range(self):
        rng = np.random.default_rng(7)
        for _ in range(2000):
            low = rng.uniform(-1, 1) * 10.0 ** rng.integers(-6, 7)
            high = low + rng.uniform(1e-3, 10) * 10.0 ** rng.integers(-6, 7)
            if high - low < 1e-6 * max(abs(low), abs(high)):
                continue  # beyond float64's resolution of the labels
            max_ticks = int(rng.integers(3, 10))
            ticks = nice_ticks(low, high, max_ticks)
            assert len(ticks) >= 2, (low, high, max_ticks)
            step = ticks[1] - ticks[0]
            mantissa = round(step / 10.0 ** math.floor(math.log10(step) + 1e-9), 6)
            assert mantissa in (1, 2, 5), (low, high, step)
            np.testing.assert_allclose(np.diff(ticks), step, rtol=1e-6)
            np.testing.assert_allclose(ticks / step, np.round(ticks / step), atol=1e-6)
            span = high - low
            assert ticks[0] >= low - 1e-9 * span and ticks[-1] <= high + 1e-9 * span
            # Every multiple of the step in the range is a tick.
            assert ticks[0] - step < low + 1e-9 * span and ticks[-1] + step > high - 1e-9 * span

            def count(s, low=low, high=high):
                return math.floor(high / s + 1e-9) - math.ceil(low / s - 1e-9) + 1

            # The next smaller 1-2-5 step gives too many ticks, or this one would give < 2.
            smaller = step * {1: 0.5, 2: 0.5, 5: 0.4}[mantissa]
            assert count(smaller) > max_ticks or count(step * 2.5) < 2, (low, high, step)
            assert len(ticks) <= max_ticks or count(step * {1: 2, 2: 2.5, 5: 2}[mantissa]) < 2

    def test_known_cases(self):
        assert nice_ticks(0, 1).tolist() == [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
        assert nice_ticks(0, 4.9).tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
        assert nice_ticks(-5.4, 0.3).tolist() == [-5.0, -4.0, -3.0, -2.0, -1.0, 0.0]
        assert nice_ticks(0, 43.5).tolist() == [0.0, 10.0, 20.0, 30.0, 40.0]
        assert nice_ticks(1.0, 1.0).size == 0 and nice_ticks(0, math.nan).size == 0

    def test_labels(self):
        assert tick_labels(np.array([0.0, 0.05, 0.1])) == ["0.00", "0.05", "0.10"]
        assert tick_labels(np.array([-10.0, 0.0, 10.0])) == ["\u221210", "0", "10"]
        assert tick_labels(nice_ticks(-0.3, 0.2)) == [
            "\u22120.3",
            "\u22120.2",
            "\u22120.1",
            "0.0",
            "0.1",
            "0.2",
        ]


class TestText:
    @pytest.mark.parametrize(
        "text",
        [
            '<script>alert("x")</script>',
            "a & b",
            "quote ' and \"",
            "tab\there",
            "bell\x07x",
            "ΔE ITP — ünïcode",
            "]]> <!-- -->",
        ],
    )
    def test_any_string_gives_well_formed_svg_with_that_text(self, text, tmp_path):
        canvas = Canvas(2, 1, 50, label=text)
        canvas.text(10, 10, text, class_="t", data_name=text)
        root = ET.parse(canvas.write(tmp_path / "t.svg")).getroot()
        (element,) = [e for e in root.iter("{http://www.w3.org/2000/svg}text")]
        kept = text.replace("\x07", "")  # XML 1.0 cannot hold control characters: dropped
        assert element.text == kept and element.get("data-name") == kept
        assert root.get("aria-label") == kept
        assert "<script" not in canvas.tostring()

    def test_escape(self):
        assert escape("<a href='x'>&</a>") == "&lt;a href=&#39;x&#39;&gt;&amp;&lt;/a&gt;"

    def test_multiline_text_is_tspans(self, tmp_path):
        canvas = Canvas(2, 1, 50)
        canvas.text(10, 10, "one\ntwo & three")
        root = ET.parse(canvas.write(tmp_path / "t.svg")).getroot()
        spans = list(root.iter("{http://www.w3.org/2000/svg}tspan"))
        assert [s.text for s in spans] == ["one", "two & three"]


class TestNumbers:
    def test_num_rounds_to_hundredths(self):
        assert [num(v) for v in (0.0, -0.004, 1.005000001, 12.3, 1e-9, -2.5, 1234.5678)] == [
            "0",
            "0",
            "1.01",
            "12.3",
            "0",
            "-2.5",
            "1234.57",
        ]

    def test_hex_colour_clips_and_rounds(self):
        assert hex_colour([0.0, 1.0, 0.5]) == "#00ff80"
        assert hex_colour([-0.5, 1.7, 127.4 / 255]) == "#00ff7f"
        values = np.random.default_rng(1).uniform(0, 1, (50, 3))
        for v in values:
            back = np.array([int(hex_colour(v)[i : i + 2], 16) for i in (1, 3, 5)]) / 255
            assert np.all(np.abs(back - v) <= 0.5 / 255 + 1e-12)


class TestLayout:
    def test_subplot_boxes_are_matplotlibs(self):
        # The figures kept the old layout: compare with matplotlib's own subplot positions
        # (matplotlib is installed, colour-science needs it; the report does not use it).
        from matplotlib.figure import Figure

        params = {
            "left": 0.06,
            "right": 0.99,
            "top": 0.91,
            "bottom": 0.2,
            "wspace": 0.14,
            "hspace": 0.2,
        }
        figure = Figure(figsize=(11.0, 6.8))
        figure.subplots_adjust(**params)
        axes = figure.subplots(2, 2).ravel()
        canvas = Canvas(11.0, 6.8, 100)
        for ax, (x, y, w, h) in zip(axes, subplot_boxes(canvas, 2, 2, **params), strict=True):
            p = ax.get_position()  # figure fractions, from the bottom left
            expected = (
                p.x0 * canvas.width,
                (1 - p.y1) * canvas.height,
                p.width * canvas.width,
                p.height * canvas.height,
            )
            np.testing.assert_allclose((x, y, w, h), expected, atol=1e-9)

    def test_axes_maps_limits_onto_the_box(self):
        axes = Axes(Canvas(2, 2, 72), (10.0, 20.0, 100.0, 50.0), (0.0, 2.0), (-1.0, 1.0))
        assert axes.x(0.0) == 10.0 and axes.x(2.0) == 110.0
        assert axes.y(-1.0) == 70.0 and axes.y(1.0) == 20.0  # y grows downwards in SVG

    def test_size_is_inches_times_dpi_and_output_is_deterministic(self, tmp_path):
        def draw(path):
            canvas = Canvas(3.0, 2.0, 40)
            canvas.rect(1 / 3, 2 / 3, 10, 10, fill=canvas.hatch("#123456"))
            canvas.polyline([0.123456, 1], [2.98765, 3])
            return canvas.write(path).read_bytes()

        first = draw(tmp_path / "a.svg")
        assert first == draw(tmp_path / "b.svg")
        root = ET.fromstring(first)
        assert (root.get("width"), root.get("height"), root.get("viewBox")) == (
            "120",
            "80",
            "0 0 216 144",
        )
        assert b'points="0.12,2.99 1,3"' in first and b'x="0.33" y="0.67"' in first
        assert b'<pattern id="hatch-123456"' in first and b'fill="url(#hatch-123456)"' in first
