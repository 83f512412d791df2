"""The report's figures as SVG (:mod:`ocio_vp.svg`): the paper's comparison charts, its Fig. 11
error bars, per-patch ΔE and the panel linearity curves. Each plot writes one file and returns
the numbers it drew; elements carry ``class`` and ``data-*`` attributes to read them back.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, Section 4: comparison charts
(target patch as a square, stage value as an inset circle) and Fig. 11 (mean error per channel
relative to white; baseline solid, ours hatched).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ocio_vp.formats.solution import Solution
from ocio_vp.report.data import STAGE_CHARTS, EnvironmentData, patch_names
from ocio_vp.svg import Axes, Canvas, data_limits, hex_colours, num, subplot_boxes

__all__ = [
    "ChartPlot",
    "DeltaEPlot",
    "ErrorBarsPlot",
    "LinearityPlot",
    "panel_titles",
    "plot_comparison_charts",
    "plot_delta_e",
    "plot_error_bars",
    "plot_linearity",
]

CHANNEL_COLOURS = ("#c0392b", "#27ae60", "#2e6fbd")
CHANNEL_NAMES = ("R", "G", "B")
#: The two series of every bar plot: baseline (M only) and ours.
SERIES = ("baseline", "corrected")


def panel_titles(solution: Solution) -> dict[str, str]:
    """Panel titles that say what "ours" is for this solution (N or black level may be absent)."""
    background = ["N" if solution.N is not None else "M (N not solved)"]
    if solution.black_level_offset is not None:
        background.append("black level")
    if solution.N is not None:
        background.append("Q")
    return {
        "lit_baseline": "Lit chart: baseline (M only)",
        "lit_corrected": "Lit chart: ours (M, then Q on the footage)",
        "displayed_baseline": "In-camera background: baseline (M only)",
        "displayed_corrected": f"In-camera background: ours ({', '.join(background)})",
    }


BACKGROUND = "#3a3a3a"


@dataclass(frozen=True)
class ChartPlot:
    """sRGB colours in [0, 1] drawn per panel: ``squares`` (target) and ``circles`` (stage)."""

    path: Path
    squares: dict[str, np.ndarray]
    circles: dict[str, np.ndarray]
    titles: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class ErrorBarsPlot:
    """Bar heights (fractions of white, not percent): (environments, 3) per series."""

    path: Path
    environments: list[str]
    baseline: np.ndarray
    ours: np.ndarray


@dataclass(frozen=True)
class DeltaEPlot:
    """Per-patch ΔE drawn: ``values[metric][chart]`` is (n,)."""

    path: Path
    values: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)


@dataclass(frozen=True)
class LinearityPlot:
    """Curves drawn: ``curves[label] = (x, y)`` arrays."""

    path: Path
    curves: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)


def _grid(n: int) -> tuple[int, int]:
    columns = 6 if n % 6 == 0 else math.ceil(math.sqrt(n))
    return columns, math.ceil(n / columns)


def _draw_chart(
    canvas: Canvas, box: tuple, panel: str, squares: np.ndarray, circles: np.ndarray
) -> tuple[float, float, float, float]:
    """Squares with inset circles on a dark ground, in reading order; the chart's box (the
    given box shrunk to square cells and centred, like an equal-aspect matplotlib axes)."""
    columns, rows = _grid(len(squares))
    x0, y0, w, h = box
    unit = min(w / columns, h / rows)
    left, top = x0 + (w - unit * columns) / 2, y0 + (h - unit * rows) / 2
    canvas.open(class_="chart", data_panel=panel)
    canvas.rect(left, top, unit * columns, unit * rows, fill=BACKGROUND)
    for j, (square, circle) in enumerate(
        zip(hex_colours(squares), hex_colours(circles), strict=True)
    ):
        x, y = left + (j % columns) * unit, top + (j // columns) * unit
        patch = {"data_panel": panel, "data_patch": str(j)}
        canvas.rect(
            x + 0.04 * unit,
            y + 0.04 * unit,
            0.92 * unit,
            0.92 * unit,
            fill=square,
            class_="square",
            **patch,
        )
        canvas.circle(
            x + 0.5 * unit,
            y + 0.5 * unit,
            0.26 * unit,
            fill=circle,
            class_="circle",
            **patch,
        )
    canvas.rect(
        left, top, unit * columns, unit * rows, fill="none", stroke="black", stroke_width=0.8
    )
    canvas.close()
    return left, top, unit * columns, unit * rows


def _suptitle(canvas: Canvas, text: str) -> None:
    canvas.text(
        canvas.width / 2, 0.02 * canvas.height, text, size=11, valign="top", class_="suptitle"
    )


def plot_comparison_charts(data: EnvironmentData, path: Path, *, dpi: float = 110) -> ChartPlot:
    """The paper's comparison charts for one environment (Section 4): squares the target chart,
    inset circles the stage's; lit chart and in-camera background (rows), baseline and ours
    (columns), in ``data.display`` colours."""
    canvas = Canvas(10.0, 7.4, dpi, label=f"{data.solution.environment}: comparison charts")
    boxes = subplot_boxes(
        canvas, 2, 2, left=0.015, right=0.985, top=0.88, bottom=0.01, hspace=0.2, wspace=0.05
    )
    titles = panel_titles(data.solution)
    target = np.clip(data.display["target"], 0.0, 1.0)
    squares, circles, drawn_titles = {}, {}, {}
    for box, chart in zip(boxes, STAGE_CHARTS, strict=True):  # rows lit/displayed, columns M/ours
        stage = np.clip(data.display[chart], 0.0, 1.0)
        chart_box = _draw_chart(canvas, box, chart, target, stage)
        error = 100 * float(np.mean(data.errors[chart]))
        drawn_titles[chart] = f"{titles[chart]}\nmean error {error:.2f}% of white"
        Axes(canvas, chart_box, (0, 1), (0, 1), name=chart).title(drawn_titles[chart])
        squares[chart], circles[chart] = target, stage
    _suptitle(
        canvas,
        f"{data.solution.environment}: squares = target chart in the real location, "
        "circles = on the stage",
    )
    return ChartPlot(canvas.write(path), squares, circles, drawn_titles)


def _axis_top(values: np.ndarray) -> float | None:
    """A y limit that keeps the others readable next to an outlier environment (sodium): 1.6
    times the second worst where the worst of ``values`` (environments, 6) is over 2.5 times
    it, else None (the data's range)."""
    worst = np.sort(np.max(values, axis=1))[::-1] if len(values) > 1 else np.array([])
    if len(worst) < 2 or not worst[1] > 0 or worst[0] <= 2.5 * worst[1]:
        return None
    return float(1.6 * worst[1])


def _bar(axes: Axes, centre: float, width: float, height: float, **attributes: object) -> None:
    """A bar from 0 to ``height`` (data units) centred on ``centre``; nothing for NaN; a bar
    too low to show also gets its bottom edge, so a 0 is not read as missing."""
    if not math.isfinite(height):
        return
    x0, x1 = axes.x(centre - width / 2), axes.x(centre + width / 2)
    y0, y1 = axes.y(0.0), axes.y(height)
    axes.canvas.rect(x0, min(y0, y1), x1 - x0, abs(y0 - y1), class_="bar", **attributes)
    if abs(y0 - y1) < 0.005 and "stroke" in attributes:
        axes.canvas.line(x0, y0, x1, y0, stroke=attributes["stroke"], class_="bar-edge")


def _label_clipped(axes: Axes, x: float, top: float, value: float) -> None:
    """The value of a bar cut by the axis top, written down the bar on a white ground."""
    text = f"{value:.3g}%"
    cx, y = float(axes.x(x)), float(axes.y(0.98 * top))
    axes.canvas.rect(cx - 4.5, y, 9.0, 0.6 * 7 * len(text) + 2, fill="white")
    axes.canvas.text(
        cx, y + 1, text, size=7, anchor="end", valign="center", rotate=-90, class_="clipped-value"
    )


def plot_error_bars(
    environments: Sequence[EnvironmentData], kind: str, path: Path, *, dpi: float = 110
) -> ErrorBarsPlot:
    """The paper's Fig. 11, mean error per channel relative to the target white, for ``kind``
    ``"lit"`` (11a) or ``"displayed"`` (11b): baseline solid, ours hatched."""
    if kind not in ("lit", "displayed"):
        raise ValueError(f"kind must be 'lit' or 'displayed', got {kind!r}")
    names = [e.solution.environment for e in environments]
    values = {
        series: np.array([e.errors[f"{kind}_{series}"] for e in environments]).reshape(-1, 3)
        for series in SERIES
    }
    width = max(7.0, 1.3 * len(names) + 3.5)
    canvas = Canvas(width, 4.2, dpi, label=f"Fig. 11 error bars, {kind} chart")
    (box,) = subplot_boxes(
        canvas, 1, 1, left=0.8 / width, right=1 - 1.9 / width, top=0.92, bottom=0.2
    )
    bar, x = 0.13, np.arange(len(names), dtype=np.float64)
    top = _axis_top(np.concatenate([values["baseline"], values["corrected"]], axis=1))
    ylim = (
        (0.0, 100 * top)
        if top is not None
        else data_limits(100 * np.concatenate(list(values.values())), zero=True)
    )
    xlim = (-2.5 * bar - bar / 2, len(names) - 1 + 2.5 * bar + bar / 2)
    pad = 0.05 * (xlim[1] - xlim[0])
    axes = Axes(canvas, box, (xlim[0] - pad, xlim[1] + pad), ylim, name="errors")
    axes.yticks()
    canvas.open(clip_path=axes.clip())
    legend, cut = [], []
    for series, offset in (("baseline", 0), ("corrected", 3)):
        for c, colour in enumerate(CHANNEL_COLOURS):
            fill = colour if series == "baseline" else canvas.hatch(colour)
            style = {"fill": fill, "stroke": colour, "stroke_width": 1.0}
            what = "baseline (M only)" if series == "baseline" else "ours"
            legend.append((f"{CHANNEL_NAMES[c]} {what}", style))
            for i, name in enumerate(names):
                centre, height = x[i] + (offset + c - 2.5) * bar, 100 * values[series][i, c]
                _bar(
                    axes,
                    centre,
                    bar,
                    height,
                    data_environment=name,
                    data_series=f"{kind}_{series}",
                    data_channel=CHANNEL_NAMES[c],
                    **style,
                )
                if top is not None and height > 100 * top:
                    cut.append((centre, height))
    canvas.close()
    for centre, height in cut:  # clipped by the axis (so ``top`` is set): print its value
        _label_clipped(axes, centre, 100 * (top or 0.0), height)
    axes.frame()
    axes.xticks(x, names, rotate=20)
    axes.ylabel("mean |error| / target white (%)")
    what = "out-of-frustum lit chart" if kind == "lit" else "in-camera-frustum displayed chart"
    axes.title(f"Error relative to white: {what}", size=11)
    axes.legend(legend, outside=True)
    return ErrorBarsPlot(canvas.write(path), names, values["baseline"], values["corrected"])


def _delta_e_style(canvas: Canvas, series: str) -> dict[str, object]:
    """A ΔE bar's style (and its legend swatch's): baseline grey, ours hatched."""
    fill = "#7f7f7f" if series == "baseline" else canvas.hatch("#333333")
    return {"fill": fill, "stroke": "#333333", "stroke_width": 0.8}


def _delta_e_panel(
    canvas: Canvas, box: tuple, data: EnvironmentData, metric: str, kind: str, bottom: bool
) -> None:
    """One panel of :func:`plot_delta_e`: baseline and ours per patch, the white patch's line."""
    n = len(data.charts["target"])
    series = {s: np.asarray(data.delta_e[metric][f"{kind}_{s}"], float) for s in SERIES}
    pad = 0.05 * (n - 1 + 0.8)
    label = "ΔE2000" if metric == "CIE 2000" else "ΔE ITP"
    axes = Axes(
        canvas,
        box,
        (-0.4 - pad, n - 0.6 + pad),
        data_limits(np.concatenate(list(series.values())), zero=True),
        name=f"{label} {kind}",
    )
    white = float(axes.x(data.white_patch))
    canvas.line(
        white,
        box[1],
        white,
        box[1] + box[3],
        stroke="#bbbbbb",
        stroke_width=0.8,
        class_="white-patch",
        data_patch=str(data.white_patch),
        data_axes=axes.name,
    )
    axes.yticks()
    for name, values in series.items():
        shift = -0.2 if name == "baseline" else 0.2
        style = _delta_e_style(canvas, name)
        tags = {"data_metric": metric, "data_series": f"{kind}_{name}"}
        for j, value in enumerate(values):
            _bar(axes, j + shift, 0.4, float(value), **style, data_patch=str(j), **tags)
        for missing in np.flatnonzero(np.isnan(values)):  # no bar: mark it, not read as 0
            x, y = float(axes.x(missing + shift)), float(axes.y(0.0))
            d = (
                f"M{num(x - 3)},{num(y - 3)}L{num(x + 3)},{num(y + 3)}"
                f"M{num(x - 3)},{num(y + 3)}L{num(x + 3)},{num(y - 3)}"
            )
            canvas.element(
                "path",
                d=d,
                stroke="#c0392b",
                stroke_width=1.0,
                class_="undefined",
                data_patch=str(missing),
                **tags,
            )
    axes.frame()
    place = "lit chart" if kind == "lit" else "in-camera background"
    axes.title(f"{label}, {place}")
    axes.ylabel(label)
    if bottom:
        rotate = 60 if n == 24 else 0
        axes.xticks(np.arange(n), patch_names(n), size=7, rotate=rotate)
        axes.xlabel("chart patch (grey line = white patch)", offset=62 if rotate else 16)
    else:
        axes.xticks(np.arange(n), None)


def plot_delta_e(data: EnvironmentData, path: Path, *, dpi: float = 110) -> DeltaEPlot:
    """Per-patch ΔE2000 and ΔE ITP (columns) of the lit and in-camera charts (rows) against
    the target, baseline vs ours; an undefined ΔE ITP is a red x at 0, not a bar."""
    canvas = Canvas(11.0, 6.8, dpi, label=f"{data.solution.environment}: ΔE per patch")
    boxes = subplot_boxes(
        canvas, 2, 2, left=0.06, right=0.99, top=0.91, bottom=0.2, hspace=0.2, wspace=0.14
    )
    for i, box in enumerate(boxes):
        metric, kind = ("CIE 2000", "ITP")[i % 2], ("lit", "displayed")[i // 2]
        _delta_e_panel(canvas, box, data, metric, kind, bottom=i >= 2)
    drawn = {
        metric: {chart: np.asarray(v, dtype=np.float64) for chart, v in charts.items()}
        for metric, charts in data.delta_e.items()
    }
    legend = [("baseline (M only)", "baseline"), ("ours", "corrected")]
    Axes(canvas, boxes[0], (0, 1), (0, 1), name="legend").legend(
        [(label, _delta_e_style(canvas, series)) for label, series in legend], corner="upper right"
    )
    title = f"{data.solution.environment}: colour difference per patch"
    if any(np.isnan(v).any() for v in data.delta_e["ITP"].values()):
        title += " (red x: ΔE ITP undefined, a colour with negative light)"
    _suptitle(canvas, title)
    return DeltaEPlot(canvas.write(path), drawn)


def _curve(axes: Axes, x: np.ndarray, y: np.ndarray, label: str, style: dict) -> None:
    """A polyline with a dot at each point, ``data-curve`` = its label."""
    canvas = axes.canvas
    xs, ys = axes.x(x), axes.y(y)
    canvas.open(class_="curve", data_curve=label, data_axes=axes.name)
    canvas.polyline(xs, ys, stroke_width=1.5, **style)
    for px, py in zip(xs, ys, strict=True):
        canvas.circle(px, py, 1.4, fill=style["stroke"])
    canvas.close()


def plot_linearity(
    curves: Mapping[str, tuple[Sequence[float] | np.ndarray, Sequence[float] | np.ndarray]],
    path: Path,
    *,
    title: str = "Panel linearity",
    dpi: float = 110,
) -> LinearityPlot:
    """Panel response (drive -> normalised camera response) and its deviation ``y - x`` from
    linear; ``curves`` maps labels such as ``"red before"`` / ``"red after"`` (dashed) to
    ``(x, y)``, the first word picking the channel colour."""
    canvas = Canvas(10.0, 4.0, dpi, label=title)
    boxes = subplot_boxes(canvas, 1, 2, left=0.07, right=0.98, top=0.88, bottom=0.13, wspace=0.25)
    drawn = {
        k: (np.asarray(x, np.float64), np.asarray(y, np.float64)) for k, (x, y) in curves.items()
    }
    xs = np.concatenate([[0.0, 1.0], *(x for x, _ in drawn.values())])
    ys = np.concatenate([[0.0, 1.0], *(y for _, y in drawn.values())])
    dev = np.concatenate([[0.0], *(100 * (y - x) for x, y in drawn.values())])
    response = Axes(canvas, boxes[0], data_limits(xs), data_limits(ys), name="response")
    deviation = Axes(canvas, boxes[1], data_limits(xs), data_limits(dev), name="deviation")
    ideal = {"stroke": "#999999", "stroke_width": 0.8}
    legend = [("linear", ideal)]
    for axes, line in (
        (response, ([0.0, 1.0], [0.0, 1.0])),
        (deviation, (deviation.xlim, [0.0, 0.0])),  # across the whole panel
    ):
        axes.yticks()
        axes.xticks(grid=True)
        canvas.polyline(
            axes.x(line[0]), axes.y(line[1]), class_="ideal", data_axes=axes.name, **ideal
        )
    for label, (x, y) in drawn.items():
        words = label.lower().split()
        channel = {"red": 0, "green": 1, "blue": 2}.get(words[0] if words else "", None)
        style = {
            "stroke": "#333333" if channel is None else CHANNEL_COLOURS[channel],
            "stroke_dasharray": "5.55,2.4" if "after" in words else None,
        }
        _curve(response, x, y, label, style)
        _curve(deviation, x, 100 * (y - x), label, style)
        legend.append((label, {**style, "stroke_width": 1.5, "marker": True}))
    for axes in (response, deviation):
        axes.frame()
        axes.xlabel("drive sent to the wall")
    response.ylabel("camera response (normalised at the top step)", offset=36)
    deviation.ylabel("response - drive (% of the top step)", offset=36)
    response.legend(legend)
    _suptitle(canvas, f"{title}: solid = measured, dashed = through the 1D LUT")
    return LinearityPlot(canvas.write(path), drawn)
