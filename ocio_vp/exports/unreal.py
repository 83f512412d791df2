"""Unreal Engine nDisplay (ICVFX) export: the config folder, a ``.ocioz``, ``UNREAL.md`` and
``unreal_ocio.json`` saying which colorspace goes in which nDisplay OCIO slot.

The outer viewports and light cards get the out-of-frustum colour space (M), the ICVFX camera's
inner frustum the in-frustum one (N plus the black-level offset); the source is Unreal's working
space when the config carries working spaces, else the reference (docs/exports.md).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import PyOpenColorIO as OCIO

from ocio_vp.calibration.headroom import content_scale
from ocio_vp.choices import CONTEXT_VARIABLE
from ocio_vp.errors import InputError
from ocio_vp.exports.panels import (
    CAMERA,
    PANEL_VERSIONS,
    ROOT_CONFIG,
    ocio_slot,
    panel_assignments,
    panel_notes,
)
from ocio_vp.exports.source import (
    DEFAULT_CUBES,
    CubeOptions,
    ExportSource,
    ExportSummary,
    copy_config,
    post_correction_carriage,
    write_json,
)
from ocio_vp.exports.templating import render_template
from ocio_vp.exports.unreal_script import SCRIPT_FILE, render_unreal_script
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.solution import OcioNames
from ocio_vp.formats.solution_inputs import SOLUTION_FILE
from ocio_vp.ocio import WORKING_SPACE_NAMES

__all__ = ["MAPPING_FILE", "unreal_mapping", "write_ocioz", "write_unreal"]

MAPPING_FILE = "unreal_ocio.json"
#: Where the property paths below were checked (Epic's nDisplay C++ and Python API pages).
UNREAL_VERSIONS = (
    "Checked in Epic's API reference for UE 5.2 to 5.7: FDisplayClusterConfigurationOCIOConfiguration "
    "holds bIsEnabled and ColorConfiguration, and light cards have LightcardOCIO.LightcardOCIOMode. "
    "UE 5.0 nests the conversion as OCIOConfiguration.ColorConfiguration."
)
UNREAL_WORKING_SPACE = WORKING_SPACE_NAMES["ITU-R BT.709"]
ACESCG = WORKING_SPACE_NAMES["ACEScg"]


#: Every archive member gets this timestamp (the zip format's earliest), so re-exports of the
#: same config are byte-identical.
ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def _archive_members(config_path: Path, config: OCIO.Config) -> list[tuple[str, Path]]:
    """(name in the archive, file) for the config and every file of its search-path folders,
    the config first and the rest sorted: the layout ``Config.archive`` writes."""
    members = [(config_path.name, config_path)]
    root = config_path.parent
    sidecars = []
    for entry in config.getSearchPaths():
        folder = root / entry
        if entry in ("", ".") or not folder.is_dir():
            continue
        sidecars += [p for p in folder.rglob("*") if p.is_file()]
    for path in sorted(set(sidecars)):
        members.append((path.relative_to(root).as_posix(), path))
    return members


def write_ocioz(config_path: Path, archive_path: Path) -> Path:
    """Archive the config at ``config_path`` with its LUT files as an OCIO ``.ocioz``.

    Same layout as ``Config.archive`` (``config.ocio`` at the root, sidecars under their
    search-path folder, deflated), but written with fixed timestamps, permissions and member
    order, so the same config always gives the same bytes.
    """
    config = OCIO.Config.CreateFromFile(str(config_path))
    if not config.isArchivable():
        raise InputError(
            "config cannot be archived (absolute or out-of-folder search paths)",
            source=config_path,
        )
    with zipfile.ZipFile(archive_path, "w") as archive:
        for name, path in _archive_members(config_path, config):
            info = zipfile.ZipInfo(name, date_time=ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3  # Unix, so the permissions below are read as such
            info.external_attr = 0o100644 << 16
            # zlib's default level: level 9 makes LUT text barely smaller at several times the
            # cost (the export rows of docs/performance.md)
            archive.writestr(info, path.read_bytes(), compresslevel=6)
    return archive_path


def _content_space(source: ExportSource) -> tuple[str, list[str]]:
    """The colour space content is rendered in (Unreal's working space when the config has
    it, else the camera's native linear RGB) and the alternatives the config offers."""
    has_working = source.config.getColorSpace(UNREAL_WORKING_SPACE) is not None
    content = UNREAL_WORKING_SPACE if has_working else source.names.reference
    alternatives = [ACESCG] if has_working and source.config.getColorSpace(ACESCG) else []
    return content, alternatives


def _desired_spaces(source: ExportSource, content: str) -> list[str]:
    """The colour spaces the OpenColorIO Configuration asset must offer."""
    names = source.names
    panels = panel_assignments(source.solution, content, source.directory / SOLUTION_FILE)
    return [content, names.out_of_frustum, names.in_frustum, *panels.color_spaces]


def _display_views(names: OcioNames) -> list[JsonValue]:
    """The wall's display views, when the config has a display."""
    views = (names.view_out_of_frustum, names.view_in_frustum)
    return [{"display": names.display, "view": v} for v in views if names.display and v]


def unreal_mapping(source: ExportSource, *, config: str, ocioz: str) -> JsonObject:
    """The machine-readable assignment of colorspaces to nDisplay's OCIO slots."""
    names = source.names
    solution = source.solution
    content, alternatives = _content_space(source)
    carriage = post_correction_carriage(solution)

    panels = panel_assignments(solution, content, source.directory / SOLUTION_FILE)  # other types
    return {
        "format": "ocio-vp/unreal-ocio",
        "version": 2,
        "stage": solution.stage,
        "environment": solution.environment,
        "config": config,
        "ocioz": ocioz,
        "content_working_space": content,
        # The OpenColorIO Configuration asset only offers the colour spaces listed here.
        "configuration_asset": {
            "class": "UOpenColorIOConfiguration",
            "configuration_file": config,
            "desired_color_spaces": _desired_spaces(source, content),
            "desired_display_views": _display_views(solution.ocio) + panels.display_views,
        },
        "content_working_space_alternatives": alternatives,
        "unreal_versions": UNREAL_VERSIONS,
        "assignments": [
            ocio_slot(
                "nDisplay root actor > ICVFX > OCIO > All Viewports Color Configuration",
                ROOT_CONFIG,
                "StageSettings.ViewportOCIO.AllViewportsOCIOConfiguration",
                content,
                names.out_of_frustum,
                "out_of_frustum",
            ),
            {
                "ui": "nDisplay root actor > ICVFX > Light Cards > Light Cards OCIO "
                "= Use nDisplay Viewport OCIO",
                "owner": ROOT_CONFIG,
                "property": "StageSettings.Lightcard.LightcardOCIO.LightcardOCIOMode",
                "enum": "EDisplayClusterConfigurationViewportLightcardOCIOMode",
                "value": "nDisplay",
                "python_value": "unreal.DisplayClusterConfigurationViewportLightcardOCIOMode"
                ".N_DISPLAY",
                "destination": names.out_of_frustum,
                "role": "out_of_frustum",
            },
            ocio_slot(
                "ICVFX camera component > OCIO > All Nodes Color Configuration",
                CAMERA,
                "CameraSettings.CameraOCIO.AllNodesOCIOConfiguration",
                content,
                names.in_frustum,
                "in_frustum",
            ),
            *panels.assignments,
        ],
        "post_correction": names.post_correction,
        "post_correction_carriage": None if carriage is None else carriage.to_dict(),
        "N_solved": solution.N is not None,
        "content_scale": content_scale(solution).to_dict(),
        **({"panel_types_checked": PANEL_VERSIONS} if panels.assignments else {}),
    }


def _inverse_note(solution) -> str | None:
    """How close the in-frustum chain's Q^-1 comes to the model's inverse (round trip through
    the exact model, ΔE2000), when N is solved with a non-linear Q."""
    block = solution.diagnostics.post_correction_ocio
    measured = None if block is None else block.inverse_agreement
    if solution.N is None or measured is None:
        return None
    p99, worst = measured.overall
    return (
        f"content -> Q^-1 (the LUT chain) -> Q (the exact model) returns the content within "
        f"{p99:.2g} ΔE2000 (p99) and {worst:.2g} (worst) "
        "over the corrected camera range."
    )


def write_unreal(
    source: ExportSource, folder: Path, cubes: CubeOptions = DEFAULT_CUBES
) -> ExportSummary:
    """Write ``config/``, ``<environment>.ocioz``, ``UNREAL.md`` and ``unreal_ocio.json``."""
    solution = source.solution
    copied = copy_config(source, folder / "config")
    ocioz = write_ocioz(copied, folder / f"{solution.environment}.ocioz")
    config_rel = f"config/{copied.name}"
    mapping = unreal_mapping(source, config=config_rel, ocioz=ocioz.name)
    write_json(folder / MAPPING_FILE, mapping)
    names = source.names
    content, alternatives = _content_space(source)
    carriage = post_correction_carriage(solution)
    if content == names.reference:
        note = (
            "The config has no working spaces (the stage did not name its camera gamut), so "
            "the source is the camera's native linear RGB: render content in that space."
        )
    else:
        note = (
            "The source is Unreal's default working space; use "
            + (" or ".join(f"`{a}`" for a in alternatives))
            + " instead if the project renders in it."
            if alternatives
            else "The source is Unreal's default working space."
        )
    text = render_template(
        "UNREAL.md.j2",
        stage=solution.stage,
        environment=solution.environment,
        mapping_file=MAPPING_FILE,
        config=config_rel,
        ocioz=ocioz.name,
        source=content,
        desired=_desired_spaces(source, content),
        out_of_frustum=names.out_of_frustum,
        in_frustum=names.in_frustum,
        post_correction=names.post_correction,
        source_note=note,
        n_solved=solution.N is not None,
        n_reason=solution.diagnostics.N_reason or "Q is not invertible",
        content_scale=content_scale(solution).lines(),
        panel_notes=panel_notes(solution, source.directory / SOLUTION_FILE),
        model_note=None if carriage is None else carriage.note,
        inverse_note=_inverse_note(solution),
    )
    (folder / "UNREAL.md").write_text(text, encoding="utf-8")
    script = render_unreal_script(
        source.config,
        stage=solution.stage,
        environment=solution.environment,
        config_name=copied.name,
        source=content,
        out_of_frustum=names.out_of_frustum,
        in_frustum=names.in_frustum,
        context={CONTEXT_VARIABLE: solution.environment},
    )
    (folder / SCRIPT_FILE).write_text(script, encoding="utf-8")
    files = [config_rel, ocioz.name, "UNREAL.md", MAPPING_FILE, SCRIPT_FILE]
    return ExportSummary(files=tuple(files))
