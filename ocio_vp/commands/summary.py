"""What ``solve`` and ``demo`` print: one screen a stage engineer reads between takes.

The stage and the wall's signal once; one line of figures per environment
(:func:`ocio_vp.calibration.diagnostics.summary_errors`, as the report's); each distinct note
once on stdout; every warning once on stderr, with the environments it concerns. No numpy at
import.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, TextIO

if TYPE_CHECKING:
    from ocio_vp.formats.diagnostics import Diagnostics
    from ocio_vp.formats.solution import Solution

__all__ = ["SUMMARY_COLUMNS", "model_words", "print_summary", "summary_lines", "summary_row"]

#: Column headers of the one terminal table.
SUMMARY_COLUMNS = (
    "environment",
    "model",
    "cond(Q)",
    "N",
    "lit M>M+Q",
    "shown M>N+Q",
    "CV",
    "LEDs in frame",
    "skin",
    "drive<0",
    "clipped",
)

LEGEND = (
    "errors in % of the target white (mean |camera RGB - target| over R, G, B): lit = the chart "
    "lit by the wall, through M then after Q;\n  shown = the background in camera, through M "
    "then N + offset and Q; CV = leave-one-patch-out after Q ('-': not given by the method);\n"
    "  LEDs in frame = p95 ΔE2000 by which Q changes the wall's own LEDs seen in frame "
    "(least squares in brackets): a Q fitted to reflective colours moves saturated emitters "
    "a lot,\n  tens to ~140 on narrow-band LEDs even when the stage is healthy; it matters only "
    "with LEDs, screens or practicals in frame: then solve --protect-emitters;\n  skin = "
    "expected mean ΔE2000 on skin of every lightness (the chart's skin samples), and its ratio "
    "to least squares'."
)

#: The model in a few words, by the correction's kind.
_KIND_WORDS = {"root-polynomial": "root-polynomial, bounded", "rank-deficient": "no inverse"}


def model_words(solution: Solution) -> str:
    """The model in a few words: ``auto: root-polynomial, bounded + emitter guard``."""
    from ocio_vp.model.correction import ProtectedCorrection, unprotected

    correction = solution.correction
    protected = isinstance(correction, ProtectedCorrection)
    inner = unprotected(correction)
    model = solution.model
    words = _KIND_WORDS.get(inner.kind)
    if words is None or model.startswith("rank-"):
        text = model
    elif model.startswith(inner.kind):
        text = words
    else:
        text = f"{model}, {words}"
    if solution.method != model and not model.startswith(solution.method):
        text = f"{solution.method}: {text}"
    skin = solution.diagnostics.skin
    first = " (skin first)" if skin is not None and skin.priority == "skin" else ""
    return text + first + (" + emitter guard" if protected else "")


def _percent(per_channel) -> str:
    if per_channel is None:
        return "-"
    return f"{100 * float(sum(per_channel)) / len(per_channel):.2f}%"


def _condition(value: float | None) -> str:
    from ocio_vp.calibration.equations import condition_text

    return condition_text(float(value)) if value is not None else "-"


def _n_state(solution: Solution) -> str:
    if solution.N is None:
        return "not solved"
    return "= M" if solution.diagnostics.N_equals_M else "solved"


def _delta_e(value: float) -> str:
    """A ΔE2000 figure; rounding (machine-dependent digits) printed as 0."""
    from ocio_vp.metrics import zero_below_rounding

    return f"{zero_below_rounding(value):.3g}"


def _leds(diagnostics: Diagnostics) -> str:
    figures = diagnostics.extrapolation
    if figures is None:
        return "-"
    return f"{_delta_e(figures.led_damage)} ({_delta_e(figures.led_damage_least_squares)})"


def summary_row(solution: Solution) -> tuple[str, ...]:
    """One environment's row (:func:`ocio_vp.calibration.diagnostics.summary_errors`)."""
    from ocio_vp.calibration.diagnostics import summary_errors

    d = solution.diagnostics
    errors = summary_errors(d)
    return (
        solution.environment,
        model_words(solution),
        _condition(d.cond_Q),
        _n_state(solution),
        f"{_percent(errors.lit_baseline)}>{_percent(errors.lit)}",
        f"{_percent(errors.shown_baseline)}>{_percent(errors.shown)}",
        _percent(errors.cross_validated),
        _leds(d),
        "-" if d.skin is None else d.skin.words(),
        ",".join("RGB"[c] for c in d.out_of_frustum_negative_channels or []) or "-",
        str(len(d.clipped_patches or [])),
    )


def _wall_line(solutions: Sequence[Solution]) -> str:
    """The stage's cond[SL] and the wall's signal, once."""
    first = solutions[0]
    from ocio_vp.wall.encoding import WallEncoding

    signal = WallEncoding.of(first.linearity).describe()
    return (
        f"stage {first.stage}: cond[SL] {_condition(first.diagnostics.cond_SL)}; "
        f"wall signal: {signal}"
    )


def _once(kind: str, found: Iterable[tuple[str, str]]) -> list[str]:
    """``kind: <environments>: <text>``, each text of the (text, environment) pairs once."""
    where: dict[str, list[str]] = {}
    for text, environment in found:
        where.setdefault(text, []).append(environment)
    return [f"{kind}: {', '.join(names)}: {text}" for text, names in where.items()]


def summary_lines(solutions: Sequence[Solution]) -> tuple[list[str], list[str]]:
    """(stdout lines, stderr lines) of the summary (module docstring)."""
    if not solutions:
        return [], []
    rows = [SUMMARY_COLUMNS, *(summary_row(s) for s in solutions)]
    widths = [max(len(r[i]) for r in rows) for i in range(len(SUMMARY_COLUMNS))]
    out = [_wall_line(solutions), LEGEND]
    out += ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    from ocio_vp.model.correction import ProtectedCorrection

    guarded = [s.correction for s in solutions if isinstance(s.correction, ProtectedCorrection)]
    if guarded:
        out.append(f"emitter guard: {guarded[0].protection()}")
    out += _skin_first_lines(solutions)
    out.append(
        "why each model: solution.json (diagnostics.model_reason) and the report; "
        "`ocio-vp report DIR` draws them"
    )
    warnings = ((str(w), s.environment) for s in solutions for w in s.diagnostics.warnings)
    return out + _gamut_notes(solutions), _once("warning", warnings)


def _skin_first_lines(solutions: Sequence[Solution]) -> list[str]:
    """With skin first, per environment: the background and the LEDs in frame beside the
    default's."""
    return [
        f"skin first: {s.environment}: {skin.default.words()}"
        for s in solutions
        if (skin := s.diagnostics.skin) is not None and skin.default is not None
    ]


def _gamut_notes(solutions: Sequence[Solution]) -> list[str]:
    """The LEDs' gamut (chart colours the wall cannot show in frustum, light outside it out of
    the frustum) and the assumptions, once per fact with the environments it concerns."""
    found = []
    for s in solutions:
        d = s.diagnostics
        ranges = d.in_frustum_drive_range
        below = None if ranges is None else ranges.below_zero
        with_M = None if ranges is None else ranges.below_zero_with_M
        if s.N is not None and below and with_M is not None and below > with_M:
            text = (
                f"{below} chart colour(s) need light outside the LEDs' gamut in-frustum after N "
                f"({with_M} with M): the wall shows them clipped, as any calibration of these "
                "LEDs would (validation shows them pulled into the gamut)"
            )
            found.append((text, s.environment))
        if d.out_of_frustum_negative_channels:
            text = (
                "this light is outside the LEDs' gamut (M w_avg has a negative channel): the "
                "wall lights the actors with the nearest colour it can make"
            )
            found.append((text, s.environment))
    # then the optional measurements the file did not give
    found += [(text, s.environment) for s in solutions for text in s.diagnostics.assumed or []]
    return _once("note", found)


def print_summary(
    solutions: Sequence[Solution], *, out: TextIO | None = None, err: TextIO | None = None
) -> None:
    """Print :func:`summary_lines`: the table on ``out`` (stdout), warnings on ``err``."""
    lines, warnings = summary_lines(solutions)
    print("\n".join(lines), file=out or sys.stdout)
    for line in warnings:
        print(line, file=err or sys.stderr)
