"""DaVinci Resolve export: CLF of the exact transforms, a DCTL for Q, and baked ``.cube`` LUTs.

``*.clf``: Q and the two wall transforms, serialised by OCIO's CLF writer from the config;
``post_correction_Q.dctl``: Q (LeGendre et al. 2022, eq. 5), or a non-linear model itself;
``*_<size>.cube``: written only where they meet :data:`ocio_vp.exports.cube.CUBE_LIMIT`;
``manifest.json``: every file with its accuracy, every file not written with the reason, and
``resolve_file``, the file to grade footage with (docs/exports.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO
from numpy.typing import ArrayLike

from ocio_vp.deprecation import deprecated_names
from ocio_vp.exports.cube import CUBE_LIMIT, CubeAccuracy, fit_cube
from ocio_vp.exports.source import (
    DEFAULT_CUBES,
    Carriage,
    CubeOptions,
    ExportSource,
    ExportSummary,
    post_correction_carriage,
    write_json,
)
from ocio_vp.exports.templating import render_template
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.solution import Solution
from ocio_vp.model.correction import (
    PostCorrection,
    ProtectedCorrection,
    RootPolynomialCorrection,
    unprotected,
)
from ocio_vp.model.expansion import root_polynomial_term_powers
from ocio_vp.ocio.clf import CLF_FORMAT, clf_v3

__all__ = [
    "MANIFEST",
    "render_dctl",
    "render_model_dctl",
    "resolve_transforms",
    "write_clf",
    "write_resolve",
]

MANIFEST = "manifest.json"

__getattr__ = deprecated_names(
    __name__,
    {
        name: (f"ocio_vp.exports.source.{name}", f"ocio_vp.exports.source:{name}")
        for name in ("DEFAULT_CUBE_SIZE", "DEFAULT_CUBE_RANGE")
    },
)


def resolve_transforms(source: ExportSource) -> dict[str, tuple[str, str, str]]:
    """File stem -> (input colorspace, output colorspace, description) for each export."""
    names = source.names
    return {
        "post_correction_Q": (
            names.post_correction_colorspace,
            names.reference,
            "Post-correction Q for footage shot on the stage (camera linear in and out).",
        ),
        "wall_out_of_frustum": (
            names.reference,
            names.out_of_frustum,
            "Content to LED drive OUTSIDE the camera frustum (M; lights the actors).",
        ),
        "wall_in_frustum": (
            names.reference,
            names.in_frustum,
            "Content to LED drive INSIDE the camera frustum (N = M Q^-1 plus black-level offset).",
        ),
    }


def write_clf(
    config: OCIO.Config, src: str, dst: str, path: Path, *, name: str, description: str
) -> Path:
    """Serialise the processor ``src -> dst`` as CLF with OCIO's writer (CLF v3 header)."""
    group = config.getProcessor(src, dst).createGroupTransform()
    metadata = group.getFormatMetadata()
    metadata.setName(name)
    metadata.setID(name)
    metadata.addChildElement("Description", description)
    path.write_text(clf_v3(group.write(CLF_FORMAT, config)), encoding="utf-8")
    return path


def render_dctl(
    *,
    title: str,
    stage: str,
    environment: str,
    description: str,
    matrix: ArrayLike,
    offset: Sequence[float] | None = None,
) -> str:
    """DCTL text computing ``matrix . rgb + offset`` (names are escaped for C comments)."""
    values = np.asarray(matrix, dtype=np.float64)
    offset_values = np.zeros(3) if offset is None else np.asarray(offset, dtype=np.float64)
    return render_template(
        "resolve_matrix.dctl.j2",
        title=title,
        stage=stage,
        environment=environment,
        description=description,
        matrix=values.tolist(),
        offset=offset_values.tolist(),
    )


def _term_expression(powers: Sequence[int], root: int) -> str:
    product = " * ".join(f"p_{c}" for c, n in zip("RGB", powers, strict=True) for _ in range(n))
    return product if root == 1 else f"signed_root({product}, {root}.0f)"


def _model_context(correction: PostCorrection) -> JsonObject:
    """The template's values for a correction (:mod:`ocio_vp.model`): its 3x3, and the
    polynomial, domain and emitter protection it has."""
    protect = None
    if isinstance(correction, ProtectedCorrection):
        low, high = correction.bright
        protect = {
            "to_drive": correction.domain.to_drive.tolist(),
            "drive_matrix": correction.drive_matrix.tolist(),
            "bright": [low, high],
            "bright_span": float(np.log2(high / low)),
            "negative": list(correction.negative),
            "floor": correction.floor,
        }
    model = unprotected(correction)
    context: JsonObject = {
        "matrix": model.matrix.tolist(),
        "terms": [],
        "edges": [],
        "protect": protect,
    }
    if isinstance(model, RootPolynomialCorrection):
        context["terms"] = [
            _term_expression(p, k) for p, k in root_polynomial_term_powers(model.degree)
        ]
        context["coefficients"] = model.coefficients.tolist()
        context["fade"] = list(model.fade)
        if model.domain is not None:
            context["gauge_drive"] = model.domain.to_drive.tolist()
            context["centre"] = model.domain.centre.tolist()
            context["edges"] = model.domain.edge_normals.tolist()
    return context


def render_model_dctl(
    *, title: str, stage: str, environment: str, description: str, correction: PostCorrection
) -> str:
    """DCTL text computing a non-linear post-correction exactly (:mod:`ocio_vp.model`): the
    bounded root-polynomial and the emitter protection, as ``ocio-vp apply`` does."""
    return render_template(
        "resolve_model.dctl.j2",
        title=title,
        stage=stage,
        environment=environment,
        description=description,
        model_text=correction.describe(),
        **_model_context(correction),
    )


def _q_dctl(solution: Solution) -> tuple[str, str]:
    """(DCTL text, accuracy note) for Q: the model itself for a non-linear Q."""
    title, description = (
        "post-correction Q",
        "Footage shot on the stage (camera linear) -> corrected camera linear.",
    )
    stage, environment = solution.stage, solution.environment
    correction = solution.correction
    if not correction.linear:
        text = render_model_dctl(
            title=title, stage=stage, environment=environment, description=description,
            correction=correction,
        )  # fmt: skip
        return text, f"{correction.kind} Q (the model, not its 3x3), float32 arithmetic"
    text = render_dctl(
        title=title, stage=stage, environment=environment, description=description,
        matrix=solution.Q,
    )  # fmt: skip
    return text, "Q as float32 literals"


def _cube_entry(
    source: ExportSource, folder: Path, stem: str, clf: str, *, size: int, input_range
) -> tuple[str, CubeAccuracy | None, str | None]:
    """Bake one transform's cube; returns (file name, accuracy or None, reason not written,
    naming the file to use instead)."""
    src, dst, _ = resolve_transforms(source)[stem]
    name = f"{stem}_{size}.cube"
    result = fit_cube(
        source.config.getProcessor(src, dst),
        folder / name,
        size=size,
        input_range=input_range,
        title=f"ocio-vp {stem}: {src} -> {dst}",
    )
    if result.path is not None:
        return name, result.errors, None
    solution = source.solution
    if (
        solution.correction.linear
        or stem == "wall_out_of_frustum"
        or (stem == "wall_in_frustum" and solution.N is None)
    ):
        return name, None, f"{result.reason}; use {clf} (exact)"
    if stem == "post_correction_Q":
        instead = f"use post_correction_Q.dctl (the model, exact) or {clf} (its LUT chain)"
    else:
        instead = f"use {clf} (its Q^-1 LUT chain: see manifest's accuracy)"
    return name, None, f"{result.reason}; {instead}"


def _clf_accuracy(stem: str, solution: Solution, carriage: Carriage | None) -> JsonValue:
    """A CLF's accuracy: exact (OCIO's own serialisation of the config's matrices and curves),
    or, where it holds a non-linear Q's LUT chain, the chain's measured agreement with the
    exact model (ΔE2000; the DCTL is the exact alternative)."""
    if carriage is None or stem == "wall_out_of_frustum":
        return "exact"
    block = solution.diagnostics.post_correction_ocio
    if stem == "post_correction_Q":
        return {
            "delta_E_2000_vs_model": None
            if carriage.agreement is None
            else carriage.agreement.to_dict(),
            "note": carriage.note,
        }
    if solution.N is None:  # the in-frustum drive is M: no LUT chain in it
        return "exact"
    return {
        "round_trip_delta_E_2000": None
        if block is None or block.inverse_agreement is None
        else block.inverse_agreement.to_dict(),
        "note": "content -> this drive's Q^-1 LUT chain -> [SL] -> the exact Q, against the "
        "content (ΔE2000 over the corrected camera range)",
    }


def write_resolve(
    source: ExportSource,
    folder: Path,
    cubes: CubeOptions = DEFAULT_CUBES,
) -> ExportSummary:
    """Write the CLFs, the Q DCTL, the cubes that meet :data:`CUBE_LIMIT` and ``manifest.json``
    (every file with its accuracy, every file not written with the reason)."""
    folder.mkdir(parents=True, exist_ok=True)
    solution, config = source.solution, source.config
    files: dict[str, JsonObject] = {}
    baked: dict[str, CubeAccuracy] = {}
    not_written: dict[str, str] = {}
    carriage = post_correction_carriage(solution)
    for stem, (src, dst, description) in resolve_transforms(source).items():
        clf = write_clf(config, src, dst, folder / f"{stem}.clf", name=f"ocio-vp {stem}",
                        description=description)  # fmt: skip
        files[clf.name] = {"kind": "clf", "from": src, "to": dst,
                           "accuracy": _clf_accuracy(stem, solution, carriage)}  # fmt: skip
        name, errors, reason = _cube_entry(
            source, folder, stem, clf.name, size=cubes.size, input_range=cubes.input_range
        )
        if errors is None:
            not_written[name] = reason or "not written"
        else:
            files[name] = {"kind": "cube", "from": src, "to": dst, "accuracy": errors.to_dict()}
            baked[name] = errors
    dctl = folder / "post_correction_Q.dctl"
    text, accuracy = _q_dctl(solution)
    dctl.write_text(text, encoding="utf-8")
    files[dctl.name] = {"kind": "dctl", "accuracy": accuracy}
    footage = resolve_file({k: v.max_error for k, v in baked.items()}, size=cubes.size)
    manifest: JsonObject = {
        "format": "ocio-vp/resolve-export",
        "version": 1,
        "stage": solution.stage,
        "environment": solution.environment,
        "cube_limit": CUBE_LIMIT,
        "post_correction": None if carriage is None else carriage.to_dict(),
        "files": files,
        "not_written": not_written,
        "resolve_file": footage,
    }
    write_json(folder / MANIFEST, manifest)
    return ExportSummary(
        files=(*files, MANIFEST),
        line=f"the Resolve file for footage: {footage['file']} ({footage['why']}); every "
        "file and its accuracy: manifest.json",
        cubes=baked,
        not_written=not_written,
    )


def resolve_file(cube_errors: Mapping[str, float], *, size: int) -> dict[str, str]:
    """*The* file to post-correct footage with in Resolve: the post-correction's cube when it
    was written (it met the limit; a cube runs everywhere in Resolve), else the DCTL (the
    model itself, exact). ``cube_errors``: each cube written and its worst error.

    >>> resolve_file({"post_correction_Q_33.cube": 2e-7}, size=33)
    {'file': 'post_correction_Q_33.cube', 'why': 'worst error 2e-07 of the exact Q, limit 1/1023'}
    >>> resolve_file({}, size=33)["file"]
    'post_correction_Q.dctl'
    """
    cube = f"post_correction_Q_{size}.cube"
    if cube in cube_errors:
        worst = cube_errors[cube]
        return {"file": cube, "why": f"worst error {worst:.2g} of the exact Q, limit 1/1023"}
    return {
        "file": "post_correction_Q.dctl",
        "why": f"the exact model; no {size}^3 cube of this Q meets 1/1023",
    }
