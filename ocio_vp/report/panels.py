"""The report's lines for a stage of several panel types: each type's share of the light, its
drive and colour spaces, the lit white against a calibration of the wall alone, and how the
in-frustum types match in camera (solution.json's ``panels`` and ``diagnostics.panels``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.formats.solution import Solution

__all__ = ["panel_facts"]


def _triple(values: ArrayLike) -> str:
    return ", ".join(f"{v:.4g}" for v in np.asarray(values, dtype=np.float64).ravel())


def _percent(values: ArrayLike) -> str:
    return " / ".join(f"{100 * v:.1f}%" for v in np.asarray(values, dtype=np.float64).ravel())


def panel_facts(solution: Solution) -> list[tuple[str, str]]:
    """(label, text) rows for the report's facts table; none for a stage of one panel type."""
    if not solution.panels:
        return []
    notes = solution.diagnostics.panels
    facts = []
    for name, panel in solution.panels.items():
        where = "in frustum" if panel.in_frustum else "out of frustum only"
        n_text = ""
        if panel.in_frustum:
            n_text = "; N solved" if panel.N is not None else f"; N not solved: {panel.N_reason}"
        spaces = ", ".join(
            s for s in (panel.ocio.out_of_frustum, panel.ocio.in_frustum) if s is not None
        )
        facts.append(
            (
                f"panel type {name}",
                f"{where}; {100 * panel.share:.0f}% of the light on the white patch; drive "
                f"M w_avg {_triple(panel.drive)}{n_text}"
                + (f"; colour spaces: {spaces}" if spaces else ""),
            )
        )
    if notes is None:
        return facts
    facts.append(
        (
            "lit white vs target, before Q (R / G / B)",
            f"{_percent(notes.lit_white_error)} with each panel type's own M; "
            f"{_percent(notes.lit_white_error_primary_M)} with every type driven by "
            f"{notes.primary}'s M (a calibration of {notes.primary} alone)",
        )
    )
    match = notes.in_frustum_match
    reference, types = ("", {}) if match is None else (match.reference, match.types)
    for name, block in types.items():
        lost = block.unreachable
        facts.append(
            (
                f"in camera, {name} vs {reference}",
                f"mean ΔE2000 {block.delta_E_2000_mean:.2f}, max "
                f"{block.delta_E_2000_max:.2f} on the chart"
                + (f"; {name} cannot reach patches {lost}" if lost else ""),
            )
        )
    return facts
