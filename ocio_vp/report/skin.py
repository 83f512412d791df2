"""The report's skin panel: what each solve expects faces to look like (``diagnostics.skin``,
:class:`ocio_vp.formats.skin.SkinFigures`): one table for all environments, facts per
environment. docs/skin.md checks these expectations against measured skin.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.skin_data import ITA_BANDS

if TYPE_CHECKING:
    from ocio_vp.formats.solution import Solution

__all__ = ["skin_facts", "skin_panel"]


def _pair(expected: float, least_squares: float) -> str:
    return f"{expected:.2f} ({least_squares:.2f})"


def skin_panel(solutions: Sequence[Solution]) -> JsonObject | None:
    """``{"bands": [...], "rows": [{"name", "key", "cells": [...], "all": str}]}`` for the
    template, bands lightest first; None when no solve has skin figures."""
    figures = [(s, f) for s in solutions if (f := s.diagnostics.skin) is not None]
    if not figures:
        return None
    present = {b.band for _, f in figures for b in f.bands}
    bands = [name for name, _ in ITA_BANDS if name in present]
    rows = []
    for solution, f in figures:
        by_band = {b.band: b for b in f.bands}
        rows.append(
            {
                "name": solution.environment,
                "priority": f.priority,
                "cells": [
                    _pair(by_band[b].expected, by_band[b].least_squares) if b in by_band else "-"
                    for b in bands
                ],
                "all": _pair(f.expected, f.least_squares),
                "ratio": f"{f.ratio:.2f}x",
                "chart": f"{f.chart_ratio:.2f}x",
            }
        )
    return {"bands": bands, "rows": rows}


def skin_facts(solution: Solution) -> list[tuple[str, str]]:
    """Per environment: the skin samples and, with skin first, the default's figures."""
    f = solution.diagnostics.skin
    if f is None:
        return []
    facts = [
        ("skin samples", f"{f.samples}: {f.source}"),
        (
            "skin (mean ΔE2000)",
            f"{f.expected:.3g} against least squares' {f.least_squares:.3g} ({f.ratio:.2f}x); "
            f"chart {f.chart:.3g} against {f.chart_least_squares:.3g} ({f.chart_ratio:.2f}x); "
            f"priority: {f.priority}",
        ),
    ]
    d = f.default
    if d is not None:
        facts.append(
            (
                "skin first against the default",
                f"the default ({d.model}) expects skin {d.expected:.3g}; {d.words()}; chart "
                f"colours N drives outside the wall's range {d.background_outside} (default "
                f"{d.background_outside_default})",
            )
        )
    return facts
