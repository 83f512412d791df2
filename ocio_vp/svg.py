"""A small SVG writer for every figure ocio_vp draws (the report's, the take's contact sheet):
shapes, text, embedded images, axes with nice ticks (against matplotlib: docs/report.md).

One user unit is one point (``width``/``height`` are the figure's pixels at ``dpi``); numbers are
rounded to 0.01 and attributes written in a fixed order, so the same input gives the same bytes;
every string goes through :func:`escape`; colours are 8-bit sRGB hex (:func:`hex_colour`).
"""

from __future__ import annotations

import base64
import functools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import overload

import numpy as np

__all__ = [
    "FONT",
    "PT",
    "Axes",
    "Canvas",
    "data_limits",
    "escape",
    "hex_colour",
    "hex_colours",
    "nice_ticks",
    "num",
    "subplot_boxes",
    "tick_labels",
]

#: User units per inch: one unit is one point.
PT = 72.0
FONT = "DejaVu Sans, Verdana, Arial, Helvetica, sans-serif"
#: For str.translate: markup to entities, tab and line breaks to character references,
#: characters XML 1.0 forbids and lone surrogates dropped.
_ESCAPES: dict[int, str | None] = {
    **dict.fromkeys([*range(0x00, 0x09), 0x0B, 0x0C, *range(0x0E, 0x20), 0xFFFE, 0xFFFF]),
    **dict.fromkeys(range(0xD800, 0xE000)),
    **{
        ord(k): v
        for k, v in {
            "&": "&amp;",
            "<": "&lt;",
            ">": "&gt;",
            '"': "&quot;",
            "'": "&#39;",
            "\t": "&#9;",
            "\n": "&#10;",
            "\r": "&#13;",
        }.items()
    },
}


def escape(text: object) -> str:
    """``text`` as XML character data or a double-quoted attribute value (:data:`_ESCAPES`).

    >>> escape('a < b & "c"')
    'a &lt; b &amp; &quot;c&quot;'
    """
    return str(text).translate(_ESCAPES)


def num(value: float | np.floating) -> str:
    """A coordinate rounded to 0.01, without trailing zeros (``-0`` written as ``0``).

    >>> num(1.0), num(2.345678), num(-0.001), num(10.5)
    ('1', '2.35', '0', '10.5')
    """
    text = f"{float(value):.2f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def hex_colour(rgb: Sequence[float] | np.ndarray) -> str:
    """``#rrggbb`` of sRGB-encoded values, clipped to [0, 1] and rounded to 8 bits.

    >>> hex_colour([1.0, 0.5, -0.2])
    '#ff8000'
    """
    return hex_colours(np.reshape(rgb, (1, 3)))[0]


def hex_colours(rgb: np.ndarray) -> list[str]:
    """:func:`hex_colour` of every row of an (n, 3) array (one numpy pass).

    >>> hex_colours(np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    ['#000000', '#ffffff']
    """
    levels = np.rint(255 * np.clip(np.asarray(rgb, dtype=np.float64), 0.0, 1.0)).astype(int)
    return [f"#{r:02x}{g:02x}{b:02x}" for r, g, b in levels.tolist()]


def nice_ticks(low: float, high: float, max_ticks: int = 7) -> np.ndarray:
    """Tick values in ``[low, high]`` at multiples of 1, 2 or 5 times a power of ten.

    The smallest such step giving at most ``max_ticks`` ticks (the next smaller where that
    leaves fewer than two); none for an empty or non-finite range.

    >>> nice_ticks(0, 10).tolist()
    [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]
    >>> nice_ticks(-0.03, 0.26).tolist()
    [0.0, 0.05, 0.1, 0.15, 0.2, 0.25]
    """
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low or max_ticks < 2:
        return np.array([])
    raw = (high - low) / (max_ticks - 1)
    power = 10.0 ** math.floor(math.log10(raw))
    candidates = []
    for factor in (1.0, 2.0, 5.0, 10.0):
        step = factor * power
        first, last = math.ceil(low / step - 1e-9), math.floor(high / step + 1e-9)
        candidates.append((step, first, last))
        if last - first + 1 <= max_ticks:
            break
    if last - first < 1 and len(candidates) > 1:
        step, first, last = candidates[-2]
    ticks = np.arange(first, last + 1) * step
    return np.round(ticks, max(0, 1 - math.floor(math.log10(step)))) + 0.0  # no -0.0


def tick_labels(ticks: np.ndarray) -> list[str]:
    """Labels with the decimals the step needs (``0.05`` -> 2), ``-0`` written as ``0``.

    >>> tick_labels(np.array([-0.1, 0.0, 0.1]))
    ['\u22120.1', '0.0', '0.1']
    """
    if len(ticks) < 2:
        return [f"{t:g}" for t in ticks]
    step = float(np.min(np.diff(ticks)))
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    labels = [f"{t:.{decimals}f}" for t in ticks]
    # No "-0"; a true minus sign (U+2212) for negative values, as typeset figures have.
    return [
        label.lstrip("-") if not float(label) else label.replace("-", "\u2212") for label in labels
    ]


@functools.cache
def _name(key: str) -> str:
    """A keyword argument as an attribute name (``class_`` -> ``class``, ``data_x`` -> ``data-x``)."""
    return key.rstrip("_").replace("_", "-")


def _attrs(attributes: dict[str, object]) -> str:
    out = []
    for key, value in attributes.items():
        if value is None:
            continue
        text = num(value) if isinstance(value, float | np.floating) else escape(value)
        out.append(f' {_name(key)}="{text}"')
    return "".join(out)


class Canvas:
    """One SVG document, written in drawing order; ``write`` puts it on disk."""

    def __init__(self, width: float, height: float, dpi: float, *, label: str = "") -> None:
        """A ``width`` x ``height`` inch figure shown at ``dpi`` pixels per inch."""
        self.width, self.height = width * PT, height * PT
        self.pixels = (width * dpi, height * dpi)
        self.label = label
        self._defs: dict[str, str] = {}
        self._parts: list[str] = []

    def element(self, tag: str, text: str | None = None, /, **attributes: object) -> None:
        """``<tag attributes/>`` or with escaped ``text`` content."""
        attrs = _attrs(attributes)
        if text is None:
            self._parts.append(f"<{tag}{attrs}/>")
        else:
            self._parts.append(f"<{tag}{attrs}>{escape(text)}</{tag}>")

    def open(self, tag: str = "g", **attributes: object) -> None:
        """Start a group (close it with :meth:`close`)."""
        self._parts.append(f"<{tag}{_attrs(attributes)}>")

    def close(self, tag: str = "g") -> None:
        """End the group :meth:`open` started."""
        self._parts.append(f"</{tag}>")

    def rect(self, x: float, y: float, w: float, h: float, **attributes: object) -> None:
        """A rectangle with its top left corner at (x, y)."""
        self.element("rect", x=float(x), y=float(y), width=float(w), height=float(h), **attributes)

    def circle(self, cx: float, cy: float, r: float, **attributes: object) -> None:
        """A circle of radius ``r`` centred on (cx, cy)."""
        self.element("circle", cx=float(cx), cy=float(cy), r=float(r), **attributes)

    def line(self, x1: float, y1: float, x2: float, y2: float, **attributes: object) -> None:
        """A straight line from (x1, y1) to (x2, y2)."""
        self.element("line", x1=float(x1), y1=float(y1), x2=float(x2), y2=float(y2), **attributes)

    def polyline(self, xs: Iterable[float], ys: Iterable[float], **attributes: object) -> None:
        """An open, unfilled line through the points (xs[i], ys[i])."""
        points = " ".join(f"{num(x)},{num(y)}" for x, y in zip(xs, ys, strict=True))
        self.element("polyline", points=points, fill="none", **attributes)

    def image(self, x: float, y: float, w: float, h: float, png: bytes) -> None:
        """A PNG drawn into the box (x, y, w, h), pixels unsmoothed, embedded in the file."""
        data = base64.b64encode(png).decode("ascii")
        self._parts.append(
            f'<image x="{num(x)}" y="{num(y)}" width="{num(w)}" height="{num(h)}" '
            f'image-rendering="pixelated" href="data:image/png;base64,{data}"/>'
        )

    def text(
        self,
        x: float,
        y: float,
        text: str,
        *,
        size: float = 10.0,
        anchor: str = "middle",
        valign: str = "baseline",
        rotate: float = 0.0,
        **attributes: object,
    ) -> None:
        """Text at (x, y); ``valign`` "top"/"center"/"baseline"; lines split at ``\\n``."""
        lines = str(text).split("\n")
        shift = {"top": 0.8, "center": 0.35 - 0.6 * (len(lines) - 1), "baseline": 0.0}[valign]
        transform = f"rotate({num(rotate)} {num(x)} {num(y)})" if rotate else None
        head = _attrs(
            {
                "x": float(x),
                "y": float(y),
                "dy": f"{shift:g}em" if shift else None,
                "font-size": float(size),
                "text-anchor": anchor,
                "transform": transform,
                **attributes,
            }
        )
        if len(lines) == 1:
            self._parts.append(f"<text{head}>{escape(lines[0])}</text>")
            return
        spans = "".join(
            f'<tspan x="{num(x)}"{"" if i == 0 else " dy=" + chr(34) + "1.2em" + chr(34)}>'
            f"{escape(line)}</tspan>"
            for i, line in enumerate(lines)
        )
        self._parts.append(f"<text{head}>{spans}</text>")

    def hatch(self, colour: str) -> str:
        """A fill of ``colour`` diagonal hatching on white (defined once); its ``url(#...)``."""
        key = f"hatch-{colour.lstrip('#')}"
        self._defs.setdefault(
            key,
            f'<pattern id="{escape(key)}" patternUnits="userSpaceOnUse" width="5" height="5">'
            f'<rect width="5" height="5" fill="white"/>'
            f'<path d="M-1,1L1,-1M0,5L5,0M4,6L6,4" stroke="{escape(colour)}" '
            f'stroke-width="0.8"/></pattern>',
        )
        return f"url(#{key})"

    def clip(self, key: str, x: float, y: float, w: float, h: float) -> str:
        """A rectangular clip path (defined once per ``key``); its ``url(#...)``."""
        box = _attrs({"x": float(x), "y": float(y), "width": float(w), "height": float(h)})
        self._defs.setdefault(key, f'<clipPath id="{escape(key)}"><rect{box}/></clipPath>')
        return f"url(#{escape(key)})"

    def tostring(self) -> str:
        """The document: a white ground, the definitions (hatches, clips), then the drawing."""
        head = _attrs(
            {
                "xmlns": "http://www.w3.org/2000/svg",
                "width": float(self.pixels[0]),
                "height": float(self.pixels[1]),
                "viewBox": f"0 0 {num(self.width)} {num(self.height)}",
                "font-family": FONT,
                "role": "img",
                "aria-label": self.label or None,
            }
        )
        defs = "<defs>" + "".join(self._defs[k] for k in sorted(self._defs)) + "</defs>"
        background = f'<rect width="{num(self.width)}" height="{num(self.height)}" fill="white"/>'
        body = "\n".join(self._parts)
        return f"<svg{head}>\n{defs}\n{background}\n{body}\n</svg>\n"

    def write(self, path: Path) -> Path:
        """Write the document as UTF-8 to ``path``; returns the path."""
        path = Path(path)
        path.write_text(self.tostring(), encoding="utf-8")
        return path


def subplot_boxes(
    canvas: Canvas,
    rows: int,
    columns: int,
    *,
    left: float,
    right: float,
    top: float,
    bottom: float,
    wspace: float = 0.2,
    hspace: float = 0.2,
) -> list[tuple[float, float, float, float]]:
    """Boxes ``(x, y, w, h)`` in reading order, placed like matplotlib's ``subplots_adjust``
    (fractions of the figure from its left and bottom edges; gaps as fractions of a box)."""
    width = (right - left) * canvas.width / (columns + wspace * (columns - 1))
    height = (top - bottom) * canvas.height / (rows + hspace * (rows - 1))
    x0, y0 = left * canvas.width, (1 - top) * canvas.height
    return [
        (x0 + c * width * (1 + wspace), y0 + r * height * (1 + hspace), width, height)
        for r in range(rows)
        for c in range(columns)
    ]


def data_limits(values: Iterable[float], *, zero: bool = False) -> tuple[float, float]:
    """The finite values' range with 5% margins (from 0 when ``zero``: bars stand on it)."""
    flat = np.ravel(np.asarray(values, dtype=np.float64))
    finite = flat[np.isfinite(flat)]
    low = float(finite.min()) if finite.size else 0.0
    high = float(finite.max()) if finite.size else 1.0
    if zero:
        low, high = min(low, 0.0), max(high, 0.0)
    if high - low < 1e-12:
        low, high = low - max(abs(low), 1.0) / 2, high + max(abs(high), 1.0) / 2
    pad = 0.05 * (high - low)
    return (0.0 if zero and low == 0 else low - pad), high + pad


@dataclass
class Axes:
    """A plot area: data ``xlim``/``ylim`` mapped onto the box ``(x, y, w, h)`` of a canvas."""

    canvas: Canvas
    box: tuple[float, float, float, float]
    xlim: tuple[float, float]
    ylim: tuple[float, float]
    name: str = "axes"

    @overload
    def x(self, value: float) -> float: ...
    @overload
    def x(self, value: Sequence[float] | np.ndarray) -> np.ndarray: ...
    def x(self, value: float | Sequence[float] | np.ndarray) -> float | np.ndarray:
        """Canvas x of data ``value`` (a number, or an array of them)."""
        x0, _, w, _ = self.box
        value = value if isinstance(value, float | int) else np.asarray(value, dtype=np.float64)
        return x0 + (value - self.xlim[0]) * w / (self.xlim[1] - self.xlim[0])

    @overload
    def y(self, value: float) -> float: ...
    @overload
    def y(self, value: Sequence[float] | np.ndarray) -> np.ndarray: ...
    def y(self, value: float | Sequence[float] | np.ndarray) -> float | np.ndarray:
        """Canvas y of data ``value``; SVG's y grows downwards."""
        _, y0, _, h = self.box
        value = value if isinstance(value, float | int) else np.asarray(value, dtype=np.float64)
        return y0 + h - (value - self.ylim[0]) * h / (self.ylim[1] - self.ylim[0])

    def clip(self) -> str:
        """A clip path of the plot area (for bars the axis cuts); its ``url(#...)``."""
        return self.canvas.clip(f"clip-{self.name}", *self.box)

    def frame(self) -> None:
        """The box outline (drawn last, over the data, like matplotlib's spines)."""
        self.canvas.rect(*self.box, fill="none", stroke="black", stroke_width=0.8)

    def yticks(self, *, grid: bool = True, size: float = 10.0) -> None:
        """Nice ticks on the y axis with labels, and light grid lines across the box."""
        x0, _, w, _ = self.box
        ticks = nice_ticks(*self.ylim)
        for value, label in zip(ticks, tick_labels(ticks), strict=True):
            y = float(self.y(value))
            self.canvas.open(class_="ytick", data_axes=self.name)
            if grid:
                self.canvas.line(
                    x0, y, x0 + w, y, stroke="#b0b0b0", stroke_width=0.8, stroke_opacity=0.3
                )
            self.canvas.line(x0 - 3.5, y, x0, y, stroke="black", stroke_width=0.8, class_="tick")
            self.canvas.text(x0 - 5, y, label, size=size, anchor="end", valign="center")
            self.canvas.close()

    def xticks(
        self,
        values: Sequence[float] | np.ndarray | None = None,
        labels: Sequence[str] | None = None,
        *,
        grid: bool = False,
        size: float = 10.0,
        rotate: float = 0.0,
    ) -> None:
        """Ticks on the x axis: ``values`` with ``labels`` (nice ticks when not given)."""
        _, y0, _, h = self.box
        bottom = y0 + h
        if values is None:
            values = nice_ticks(*self.xlim)
            labels = tick_labels(np.asarray(values))
        for value, label in zip(values, labels or [""] * len(values), strict=True):
            x = float(self.x(value))
            self.canvas.open(class_="xtick", data_axes=self.name)
            if grid:
                self.canvas.line(
                    x, y0, x, bottom, stroke="#b0b0b0", stroke_width=0.8, stroke_opacity=0.3
                )
            self.canvas.line(
                x, bottom, x, bottom + 3.5, stroke="black", stroke_width=0.8, class_="tick"
            )
            if label:
                anchor = "end" if rotate else "middle"
                self.canvas.text(
                    x, bottom + 5, label, size=size, anchor=anchor, valign="top", rotate=-rotate
                )
            self.canvas.close()

    def title(self, text: str, *, size: float = 10.0) -> None:
        """Centred above the box; a multi-line title grows upwards."""
        x0, y0, w, _ = self.box
        lines = text.count("\n")
        self.canvas.text(
            x0 + w / 2,
            y0 - 6 - 1.2 * size * lines,
            text,
            size=size,
            class_="title",
            data_axes=self.name,
        )

    def ylabel(self, text: str, *, offset: float = 30.0, size: float = 10.0) -> None:
        """Rotated, ``offset`` points left of the box."""
        x0, y0, _, h = self.box
        self.canvas.text(x0 - offset, y0 + h / 2, text, size=size, rotate=-90, class_="ylabel")

    def xlabel(self, text: str, *, offset: float = 18.0, size: float = 10.0) -> None:
        """Centred, ``offset`` points below the box (below the tick labels)."""
        x0, y0, w, h = self.box
        self.canvas.text(
            x0 + w / 2, y0 + h + offset, text, size=size, valign="top", class_="xlabel"
        )

    def legend(
        self,
        entries: Sequence[tuple[str, dict[str, object]]],
        *,
        corner: str = "upper left",
        outside: bool = False,
        size: float = 8.0,
    ) -> None:
        """A legend box; each entry is ``(label, style)``: a ``fill`` swatch, or a ``stroke``
        line (with ``stroke_dasharray``), optionally ``marker`` True for a dot on it."""
        x0, y0, w, h = self.box
        row = 1.5 * size
        width = 2.8 * size + 0.58 * size * max(len(label) for label, _ in entries)
        height = row * len(entries) + 0.6 * size
        if outside:
            left, top = x0 + w + 0.01 * self.canvas.width, y0
        else:
            left = x0 + 6 if "left" in corner else x0 + w - 6 - width
            top = y0 + 6 if "upper" in corner else y0 + h - 6 - height
        canvas = self.canvas
        canvas.open(class_="legend", data_axes=self.name)
        canvas.rect(
            left,
            top,
            width,
            height,
            fill="white",
            fill_opacity=0.8,
            stroke="#cccccc",
            stroke_width=0.8,
            rx=2.0,
        )
        for i, (label, style) in enumerate(entries):
            y = top + 0.3 * size + row * (i + 0.5)
            sx = left + 0.4 * size
            if "fill" in style:
                canvas.rect(sx, y - 0.35 * size, 1.6 * size, 0.7 * size, **style)
            else:
                dots = style.get("marker")
                line = {k: v for k, v in style.items() if k != "marker"}
                if line.get("stroke_dasharray"):  # a dash centred on the marker, gaps beside
                    line["stroke_dashoffset"] = 4.33
                canvas.line(sx, y, sx + 1.6 * size, y, **line)
                if dots:
                    canvas.circle(sx + 0.8 * size, y, 1.4, fill=style["stroke"])
            canvas.text(left + 2.4 * size, y, label, size=size, anchor="start", valign="center")
        canvas.close()
