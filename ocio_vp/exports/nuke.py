"""Nuke export: one ``.nk`` script per environment with its config beside it.

A Group named after the environment: ``Input -> OCIONamedTransform (Q from the config) ->
ColorMatrix (Q, disabled) -> Output`` (the ColorMatrix is the config-free fallback; a
non-linear Q adds a disabled ``OCIOFileTransform`` of its CLF). Paths are relative to the
script through Tcl (``[file dirname [value root.name]]/config/config.ocio``), and the OCIO
node's context sets ``VP_ENVIRONMENT`` for a show config (docs/exports.md).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ocio_vp.choices import CONTEXT_VARIABLE
from ocio_vp.errors import InputError
from ocio_vp.exports.escape import nuke_identifier
from ocio_vp.exports.source import (
    DEFAULT_CUBES,
    ConfigNames,
    CubeOptions,
    ExportSource,
    ExportSummary,
    copy_config,
    post_correction_carriage,
)
from ocio_vp.exports.templating import render_template
from ocio_vp.formats.measurements import check_safe_name

__all__ = ["render_nuke_script", "write_nuke"]

#: Nuke evaluates this in a file knob when it reads it: the folder the script is in.
SCRIPT_FOLDER = "[file dirname [value root.name]]"
# Only the names the script writes itself go into path knobs (no user path): safe for Tcl.
_SAFE_RELATIVE = re.compile(r"\A[A-Za-z0-9._/-]+\Z")


def _relative(path: str) -> str:
    """``path`` (relative to the script's folder) as a file knob that Nuke resolves."""
    if not _SAFE_RELATIVE.match(path) or ".." in path.split("/"):
        raise InputError(f"unexpected file name {path!r} for a Nuke path", key="nuke export")
    return f"{SCRIPT_FOLDER}/{path}"


_MATRIX_LABEL = (
    "Q as a plain matrix: enable this and disable the OCIO node when the config is unavailable"
)
_APPROXIMATION_LABEL = (
    "3x3 approximation of the non-linear Q, NOT the model: only where neither OCIO node can be used"
)


def render_nuke_script(
    *,
    stage: str,
    environment: str,
    Q: np.ndarray,
    config_path: str,
    names: ConfigNames,
    q_lut: str | None = None,
    model_note: str | None = None,
) -> str:
    """The ``.nk`` text for one environment (its nodes: the module docstring).

    ``config_path`` and ``q_lut`` (a non-linear Q's CLF; None for a matrix Q) are relative to
    the script's folder, and ``model_note`` says how the config carries a non-linear Q
    (:func:`post_correction_carriage`). Names are validated here too (not only on input): Nuke
    labels evaluate Tcl.
    """
    check_safe_name(environment, source="nuke export", key="environment")
    check_safe_name(stage, source="nuke export", key="stage")
    return render_template(
        "nuke_environment.nk.j2",
        config_path=_relative(config_path),
        context_key=CONTEXT_VARIABLE,
        environment=environment,
        reference=names.reference,
        named_transform=names.post_correction,
        group_name=nuke_identifier(environment, prefix="ocio_vp_"),
        label=f"ocio-vp Q: {stage} / {environment}",
        Q=[[float(v) for v in row] for row in Q],
        q_lut=None if q_lut is None else _relative(q_lut),
        ocio_label="Q from the config (needs the Root OCIO config)"
        + ("" if not model_note else f". {model_note}"),
        matrix_label=_MATRIX_LABEL if q_lut is None else _APPROXIMATION_LABEL,
    )


def write_nuke(
    source: ExportSource, folder: Path, cubes: CubeOptions = DEFAULT_CUBES
) -> ExportSummary:
    """Write ``<environment>.nk`` and ``config/`` into ``folder`` (paths relative to the
    script, so the folder can be moved)."""
    solution = source.solution
    copy_config(source, folder / "config")
    config_path = f"config/{source.config_path.name}"
    block = solution.diagnostics.post_correction_ocio
    q_files = [] if block is None else block.files
    q_lut = f"config/{q_files[0]}" if q_files else None
    carriage = post_correction_carriage(solution)
    text = render_nuke_script(
        stage=solution.stage,
        environment=solution.environment,
        Q=solution.Q,
        config_path=config_path,
        names=source.names,
        q_lut=q_lut,
        model_note=None if carriage is None else carriage.note,
    )
    script = folder / f"{solution.environment}.nk"
    script.write_text(text, encoding="utf-8")
    return ExportSummary(files=(script.name, config_path))
