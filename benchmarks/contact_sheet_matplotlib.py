"""The take's contact sheet drawn with matplotlib, as ocio_vp drew it before it moved to its SVG
writer (``ocio_vp/plates/contact_sheet.py`` at commit fb47e70, unchanged but for this docstring and
the thumbnail, strip length and colours, imported from it):
the reference :mod:`benchmarks.bench_figures` times :mod:`ocio_vp.plates.contact_sheet`
against. Not part of ocio_vp.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

# The thumbnail, the strip length and the colours are the package's own (the same project's
# private names); only the drawing is matplotlib.
from ocio_vp.plates.contact_sheet import _COLOURS, _FRAMES_PER_STRIP, _thumbnail
from ocio_vp.plates.take import TakeReading, rows_read

__all__ = ["write_contact_sheet"]


def _draw_frame(ax, reading: TakeReading) -> None:
    import matplotlib.patches as mpatches

    image, step, frame = _thumbnail(reading)
    ax.imshow(image, interpolation="nearest")
    x0, y0, x1, y1 = reading.region
    ox, oy = reading.info.x, reading.info.y
    ax.add_patch(
        mpatches.Rectangle(
            ((x0 - ox) / step - 0.5, (y0 - oy) / step - 0.5),
            (x1 - x0) / step,
            (y1 - y0) / step,
            fill=False,
            edgecolor="#00e000",
            linewidth=1.5,
        )
    )
    for ya, yb in rows_read(reading.info, reading.region, reading.movie)[1]:
        ax.plot(
            [(x0 - ox) / step, (x1 - ox) / step],
            [(ya + yb) / 2 / step] * 2,
            color="#ffd000",
            lw=0.6,
        )
    how = "found automatically" if reading.region_found else "given"
    ax.set_title(
        f"frame {frame}: wall region {list(reading.region)} ({how}); yellow: rows read", fontsize=8
    )
    ax.set_axis_off()


def _draw_strip(ax, reading: TakeReading, lo: float, hi: float, floor: float) -> None:
    numbers, signal = reading.numbers, reading.signal
    inside = (numbers >= lo) & (numbers < hi)
    for c in range(3):
        ax.plot(numbers[inside], np.maximum(signal[inside, c], floor), color=_COLOURS[c], lw=0.7)
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(floor, float(np.max(signal)) * 2)
    for patch in reading.sequence.of_kind("sync"):
        a, b = (
            float(v) for v in reading.alignment.to_camera(np.array([patch.first, patch.last + 1.0]))
        )
        if b > lo and a < hi:
            ax.axvspan(a, b, color="#ffe680", alpha=0.5, lw=0)
    for k, reading_patch in enumerate(reading.patches.values()):
        a, b = reading_patch.window
        if b < lo or a >= hi:
            continue
        ax.axvspan(a, b, color=("#d8d8d8", "#ececec")[k % 2], lw=0)
        ax.text(
            (a + b) / 2,
            floor * 1.5,
            reading_patch.name,
            rotation=90,
            fontsize=4.5,
            ha="center",
            va="bottom",
        )
        kept = np.isin(numbers, reading_patch.frames)
        ax.plot(
            numbers[kept], np.maximum(np.max(signal[kept], axis=1), floor), ".", ms=1.5, color="k"
        )
        bad = np.isin(numbers, reading_patch.rejected)
        if np.any(bad):
            ax.plot(
                numbers[bad], np.maximum(np.max(signal[bad], axis=1), floor), "x", ms=3, color="r"
            )
    ax.tick_params(labelsize=6)


def write_contact_sheet(reading: TakeReading, path: str | Path) -> None:
    """Draw the contact sheet of ``reading`` into ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    first, last = float(reading.numbers[0]), float(reading.numbers[-1]) + 1
    strips = max(1, int(np.ceil((last - first) / _FRAMES_PER_STRIP)))
    figure = Figure(figsize=(16, 4 + 1.8 * strips), dpi=100)
    grid = figure.add_gridspec(1 + strips, 1, height_ratios=[2.2] + [1] * strips)
    _draw_frame(figure.add_subplot(grid[0]), reading)
    floor = 1e-4 * float(np.max(reading.signal))
    width = (last - first) / strips
    for k in range(strips):
        _draw_strip(
            figure.add_subplot(grid[1 + k]),
            reading,
            first + k * width,
            first + (k + 1) * width,
            floor,
        )
    a = reading.alignment
    steps = "; ".join(
        f"{abs(n)} frame(s) {'dropped' if n < 0 else 'repeated'} near {T:g}" for T, n in a.steps
    )
    figure.suptitle(
        f"{Path(str(reading.take.frames)).name}: {len(reading.numbers)} frames; "
        f"{a.rate:.5f} camera frames per player frame; sync marks {len(a.marks_found)} of "
        f"{a.marks_expected}; {a.changes_used} patch changes timed"
        + (f"; {steps}" if steps else ""),
        fontsize=9,
    )
    figure.savefig(str(path), format="png", metadata={"Software": None})
