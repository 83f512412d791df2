"""The colour spaces of a stage's other panel types, beside the wall's (docs/panels.md, *The
config*): each built as the wall's (:func:`ocio_vp.ocio.config.wall_chains`,
:func:`ocio_vp.ocio.config.wall_space`) on a view of the solution as if that type were the wall.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ocio_vp.formats.panel_solution import PanelSolution
from ocio_vp.formats.solution import OcioNames, Solution
from ocio_vp.ocio.config import (
    DISPLAY,
    IN_FRUSTUM,
    OUT_OF_FRUSTUM,
    VIEW_INNER,
    VIEW_OUTER,
    drive_description,
    in_frustum_text,
    wall_chains,
    wall_space,
)
from ocio_vp.ocio.description import ColourSpace, ConfigData, View
from ocio_vp.ocio.matrix import format_matrix
from ocio_vp.ocio.viewing import set_categories
from ocio_vp.ocio.wall import wall_outputs

if TYPE_CHECKING:
    from ocio_vp.ocio.bake import ModelOutputs

__all__ = ["PanelOutputs", "add_panel_spaces", "panel_labels", "panel_outputs"]


def panel_labels(names: list[str], primary: str) -> dict[str, str]:
    """How each panel type reads in colour-space names: ``Wall`` for ``primary``, the others
    in title case, ``Panel <name>`` where that would repeat a label or read ``Wall``.

    >>> panel_labels(["wall", "ceiling", "wild-wall", "wild_wall"], "wall")
    {'wall': 'Wall', 'ceiling': 'Ceiling', 'wild-wall': 'Panel wild-wall', 'wild_wall': 'Panel wild_wall'}
    """
    titles = {n: " ".join(n.replace("-", " ").replace("_", " ").split()).title() for n in names}
    labels = {}
    for name in names:
        title = titles[name]
        clash = title == "Wall" or sum(t == title for t in titles.values()) > 1
        labels[name] = "Wall" if name == primary else (f"Panel {name}" if clash else title)
    return labels


def _names(label: str, in_frustum: bool) -> dict[str, str]:
    names = {
        "out_of_frustum": f"LED {label} - Outer Frustum",
        "view_out_of_frustum": f"{label} {VIEW_OUTER}",
    }
    if in_frustum:
        names["in_frustum"] = f"LED {label} - Inner Frustum"
        names["view_in_frustum"] = f"{label} {VIEW_INNER}"
    return names


@dataclass(frozen=True)
class PanelOutputs:
    """What the other panel types add: colour spaces, (view, colour space) pairs for the
    ``LED Wall`` display, LUT sidecars (relative path -> text), and every type's
    :class:`~ocio_vp.formats.panel_solution.PanelSolution` with ``ocio`` and ``linearity``
    filled in, as solution.json records them."""

    colorspaces: tuple[ColourSpace, ...]
    views: tuple[tuple[str, str], ...]
    files: dict[str, str] = field(default_factory=dict)
    panels: dict[str, PanelSolution] = field(default_factory=dict)


def _view(solution: Solution, panel: PanelSolution) -> Solution:
    """The solution as if ``panel`` were the stage's one wall (its M, N, offset, linearity)."""
    return dataclasses.replace(
        solution,
        SL=panel.SL,
        M=panel.M,
        N=panel.N,
        black_level_offset=panel.black_level_offset,
        linearity=panel.linearity,
        panels=None,
    )


def _descriptions(solution: Solution, panel: PanelSolution) -> dict[str, str]:
    origin = f"stage {solution.stage!r}, environment {solution.environment!r}"
    inner = in_frustum_text(panel.M, panel.N, panel.black_level_offset, panel.N_reason)
    outer = f"its own M = [SL]^-1 {format_matrix(panel.M)}"
    return {
        OUT_OF_FRUSTUM: drive_description(False, outer, panel.linearity, origin, panel.name),
        IN_FRUSTUM: drive_description(True, inner, panel.linearity, origin, panel.name),
    }


def panel_outputs(solution: Solution, model: ModelOutputs | None = None) -> PanelOutputs | None:
    """The other panel types' colour spaces (None for a stage of one panel type); ``model``:
    a non-linear Q's sidecars, as for the wall's."""
    if not solution.panels:
        return None
    primary = next(p.name for p in solution.panels.values() if p.in_frustum)
    labels = panel_labels(list(solution.panels), primary)
    spaces: list[ColourSpace] = []
    views: list[tuple[str, str]] = []
    files: dict[str, str] = {}
    panels: dict[str, PanelSolution] = {}
    for name, panel in solution.panels.items():
        if name == primary:
            wall_names = OcioNames(
                out_of_frustum=OUT_OF_FRUSTUM,
                in_frustum=IN_FRUSTUM,
                view_out_of_frustum=VIEW_OUTER,
                view_in_frustum=VIEW_INNER,
            )
            panels[name] = dataclasses.replace(panel, linearity=solution.linearity, ocio=wall_names)
            continue
        view = _view(solution, panel)
        wall = wall_outputs(view)
        files.update(wall.files)
        chains = wall_chains(view, wall.extra_wall_transforms or {}, model)
        names = _names(labels[name], panel.in_frustum)
        texts = _descriptions(solution, panel)
        roles = [(OUT_OF_FRUSTUM, "out_of_frustum")]
        roles += [(IN_FRUSTUM, "in_frustum")] if panel.in_frustum else []
        for role, key in roles:
            spaces.append(wall_space(names[key], texts[role], wall.linearity, chains[role]))
            views.append((names[f"view_{key}"], names[key]))
        panels[name] = dataclasses.replace(panel, linearity=wall.linearity, ocio=OcioNames(**names))
    return PanelOutputs(tuple(spaces), tuple(views), files, panels)


def add_panel_spaces(data: ConfigData, outputs: PanelOutputs) -> None:
    """Add the colour spaces, their views on the ``LED Wall`` display and their categories."""
    data.colour_spaces += outputs.colorspaces
    data.views += [View(DISPLAY, view, space) for view, space in outputs.views]
    if data.active_views:  # none listed: every view is active
        data.active_views = (*data.active_views, *(view for view, _ in outputs.views))
    set_categories(data)
