"""Read the report's SVG figures back: what a reader sees, from the file alone.

Values come from the drawing, never from the code that drew it: a bar's height is converted
through the axis scale that the axis's own tick labels define (pixel position of each tick mark
against the number printed beside it), colours are parsed from the fill attribute.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np

SVG = "{http://www.w3.org/2000/svg}"


def load(path: Path) -> ET.Element:
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG}svg", root.tag
    return root


def find(root: ET.Element, tag: str, **data: str) -> list[ET.Element]:
    """Elements ``tag`` whose attributes match ``data`` (``class_`` -> ``class``,
    ``data_patch`` -> ``data-patch``)."""
    wanted = {k.rstrip("_").replace("_", "-"): v for k, v in data.items()}
    return [e for e in root.iter(f"{SVG}{tag}") if all(e.get(k) == v for k, v in wanted.items())]


def text_of(element: ET.Element) -> str:
    """A <text>'s content, its <tspan> lines joined with newlines."""
    spans = element.findall(f"{SVG}tspan")
    return "\n".join(s.text or "" for s in spans) if spans else (element.text or "")


def number(label: str) -> float:
    return float(label.replace("\u2212", "-"))


def axis_scale(root: ET.Element, axes: str, axis: str = "y") -> tuple[Callable, float]:
    """(pixel -> value, value units per pixel) of one axis, fitted on its labelled ticks.

    Asserts the ticks are evenly spaced as labelled (a straight line through every tick).
    """
    pixels, values = [], []
    for group in find(root, "g", class_=f"{axis}tick", data_axes=axes):
        (mark,) = [e for e in group.iter(f"{SVG}line") if e.get("class") == "tick"]
        labels = list(group.iter(f"{SVG}text"))
        if not labels:
            continue
        pixels.append(float(mark.get("y1" if axis == "y" else "x1")))
        values.append(number(text_of(labels[0])))
    assert len(pixels) >= 2, f"{axes}: fewer than 2 labelled {axis} ticks"
    slope, intercept = np.polyfit(pixels, values, 1)
    fitted = slope * np.array(pixels) + intercept
    np.testing.assert_allclose(fitted, values, atol=0.02 * abs(slope) + 1e-12)
    return (lambda p: slope * np.asarray(p, dtype=np.float64) + intercept), abs(float(slope))


def bar_height(rect: ET.Element, scale: Callable) -> float:
    """Value at the bar's top minus value at its bottom."""
    y, h = float(rect.get("y")), float(rect.get("height"))
    return float(scale(y) - scale(y + h))


def bar_base(rect: ET.Element, scale: Callable) -> float:
    return float(scale(float(rect.get("y")) + float(rect.get("height"))))


def rgb(fill: str) -> np.ndarray:
    """``#rrggbb`` -> (3,) in [0, 1]."""
    assert len(fill) == 7 and fill.startswith("#"), fill
    return np.array([int(fill[i : i + 2], 16) for i in (1, 3, 5)]) / 255.0


def points(polyline: ET.Element) -> np.ndarray:
    """(n, 2) pixel points of a <polyline>."""
    return np.array([[float(v) for v in p.split(",")] for p in polyline.get("points").split()])
