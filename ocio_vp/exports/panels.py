"""Unreal nDisplay for a stage of several panel types: each type's colour space on its viewports.

The wall (the first in-frustum type) keeps the stage-wide slots of :mod:`ocio_vp.exports.unreal`;
every other type overrides them with nDisplay's per-viewport (outer frustum) and, in frustum,
per-node (inner frustum) OCIO profiles. Each profile's ``ApplyOCIOToObjects`` is left empty for
the stage engineer to fill (UNREAL.md says which; docs/exports.md).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ocio_vp.errors import InputError
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.panel_solution import OcioNames, PanelSolution
from ocio_vp.formats.solution import Solution

__all__ = ["PANEL_VERSIONS", "PanelAssignments", "ocio_slot", "panel_assignments", "panel_notes"]

#: Owners of the slots: the root actor's configuration data, and each ICVFX camera.
ROOT_CONFIG = "ADisplayClusterRootActor config data (UDisplayClusterConfigurationData)"
CAMERA = "UDisplayClusterICVFXCameraComponent"
#: Where the per-viewport and per-node profiles were checked.
PANEL_VERSIONS = (
    "FDisplayClusterConfigurationICVFX_ViewportOCIO.PerViewportOCIOProfiles and "
    "FDisplayClusterConfigurationICVFX_CameraOCIO.PerNodeOCIOProfiles, arrays of "
    "FDisplayClusterConfigurationOCIOProfile (bIsEnabled, ApplyOCIOToObjects, ColorConfiguration) "
    "in Epic's API reference pages for UE 5.4 to 5.7 (the conversion is ColorConfiguration; "
    "UE 5.0's Python names it ocio_configuration)."
)


def ocio_slot(
    ui: str,
    owner: str,
    prop: str,
    source: str,
    destination: str,
    role: str,
    *,
    profile: bool = False,
) -> JsonObject:
    """One OCIO conversion of ``unreal_ocio.json``: ``set`` on a stage-wide slot, or with
    ``profile`` appended as a per-viewport or per-node profile (its objects left to fill)."""
    objects: JsonObject = {"ApplyOCIOToObjects": []} if profile else {}
    conversion: JsonObject = {
        "bIsEnabled": True,
        **objects,
        "ColorConfiguration.SourceColorSpace": source,
        "ColorConfiguration.DestinationColorSpace": destination,
    }
    return {
        "ui": ui,
        "owner": owner,
        "property": prop,
        "append" if profile else "set": conversion,
        "source": source,
        "destination": destination,
        "role": role,
    }


@dataclass(frozen=True)
class PanelAssignments:
    """The other panel types' part of ``unreal_ocio.json``: colour spaces and display views the
    configuration asset must offer, and their profiles (all empty for one panel type)."""

    color_spaces: list[str]
    display_views: list[JsonValue]
    assignments: list[JsonValue]


def _spaces(
    name: str, panel: PanelSolution, where: Path | str | None
) -> tuple[str, str | None] | None:
    """A panel type's out-of-frustum and (in frustum) in-frustum colour spaces; None while its
    ``ocio`` block is empty (no config names its spaces yet). A block naming some but not
    these is an InputError naming the missing key in ``where`` (its solution.json)."""
    names = panel.ocio
    if names == OcioNames():
        return None
    outer, inner = names.out_of_frustum, names.in_frustum if panel.in_frustum else None
    if outer is None or (panel.in_frustum and inner is None):
        role = "out_of_frustum" if outer is None else "in_frustum"
        raise InputError(
            f"expected the name of the {name} panels' {role} colour space",
            source=where,
            key=f"panels.{name}.ocio.{role}",
        )
    return outer, inner


def _other_types(
    solution: Solution, where: Path | str | None
) -> Iterator[tuple[str, PanelSolution, str, str | None]]:
    """(name, panel, out-of-frustum space, in-frustum space or None) of every panel type but the
    first in-frustum one, once its ``ocio`` block names its spaces."""
    panels = solution.panels or {}
    primary = next((p.name for p in panels.values() if p.in_frustum), None)
    for name, panel in panels.items():
        spaces = None if name == primary else _spaces(name, panel, where)
        if spaces is not None:
            yield name, panel, *spaces


def panel_assignments(
    solution: Solution, source: str, where: Path | str | None = None
) -> PanelAssignments:
    """One per-viewport (and, in frustum, per-node) profile per other panel type, with the
    colour spaces and display views they need; ``where`` is solution.json (for errors)."""
    spaces: list[str] = []
    views: list[JsonValue] = []
    assignments: list[JsonValue] = []
    display = solution.ocio.display
    for name, panel, outer, inner in _other_types(solution, where):
        names = panel.ocio
        for space, view in ((outer, names.view_out_of_frustum), (inner, names.view_in_frustum)):
            if space is not None:
                spaces.append(space)
            if space is not None and display and view is not None:
                views.append({"display": display, "view": view})
        assignments.append(
            ocio_slot(
                f"nDisplay root actor > ICVFX > OCIO > Per-Viewport OCIO Overrides: the {name} "
                "viewports",
                ROOT_CONFIG,
                "StageSettings.ViewportOCIO.PerViewportOCIOProfiles",
                source,
                outer,
                f"{name}.out_of_frustum",
                profile=True,
            )
        )
        if inner is not None:
            assignments.append(
                ocio_slot(
                    f"ICVFX camera component > OCIO > Per-Node OCIO Overrides: the nodes "
                    f"driving the {name}",
                    CAMERA,
                    "CameraSettings.CameraOCIO.PerNodeOCIOProfiles",
                    source,
                    inner,
                    f"{name}.in_frustum",
                    profile=True,
                )
            )
    return PanelAssignments(spaces, views, assignments)


def panel_notes(solution: Solution, where: Path | str | None = None) -> list[str]:
    """One UNREAL.md step per other panel type (none for a stage of one panel type);
    ``where`` is solution.json (for errors)."""
    notes = []
    for name, _, outer, inner in _other_types(solution, where):
        text = (
            f"Panel type `{name}`: on the nDisplay root actor, **OCIO > Per-Viewport OCIO "
            f"Overrides**, add a profile for the viewports of the {name} (list them in *Apply "
            f"OCIO To Objects*) with *Destination* = `{outer}` (its own "
            "M: driving it with the wall's gets the actors' light wrong)."
        )
        if inner is not None:
            text += (
                f" On each ICVFX camera component, **OCIO > Per-Node OCIO Overrides**: a "
                f"profile for the cluster nodes that drive the {name}, *Destination* = "
                f"`{inner}` (its own N)."
            )
        notes.append(text)
    return notes
