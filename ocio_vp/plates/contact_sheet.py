"""The take's contact sheet (``<measurements>.overlays/take.svg``, drawn with :mod:`ocio_vp.svg`;
docs/capture.md, *The take*, step 5): which frames went to which patch, and the region measured.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.plates.take import TakeReading, rows_read
from ocio_vp.svg import Axes, Canvas

__all__ = ["SHEET", "write_contact_sheet"]

#: The contact sheet's file name (beside the overlays of ``measure``, in a validation folder).
SHEET = "take.svg"

_THUMB_WIDTH = 640
_FRAMES_PER_STRIP = 400
_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")
#: Layout in points: margins of the page, gap between panels, the frame's share of the height.
_LEFT, _RIGHT, _TOP, _BOTTOM, _GAP, _FRAME_SHARE = 50.0, 20.0, 45.0, 30.0, 28.0, 2.2


def _thumbnail(reading: TakeReading) -> tuple[np.ndarray, int, int]:
    """A frame of the take, subsampled to at most 640 pixels wide: (image, step, frame)."""
    from ocio_vp.plates.overlay import tone_map

    brightest = max(reading.patches.values(), key=lambda p: float(np.max(p.mean)))
    frame = brightest.frames[len(brightest.frames) // 2]
    index = int(np.flatnonzero(reading.numbers == frame)[0])
    info = reading.info
    step = max(1, -(-info.width // _THUMB_WIDTH))
    rows = []
    read = reading.frame_reader(index)
    for y in range(info.y, info.y + info.height, step * 64):
        y1 = min(y + step * 64, info.y + info.height)
        band = read((info.x, y, info.x + info.width, y1))
        rows.append(band[::step, ::step])
    image = np.concatenate(rows, axis=0)
    return tone_map(image, white=float(np.max(brightest.mean)) * 1.1), step, frame


def _png(image: np.ndarray) -> bytes:
    from ocio_vp.plates.overlay import write_png

    with tempfile.TemporaryDirectory(prefix="ocio-vp-sheet-") as folder:
        path = Path(folder) / "frame.png"
        write_png(path, image)
        return path.read_bytes()


def _draw_frame(
    canvas: Canvas, box: tuple[float, float, float, float], reading: TakeReading
) -> None:
    image, step, frame = _thumbnail(reading)
    bx, by, bw, bh = box
    scale = min(bw / image.shape[1], bh / image.shape[0])  # points per thumbnail pixel
    w, h = image.shape[1] * scale, image.shape[0] * scale
    x, y = bx + (bw - w) / 2, by + (bh - h) / 2
    canvas.image(x, y, w, h, _png(image))
    x0, y0, x1, y1 = reading.region
    ox, oy = reading.info.x, reading.info.y
    k = scale / step  # points per frame pixel
    canvas.rect(
        x + (x0 - ox) * k, y + (y0 - oy) * k, (x1 - x0) * k, (y1 - y0) * k,
        fill="none", stroke="#00e000", stroke_width=1.5, class_="region",
    )  # fmt: skip
    for ya, yb in rows_read(reading.info, reading.region, reading.movie)[1]:
        row = y + ((ya + yb) / 2 - oy) * k
        canvas.line(x + (x0 - ox) * k, row, x + (x1 - ox) * k, row, stroke="#ffd000",
                    stroke_width=0.6, class_="row-read")  # fmt: skip
    how = "found automatically" if reading.region_found else "given"
    canvas.text(
        x + w / 2, y - 6, f"frame {frame}: wall region {list(reading.region)} ({how}); "
        "yellow: rows read", size=8,
    )  # fmt: skip


@dataclass(frozen=True)
class _Traces:
    """What every strip draws, computed once for the whole take: log10 R, G, B per frame and
    their maximum, each patch's frames averaged and left out (masks), the sync marks' spans."""

    log: np.ndarray
    top: np.ndarray
    kept: list[np.ndarray]
    rejected: list[np.ndarray]
    syncs: list[tuple[float, float]]


def _traces(reading: TakeReading, floor: float) -> _Traces:
    log = np.log10(np.maximum(reading.signal, floor))
    patches = reading.patches.values()
    syncs = [
        tuple(float(v) for v in reading.alignment.to_camera(np.array([m.first, m.last + 1.0])))
        for m in reading.sequence.of_kind("sync")
    ]
    return _Traces(
        log,
        np.max(log, axis=1),
        [np.isin(reading.numbers, p.frames) for p in patches],
        [np.isin(reading.numbers, p.rejected) for p in patches],
        syncs,  # type: ignore[arg-type]
    )


def _spans(axes: Axes, reading: TakeReading, syncs: list[tuple[float, float]]) -> None:
    """The sync marks (yellow) and the measured patches (grey, alternating) behind the data."""
    lo, hi = axes.xlim
    _, y0, _, h = axes.box
    for a, b in syncs:
        if b > lo and a < hi:
            a, b = max(a, lo), min(b, hi)
            axes.canvas.rect(axes.x(a), y0, axes.x(b) - axes.x(a), h, fill="#ffe680",
                             fill_opacity=0.5, class_="sync")  # fmt: skip
    for k, patch in enumerate(reading.patches.values()):
        a, b = patch.window
        if b < lo or a >= hi:
            continue
        a, b = max(a, lo), min(b, hi)
        axes.canvas.rect(axes.x(a), y0, axes.x(b) - axes.x(a), h,
                         fill=("#d8d8d8", "#ececec")[k % 2], class_="patch")  # fmt: skip
        axes.canvas.text(axes.x((a + b) / 2), y0 + h - 3, patch.name, size=4.5,
                         anchor="start", valign="center", rotate=-90)  # fmt: skip


def _draw_strip(axes: Axes, reading: TakeReading, traces: _Traces) -> None:
    """One strip of the take's signal (log10 on the axes' linear scale)."""
    lo, hi = axes.xlim
    numbers, log, top = reading.numbers, traces.log, traces.top
    inside = (numbers >= lo) & (numbers < hi)
    _spans(axes, reading, traces.syncs)
    clip = axes.clip()
    for c in range(3):
        axes.canvas.polyline(axes.x(numbers[inside]), axes.y(log[inside, c]),
                             stroke=_COLOURS[c], stroke_width=0.7, clip_path=clip)  # fmt: skip
    for kept, bad in zip(traces.kept, traces.rejected, strict=True):
        for x, y in zip(axes.x(numbers[inside & kept]), axes.y(top[inside & kept]), strict=True):
            axes.canvas.circle(x, y, 0.75, fill="black", class_="kept")
        for x, y in zip(axes.x(numbers[inside & bad]), axes.y(top[inside & bad]), strict=True):
            axes.canvas.text(x, y, "\u00d7", size=6, valign="center", fill="red", class_="rejected")
    x0, _, _, _ = axes.box
    for decade in range(math.ceil(axes.ylim[0]), math.floor(axes.ylim[1]) + 1):
        y = float(axes.y(float(decade)))
        axes.canvas.line(x0 - 3.5, y, x0, y, stroke="black", stroke_width=0.8)
        axes.canvas.text(x0 - 5, y, f"1e{decade}", size=6, anchor="end", valign="center")
    axes.xticks(size=6)
    axes.frame()


def write_contact_sheet(reading: TakeReading, path: str | Path) -> None:
    """Draw the contact sheet of ``reading`` into ``path`` (SVG)."""
    first, last = float(reading.numbers[0]), float(reading.numbers[-1]) + 1
    strips = max(1, int(np.ceil((last - first) / _FRAMES_PER_STRIP)))
    canvas = Canvas(16, 4 + 1.8 * strips, 100, label="contact sheet of the take")
    width = canvas.width - _LEFT - _RIGHT
    unit = (canvas.height - _TOP - _BOTTOM - _GAP * strips) / (_FRAME_SHARE + strips)
    _draw_frame(canvas, (_LEFT, _TOP, width, _FRAME_SHARE * unit), reading)
    floor = 1e-4 * float(np.max(reading.signal))
    ylim = (math.log10(floor), math.log10(float(np.max(reading.signal)) * 2))
    span = (last - first) / strips
    traces = _traces(reading, floor)
    for k in range(strips):
        y = _TOP + (_FRAME_SHARE + k) * unit + _GAP * (k + 1)
        xlim = (first + k * span, first + (k + 1) * span)
        axes = Axes(canvas, (_LEFT, y, width, unit), xlim, ylim, name=f"strip{k}")
        _draw_strip(axes, reading, traces)
    a = reading.alignment
    steps = "; ".join(
        f"{abs(n)} frame(s) {'dropped' if n < 0 else 'repeated'} near {T:g}" for T, n in a.steps
    )
    canvas.text(
        canvas.width / 2,
        18,
        f"{Path(str(reading.take.frames)).name}: {len(reading.numbers)} frames; "
        f"{a.rate:.5f} camera frames per player frame; sync marks {len(a.marks_found)} of "
        f"{a.marks_expected}; {a.changes_used} patch changes timed"
        + (f"; {steps}" if steps else ""),
        size=9,
    )
    canvas.write(Path(path))
