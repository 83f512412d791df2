"""The report's figures drawn with matplotlib, as ocio_vp drew them before its SVG writer
(``ocio_vp/report/plots.py`` at commit cc0000c^, unchanged but for this docstring, the SVG
backend in ``_save`` and the records, titles and colours, imported from the package): the reference :mod:`benchmarks.bench_figures` times the SVG writer
against, on today's report data. Not part of ocio_vp.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.report.data import STAGE_CHARTS, EnvironmentData, patch_names

# What is drawn and how it is recorded is the package's own; only the drawing is matplotlib.
from ocio_vp.report.plots import (
    BACKGROUND,
    CHANNEL_COLOURS,
    CHANNEL_NAMES,
    ChartPlot,
    DeltaEPlot,
    ErrorBarsPlot,
    LinearityPlot,
    panel_titles,
)

__all__ = [
    "plot_comparison_charts",
    "plot_delta_e",
    "plot_error_bars",
    "plot_linearity",
]


def _figure(width: float, height: float, **margins: float) -> Any:
    # A Figure on its own Agg canvas: no pyplot, so no global backend or figure registry.
    # Fixed margins rather than constrained layout, which draws every figure twice (2-3x the
    # time of a report).
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=(width, height))
    figure.subplots_adjust(**margins)
    FigureCanvasAgg(figure)
    return figure


def _save(figure: Any, path: Path, dpi: float) -> Path:
    path = Path(path)
    # No "Software" key: matplotlib's default puts its web address into every PNG. zlib level 3
    # instead of 6: the same pixels, files within ~10%, half the encoding time.
    if path.suffix == ".svg":  # matplotlib's SVG backend (text as paths, its default)
        figure.savefig(path, format="svg", metadata={"Creator": None})
    else:
        figure.savefig(path, dpi=dpi, metadata={"Software": None}, pil_kwargs={"compress_level": 3})
    return path


def _grid(n: int) -> tuple[int, int]:
    columns = 6 if n % 6 == 0 else math.ceil(math.sqrt(n))
    return columns, math.ceil(n / columns)


def _draw_chart(ax: Any, squares: np.ndarray, circles: np.ndarray) -> tuple[list, list]:
    from matplotlib.patches import Circle, Rectangle

    columns, rows = _grid(len(squares))
    square_artists, circle_artists = [], []
    # add_artist, not add_patch: the limits are set below, and add_patch's data-limit update
    # (every circle's Bezier path transformed) was a third of a chart figure's time.
    for j, (square, circle) in enumerate(zip(squares, circles, strict=True)):
        x, y = j % columns, rows - 1 - j // columns
        square_artists.append(
            ax.add_artist(Rectangle((x + 0.04, y + 0.04), 0.92, 0.92, facecolor=square, lw=0))
        )
        circle_artists.append(
            ax.add_artist(Circle((x + 0.5, y + 0.5), 0.26, facecolor=circle, lw=0))
        )
    ax.set_xlim(0, columns)
    ax.set_ylim(0, rows)
    ax.set_aspect("equal")
    ax.set_facecolor(BACKGROUND)
    ax.set_xticks([])
    ax.set_yticks([])
    return square_artists, circle_artists


def _reused(reuse: dict | None, key: tuple, build: Any) -> Any:
    """``build()``, or what it built before under ``key`` in ``reuse`` (one report's figures).

    A figure is built with its first environment's numbers, as it always was; the next ones
    only update it (and tests compare those pictures with figures built for them).
    """
    if reuse is None:
        return build()
    if key not in reuse:
        reuse[key] = build()
    return reuse[key]


def _charts_figure(data: EnvironmentData) -> tuple[Any, dict[str, tuple[Any, list, list]]]:
    figure = _figure(
        10.0, 7.4, left=0.015, right=0.985, top=0.88, bottom=0.01, hspace=0.2, wspace=0.05
    )
    panels = {}
    for ax, chart in zip(figure.subplots(2, 2).ravel(), STAGE_CHARTS, strict=True):
        panels[chart] = (ax, *_draw_chart(ax, data.display["target"], data.display[chart]))
    return figure, panels


def plot_comparison_charts(
    data: EnvironmentData, path: Path, *, dpi: float = 110, reuse: dict | None = None
) -> ChartPlot:
    """The paper's comparison charts for one environment (Section 4, its result figures).

    Squares are the target chart (real location), inset circles the stage chart; a 2x2 grid:
    lit chart (top) and in-camera background chart (bottom), baseline (left) and ours (right).
    Colours are ``data.display`` (see :mod:`ocio_vp.report.data`). With ``reuse`` (a dict kept
    across the environments of one report) the figure is built once per patch count and only
    its colours and titles change: the same picture, without rebuilding every artist.
    """
    from matplotlib.colors import to_rgb

    n = len(data.display["target"])
    figure, panels = _reused(reuse, ("charts", n), lambda: _charts_figure(data))
    squares, circles, drawn_titles = {}, {}, {}
    titles = panel_titles(data.solution)
    for chart, (ax, square_artists, circle_artists) in panels.items():
        for artist, colour in zip(square_artists, data.display["target"], strict=True):
            artist.set_facecolor(colour)
        for artist, colour in zip(circle_artists, data.display[chart], strict=True):
            artist.set_facecolor(colour)
        error = 100 * float(np.mean(data.errors[chart]))
        ax.set_title(f"{titles[chart]}\nmean error {error:.2f}% of white", fontsize=10)
        drawn_titles[chart] = ax.get_title()
        squares[chart] = np.array([to_rgb(a.get_facecolor()) for a in square_artists])
        circles[chart] = np.array([to_rgb(a.get_facecolor()) for a in circle_artists])
    figure.suptitle(
        f"{data.solution.environment}: squares = target chart in the real location, "
        "circles = on the stage",
        fontsize=11,
    )
    return ChartPlot(_save(figure, path, dpi), squares, circles, drawn_titles)


def _axis_top(values: np.ndarray) -> float | None:
    """A y limit that keeps the other environments readable next to an outlier (sodium).

    ``values`` is (environments, 6). When one environment's worst bar is over 2.5 times every
    other environment's, the axis stops at 1.6 times the second worst and the outlier bars are
    labelled with their value; otherwise ``None`` (matplotlib's own limits).
    """
    worst = np.sort(np.max(values, axis=1))[::-1] if len(values) > 1 else np.array([])
    if len(worst) < 2 or not worst[1] > 0 or worst[0] <= 2.5 * worst[1]:
        return None
    return float(1.6 * worst[1])


def plot_error_bars(
    environments: Sequence[EnvironmentData], kind: str, path: Path, *, dpi: float = 110
) -> ErrorBarsPlot:
    """The paper's Fig. 11: mean error per channel relative to the target white patch.

    ``kind`` is ``"lit"`` (out-of-frustum lit chart, Fig. 11a) or ``"displayed"`` (in-frustum
    displayed chart, Fig. 11b). Solid bars: baseline (M only); hatched bars: ours.
    """
    if kind not in ("lit", "displayed"):
        raise ValueError(f"kind must be 'lit' or 'displayed', got {kind!r}")
    names = [e.solution.environment for e in environments]
    width = max(7.0, 1.3 * len(names) + 3.5)
    figure = _figure(width, 4.2, left=0.8 / width, right=1 - 1.9 / width, top=0.92, bottom=0.2)
    ax = figure.subplots()
    width = 0.13
    x = np.arange(len(names))
    heights: dict[str, list[Any]] = {"baseline": [], "corrected": []}
    for series, hatch, offset in (("baseline", None, 0), ("corrected", "///", 3)):
        values = np.array([e.errors[f"{kind}_{series}"] for e in environments]).reshape(-1, 3)
        bars_per_channel = []
        for c in range(3):
            bars = ax.bar(
                x + (offset + c - 2.5) * width,
                100 * values[:, c],
                width,
                color=CHANNEL_COLOURS[c] if hatch is None else "white",
                edgecolor=CHANNEL_COLOURS[c],
                hatch=hatch,
                linewidth=1.0,
                label=f"{CHANNEL_NAMES[c]} {'baseline (M only)' if hatch is None else 'ours'}",
            )
            bars_per_channel.append([b.get_height() / 100 for b in bars])
        heights[series] = np.array(bars_per_channel).T
    top = _axis_top(np.concatenate([heights["baseline"], heights["corrected"]], axis=1))
    if top is not None:
        ax.set_ylim(0, 100 * top)
        for bar in ax.patches:
            if bar.get_height() > 100 * top:  # clipped by the axis: print its value
                ax.text(
                    bar.get_x() + bar.get_width() / 2,
                    100 * top * 0.98,
                    f"{bar.get_height():.3g}%",
                    rotation=90,
                    ha="center",
                    va="top",
                    fontsize=7,
                    color="black",
                    bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5},
                )
    ax.set_xticks(x, names, rotation=20, ha="right")
    ax.set_ylabel("mean |error| / target white (%)")
    what = "out-of-frustum lit chart" if kind == "lit" else "in-camera-frustum displayed chart"
    ax.set_title(f"Error relative to white: {what}", fontsize=11)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return ErrorBarsPlot(
        _save(figure, path, dpi),
        names,
        np.asarray(heights["baseline"], dtype=np.float64).reshape(-1, 3),
        np.asarray(heights["corrected"], dtype=np.float64).reshape(-1, 3),
    )


def _delta_e_figure(data: EnvironmentData) -> tuple[Any, Any, dict, dict]:
    n = len(data.charts["target"])
    figure = _figure(
        11.0, 6.8, left=0.06, right=0.99, top=0.91, bottom=0.2, hspace=0.2, wspace=0.14
    )
    axes = figure.subplots(2, 2, sharex=True)
    x = np.arange(n)
    bars, white_lines = {}, {}
    for col, metric in enumerate(("CIE 2000", "ITP")):
        for row, kind in enumerate(("lit", "displayed")):
            ax = axes[row, col]
            for series, colour, hatch, shift in (
                ("baseline", "#7f7f7f", None, -0.2),
                ("corrected", "white", "///", 0.2),
            ):
                bars[metric, f"{kind}_{series}"] = ax.bar(
                    x + shift,
                    data.delta_e[metric][f"{kind}_{series}"],
                    0.4,
                    color=colour,
                    edgecolor="#333333",
                    hatch=hatch,
                    linewidth=0.8,
                    label="baseline (M only)" if hatch is None else "ours",
                )
            label = "ΔE2000" if metric == "CIE 2000" else "ΔE ITP"
            place = "lit chart" if kind == "lit" else "in-camera background"
            ax.set_title(f"{label}, {place}", fontsize=10)
            ax.set_ylabel(label)
            ax.grid(axis="y", alpha=0.3)
            white_lines[ax] = ax.axvline(data.white_patch, color="#bbbbbb", lw=0.8, zorder=0)
    labels = patch_names(n)
    for ax in axes[1]:
        ax.set_xticks(x, labels, fontsize=7, rotation=60 if n == 24 else 0, ha="right")
        ax.set_xlabel("chart patch (grey line = white patch)")
    axes[0, 0].legend(fontsize=8)
    return figure, axes, bars, white_lines


def plot_delta_e(
    data: EnvironmentData, path: Path, *, dpi: float = 110, reuse: dict | None = None
) -> DeltaEPlot:
    """Per-patch ΔE2000 and ΔE ITP of the stage charts against the target, baseline vs ours.

    ``reuse`` as in :func:`plot_comparison_charts`: bar heights, the white patch's line and the
    axis limits are updated in a figure built once per patch count.
    """
    n = len(data.charts["target"])
    figure, axes, bars, white_lines = _reused(reuse, ("delta_e", n), lambda: _delta_e_figure(data))
    drawn: dict[str, dict[str, np.ndarray]] = {"CIE 2000": {}, "ITP": {}}
    for (metric, chart), container in bars.items():
        for bar, height in zip(container, data.delta_e[metric][chart], strict=True):
            bar.set_height(height)
        drawn[metric][chart] = np.array([b.get_height() for b in container])
    for marker in reuse.pop(("delta_e markers", n), []) if reuse is not None else []:
        marker.remove()
    markers = []
    for (metric, chart), container in bars.items():
        undefined = np.flatnonzero(np.isnan(data.delta_e[metric][chart]))
        if undefined.size:  # no bar to draw: mark the patch so it is not read as 0
            shift = -0.2 if chart.endswith("baseline") else 0.2  # as the bars are placed
            ax = container.patches[0].axes
            x = np.arange(n)[undefined] + shift
            markers += ax.plot(x, np.zeros(undefined.size), "x", color="#c0392b")
    if reuse is not None:
        reuse["delta_e markers", n] = markers
    for ax, line in white_lines.items():
        line.set_xdata([data.white_patch, data.white_patch])
        ax.relim()  # as a new figure's limits: from the bars (and the line's x), then margins
        ax.autoscale_view()
    title = f"{data.solution.environment}: colour difference per patch"
    if any(np.isnan(v).any() for v in data.delta_e["ITP"].values()):
        title += " (red x: ΔE ITP undefined, a colour with negative light)"
    figure.suptitle(title, fontsize=11)
    return DeltaEPlot(_save(figure, path, dpi), drawn)


def plot_linearity(
    curves: dict[str, tuple[Sequence[float], Sequence[float]]],
    path: Path,
    *,
    title: str = "Panel linearity",
    dpi: float = 110,
) -> LinearityPlot:
    """Panel response (drive -> normalised camera response) and its deviation from linear.

    ``curves`` maps a label such as ``"red before"``/``"red after"`` to ``(x, y)``; the label's
    first word picks the channel colour, ``after`` curves are dashed. Left: the curves with the
    ideal line y = x; right: ``y - x`` in percent of the top step, where small deviations show.
    """
    figure = _figure(10.0, 4.0, left=0.07, right=0.98, top=0.88, bottom=0.13, wspace=0.25)
    response_ax, deviation_ax = figure.subplots(1, 2)
    response_ax.plot([0, 1], [0, 1], color="#999999", lw=0.8, label="linear")
    deviation_ax.axhline(0.0, color="#999999", lw=0.8)
    drawn = {}
    for label, (x, y) in curves.items():
        words = label.lower().split()
        channel = {"red": 0, "green": 1, "blue": 2}.get(words[0] if words else "", None)
        colour = "#333333" if channel is None else CHANNEL_COLOURS[channel]
        style = "--" if "after" in words else "-"
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        (line,) = response_ax.plot(x, y, style, color=colour, marker=".", ms=4, label=label)
        deviation_ax.plot(x, 100 * (y - x), style, color=colour, marker=".", ms=4, label=label)
        drawn[label] = (np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float))
    response_ax.set_xlabel("drive sent to the wall")
    response_ax.set_ylabel("camera response (normalised at the top step)")
    deviation_ax.set_xlabel("drive sent to the wall")
    deviation_ax.set_ylabel("response - drive (% of the top step)")
    for ax in (response_ax, deviation_ax):
        ax.grid(alpha=0.3)
    response_ax.legend(fontsize=8)
    figure.suptitle(f"{title}: solid = measured, dashed = through the 1D LUT", fontsize=11)
    return LinearityPlot(_save(figure, path, dpi), drawn)
