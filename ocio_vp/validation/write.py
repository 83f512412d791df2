"""Writing a validation: ``validation.json`` (its keys: docs/validation.md), ``index.html``
(with the take's contact sheet) and the terminal's lines, all from one
:class:`~ocio_vp.validation.compare.ValidationResult`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ocio_vp.formats.jsontypes import JsonMapping, JsonObject
from ocio_vp.plates.contact_sheet import SHEET
from ocio_vp.plates.take import TakeReading
from ocio_vp.validation.compare import ValidationResult
from ocio_vp.wall.encoding import encode

__all__ = ["VALIDATION_FORMAT", "summary_lines", "validation_document", "write_validation"]

VALIDATION_FORMAT = "ocio-vp/validation"


def label(patch) -> str:
    """How people read a patch: numbered from 1 on the chart, with its name (``'14 green'``);
    files keep the 0-based ``index``."""
    name = patch.name.partition(" (")[2][:-1]  # "patch 13 (green)" -> "green"
    return f"{patch.index + 1} {name}".strip()


def label_of(index: int, result: ValidationResult) -> str:
    """:func:`label` of the patch with chart index ``index``."""
    for p in result.patches:
        if p.index == index:
            return label(p)
    return str(index + 1)


def summary_lines(
    result: ValidationResult, reading: TakeReading, pulled: tuple[tuple[int, float], ...] = ()
) -> list[str]:
    """What ``ocio-vp validate`` prints: the figures, the verdict, what was pulled into the
    wall's gamut (``pulled``: the sequence's ``validation.pulled``) or left out."""
    worst = result.worst
    how = "after post-correction" if result.post_corrected else "as recorded (N not solved: no Q)"
    lines = [
        f"validation of {result.environment} (stage {result.stage}): {len(result.judged)} of "
        f"{len(result.patches)} chart patches judged in camera {how}, {len(reading.numbers)} "
        "frames",
        f"  ΔE2000 mean {result.mean:.2f}, p95 {result.p95:.2f}, worst {worst.delta_e:.2f} "
        f"({label(worst)})"
        + (
            f"; the solve's own model predicted mean {result.predicted_mean:.2f}"
            if result.predicted_mean is not None
            else ""
        ),
    ]
    verdict = "PASS" if result.passed else "FAIL"
    relation = "<=" if result.passed else ">"
    lines.append(
        f"  {verdict}: p95 {result.p95:.2f} {relation} {result.threshold:g} (threshold, "
        "docs/validation.md)"
    )
    if pulled:
        listed = ", ".join(f"{label_of(j, result)} {100 * k:.0f}%" for j, k in pulled)
        lines.append(
            f"  {len(pulled)} patch(es) need light outside the LEDs' gamut after N: shown and "
            f"judged pulled towards grey (saturation kept): {listed}"
        )
    hidden = [p for p in result.patches if not p.shown]
    if hidden:
        listed = ", ".join(f"{label(p)} {p.delta_e:.1f}/{p.expected_delta_e:.1f}" for p in hidden)
        lines.append(
            f"  {len(hidden)} patch(es) need light outside the wall's gamut at this exposure, not "
            f"judged (ΔE2000 measured/expected from the gamut alone): {listed}"
        )
    return lines


def validation_document(
    result: ValidationResult, reading: TakeReading, *, sources: JsonMapping
) -> JsonObject:
    """The ``validation.json`` document (plain types)."""
    worst = result.worst
    a = reading.alignment
    return {
        "format": VALIDATION_FORMAT,
        "version": 1,
        "environment": result.environment,
        "stage": result.stage,
        **sources,
        "metric": "CIE ΔE2000, intended white patch as reference white; " + result.xyz_description,
        "post_corrected": result.post_corrected,
        "threshold_p95": result.threshold,
        "passed": result.passed,
        "delta_e2000": {
            "mean": result.mean,
            "p95": result.p95,
            "max": worst.delta_e,
            "worst_patch": {"index": worst.index, "name": worst.name},
            "patches_judged": len(result.judged),
            "predicted_mean": result.predicted_mean,
        },
        "take": {
            "frames": len(reading.numbers),
            "region": list(reading.region),
            "camera_frames_per_player_frame": a.rate,
            "sync_marks_found": list(a.marks_found),
            "steps": [{"player_frame": T, "camera_frames": n} for T, n in a.steps],
            "contact_sheet": SHEET,
        },
        "patches": [
            {
                "index": p.index,
                "name": p.name,
                "intended": p.intended.tolist(),
                "measured": p.measured.tolist(),
                "corrected": p.corrected.tolist(),
                "delta_e2000": p.delta_e,
                "expected_delta_e2000": p.expected_delta_e,
                "shown": p.shown,
                "frames": p.frames,
            }
            for p in result.patches
        ],
    }


def _swatches(result: ValidationResult) -> str:
    """An SVG: per patch, the intended colour (top) and the post-corrected measurement
    (bottom), as sRGB through the same camera-to-display matrix, with its ΔE2000."""
    from ocio_vp.svg import escape, hex_colour

    intended = np.array([p.intended for p in result.patches])
    matrix = result.display_matrix
    scale = 0.9 / max(float(np.max(intended @ matrix.T)), 1e-12)
    columns, size = 6, 70
    rows = -(-len(result.patches) // columns)
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{columns * (size + 10)}" '
        f'height="{rows * (size + 26)}" font-family="sans-serif" font-size="11">'
    ]
    for k, p in enumerate(result.patches):
        x, y = (k % columns) * (size + 10), (k // columns) * (size + 26)
        top = encode(np.clip(matrix @ p.intended * scale, 0.0, 1.0), "srgb")
        bottom = encode(np.clip(matrix @ p.corrected * scale, 0.0, 1.0), "srgb")
        parts.append(
            f'<rect x="{x}" y="{y}" width="{size}" height="{size // 2}" fill="{hex_colour(top)}"/>'
        )
        parts.append(
            f'<rect x="{x}" y="{y + size // 2}" width="{size}" height="{size // 2}" fill="{hex_colour(bottom)}"/>'
        )
        text = f"{p.index + 1}: {p.delta_e:.2f}" + ("" if p.shown else " (not shown)")
        parts.append(f'<text x="{x}" y="{y + size + 14}">{escape(text)}</text>')
    parts.append("</svg>")
    return "\n".join(parts)


def _html(result: ValidationResult, reading: TakeReading, lines: list[str]) -> str:
    from markupsafe import Markup

    from ocio_vp.exports.templating import html_template

    return html_template("validation.html.j2").render(
        result=result,
        lines=lines,
        swatches=Markup(_swatches(result)),
        sheet=SHEET,
        verdict="PASS" if result.passed else "FAIL",
    )


def write_validation(
    result: ValidationResult,
    reading: TakeReading,
    folder: str | Path,
    *,
    sources: JsonMapping,
    pulled: tuple[tuple[int, float], ...] = (),
) -> list[str]:
    """Write ``validation.json``, ``index.html`` and the contact sheet into ``folder`` (new or
    staged); returns the terminal's lines."""
    from ocio_vp.plates.contact_sheet import write_contact_sheet

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lines = summary_lines(result, reading, pulled)
    document = validation_document(result, reading, sources=sources)
    if pulled:
        document["pulled_into_gamut"] = {str(j): k for j, k in pulled}
    (folder / "validation.json").write_text(
        json.dumps(document, indent=2, allow_nan=False) + "\n", "utf-8"
    )
    write_contact_sheet(reading, folder / SHEET)
    (folder / "index.html").write_text(_html(result, reading, lines), "utf-8")
    return lines
