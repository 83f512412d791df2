"""Nuke export: one ``.nk`` script per environment with its config beside it.

The script sets the Root to the exported OCIO config and holds a Group named after the
environment: ``Input -> OCIONamedTransform (Q from the config) -> ColorMatrix (Q, disabled)
-> Output``. The ColorMatrix is the config-free fallback: enable it and disable the OCIO node
where the config cannot be loaded. Q is the paper's post-correction (LeGendre et al. 2022,
eq. 5), applied to camera-native linear footage.

A root-polynomial Q is non-linear: the named transform carries it (the config's LUT bake), and
a disabled ``OCIOFileTransform`` reading its CLF sidecar is the fallback that works under any
Root config; the ColorMatrix then holds only the model's 3x3 approximation, the last resort.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from ocio_vp.errors import InputError
from ocio_vp.exports.escape import nuke_identifier
from ocio_vp.exports.source import ExportSource, copy_config
from ocio_vp.exports.templating import render_template
from ocio_vp.formats.measurements import check_safe_name

__all__ = ["render_nuke_script", "write_nuke"]

# Nuke evaluates [...] and $... inside path and label knobs at run time (a second level of Tcl
# after the file is parsed), so a path carrying them is refused rather than escaped twice.
_NUKE_SAFE_PATH = re.compile(r"^[^\[\]{}$\\\"\x00-\x1f\x7f]+$")


def _check_nuke_path(path: str) -> str:
    if not _NUKE_SAFE_PATH.match(path):
        raise InputError(
            'Nuke would evaluate the characters [ ] { } $ \\ " or control characters in '
            "this path as Tcl; export to a folder whose path has none of them",
            source=path,
            key="--out",
        )
    return path


_MATRIX_LABEL = (
    "Q as a plain matrix: enable this and disable the OCIO node when the config is unavailable"
)
_APPROXIMATION_LABEL = (
    "3x3 approximation of the root-polynomial Q: only where neither OCIO node can be used"
)


def render_nuke_script(
    *,
    stage: str,
    environment: str,
    Q: Any,
    config_path: str,
    names: dict[str, str],
    q_lut: str | None = None,
) -> str:
    """The ``.nk`` text for one environment (see the module docstring for its nodes).

    ``q_lut`` is the absolute path of a root-polynomial Q's CLF (None for a matrix Q). Names
    are validated here too (not only on input): Nuke labels evaluate Tcl.
    """
    check_safe_name(environment, source="nuke export", key="environment")
    check_safe_name(stage, source="nuke export", key="stage")
    _check_nuke_path(config_path)
    if q_lut is not None:
        _check_nuke_path(q_lut)
    return render_template(
        "nuke_environment.nk.j2",
        config_path=config_path,
        reference=names["reference"],
        named_transform=names["post_correction"],
        group_name=nuke_identifier(environment, prefix="ocio_vp_"),
        label=f"ocio-vp Q: {stage} / {environment}",
        Q=[[float(v) for v in row] for row in Q],
        q_lut=q_lut,
        matrix_label=_MATRIX_LABEL if q_lut is None else _APPROXIMATION_LABEL,
    )


def write_nuke(source: ExportSource, folder: Path, *, final_folder: Path, **_: Any) -> dict:
    """Write ``<environment>.nk`` and ``config/`` into ``folder``.

    ``final_folder`` is where ``folder`` will be renamed to: the Root's config path is absolute
    (Nuke resolves a relative one against its working directory, not the script).
    """
    solution = source.solution
    copy_config(source, folder / "config")
    config_path = (final_folder / "config" / source.config_path.name).resolve().as_posix()
    q_files = (solution.diagnostics.get("root_polynomial_ocio") or {}).get("files") or []
    q_lut = (final_folder / "config" / q_files[0]).resolve().as_posix() if q_files else None
    text = render_nuke_script(
        stage=solution.stage,
        environment=solution.environment,
        Q=solution.Q,
        config_path=config_path,
        names=source.names,
        q_lut=q_lut,
    )
    script = folder / f"{solution.environment}.nk"
    script.write_text(text, encoding="utf-8")
    return {"script": script.name, "config": f"config/{source.config_path.name}"}
