"""Unreal Engine nDisplay (ICVFX) export: the config folder, a ``.ocioz``, ``UNREAL.md`` and
``unreal_ocio.json`` saying which colorspace goes where.

nDisplay picks a source and a destination colorspace per OCIO slot (UI names checked against
Epic's nDisplay API docs: ``AllViewportsOCIOConfiguration`` shown as "All Viewports Color
Configuration", the ICVFX camera's ``CameraOCIO.AllNodesOCIOConfiguration`` shown as "All Nodes
Color Configuration", and ``LightcardOCIOMode`` = "Use nDisplay Viewport OCIO"):

- the outer viewports and the light cards light the actors: destination = out-of-frustum (M);
- the ICVFX camera's inner frustum is the in-camera background: destination = in-frustum
  (N = M Q^-1 plus the black-level offset; LeGendre et al. 2022, eq. 8 and Section 3.4);
- the source is the content's working space: Unreal's own working space (Linear Rec.709) when
  the config carries working spaces (the stage named its camera gamut), else the reference.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import PyOpenColorIO as OCIO

from ocio_vp.errors import InputError
from ocio_vp.exports.source import ExportSource, copy_config
from ocio_vp.exports.templating import render_template
from ocio_vp.ocio.config import WORKING_SPACE_NAMES

__all__ = ["MAPPING_FILE", "unreal_mapping", "write_ocioz", "write_unreal"]

MAPPING_FILE = "unreal_ocio.json"
UNREAL_WORKING_SPACE = WORKING_SPACE_NAMES["ITU-R BT.709"]
ACESCG = WORKING_SPACE_NAMES["ACEScg"]


def write_ocioz(config_path: Path, archive_path: Path) -> Path:
    """Archive the config at ``config_path`` (with its LUT files) with ``Config.archive``."""
    config = OCIO.Config.CreateFromFile(str(config_path))
    if not config.isArchivable():
        raise InputError(
            "config cannot be archived (absolute or out-of-folder search paths)",
            source=config_path,
        )
    config.archive(str(archive_path))
    return archive_path


def unreal_mapping(source: ExportSource, *, config: str, ocioz: str) -> dict[str, Any]:
    """The machine-readable assignment of colorspaces to nDisplay's OCIO slots."""
    names = source.names
    solution = source.solution
    has_working = source.config.getColorSpace(UNREAL_WORKING_SPACE) is not None
    content = UNREAL_WORKING_SPACE if has_working else names["reference"]
    alternatives = [ACESCG] if has_working and source.config.getColorSpace(ACESCG) else []

    def slot(ui: str, prop: str, destination: str, role: str) -> dict[str, str]:
        return {
            "ui": ui,
            "property": prop,
            "source": content,
            "destination": destination,
            "role": role,
        }

    return {
        "format": "ocio-vp/unreal-ocio",
        "version": 1,
        "stage": solution.stage,
        "environment": solution.environment,
        "config": config,
        "ocioz": ocioz,
        "content_working_space": content,
        # The OpenColorIO Configuration asset only offers the colour spaces listed here.
        "configuration_asset": {
            "configuration_file": config,
            "desired_color_spaces": [content, names["out_of_frustum"], names["in_frustum"]],
            "desired_display_views": [
                {"display": names["display"], "view": names["view_out_of_frustum"]},
                {"display": names["display"], "view": names["view_in_frustum"]},
            ]
            if "display" in names
            else [],
        },
        "content_working_space_alternatives": alternatives,
        "assignments": [
            slot(
                "nDisplay root actor > OCIO > All Viewports Color Configuration",
                "ViewportOCIO.AllViewportsOCIOConfiguration",
                names["out_of_frustum"],
                "out_of_frustum",
            ),
            {
                "ui": "nDisplay root actor > Light Cards > Light Cards OCIO",
                "property": "StageSettings.Lightcard.LightcardOCIO.LightcardOCIOMode",
                "value": "Use nDisplay Viewport OCIO",
                "destination": names["out_of_frustum"],
                "role": "out_of_frustum",
            },
            slot(
                "ICVFX camera component > OCIO > All Nodes Color Configuration",
                "CameraSettings.CameraOCIO.AllNodesOCIOConfiguration",
                names["in_frustum"],
                "in_frustum",
            ),
        ],
        "post_correction": names["post_correction"],
        "N_solved": solution.N is not None,
    }


def write_unreal(source: ExportSource, folder: Path, **_: Any) -> dict[str, Any]:
    """Write ``config/``, ``<environment>.ocioz``, ``UNREAL.md`` and ``unreal_ocio.json``."""
    solution = source.solution
    copied = copy_config(source, folder / "config")
    ocioz = write_ocioz(copied, folder / f"{solution.environment}.ocioz")
    config_rel = f"config/{copied.name}"
    mapping = unreal_mapping(source, config=config_rel, ocioz=ocioz.name)
    (folder / MAPPING_FILE).write_text(
        json.dumps(mapping, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    names = source.names
    if mapping["content_working_space"] == names["reference"]:
        note = (
            "The config has no working spaces (the stage did not name its camera gamut), so "
            "the source is the camera's native linear RGB: render content in that space."
        )
    else:
        note = (
            "The source is Unreal's default working space; use "
            + (" or ".join(f"`{a}`" for a in mapping["content_working_space_alternatives"]))
            + " instead if the project renders in it."
            if mapping["content_working_space_alternatives"]
            else "The source is Unreal's default working space."
        )
    text = render_template(
        "UNREAL.md.j2",
        stage=solution.stage,
        environment=solution.environment,
        mapping_file=MAPPING_FILE,
        config=config_rel,
        ocioz=ocioz.name,
        source=mapping["content_working_space"],
        desired=mapping["configuration_asset"]["desired_color_spaces"],
        out_of_frustum=names["out_of_frustum"],
        in_frustum=names["in_frustum"],
        post_correction=names["post_correction"],
        source_note=note,
        n_solved=solution.N is not None,
        n_reason=solution.diagnostics.get("N_reason") or "Q is not invertible",
    )
    (folder / "UNREAL.md").write_text(text, encoding="utf-8")
    return {"files": [config_rel, ocioz.name, "UNREAL.md", MAPPING_FILE], "mapping": mapping}
