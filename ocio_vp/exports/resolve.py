"""DaVinci Resolve export: CLF of the exact transforms, a DCTL for Q, and baked ``.cube`` LUTs.

- ``*.clf``: the exact post-correction Q (footage -> corrected) and the two wall transforms
  (content -> drive: M, and N plus the black-level offset, with the panel-linearity LUT1D when
  the config carries one), serialised by OCIO's own CLF writer from the config's processors.
- ``post_correction_Q.dctl``: Q (LeGendre et al. 2022, eq. 5) as a DCTL in full float precision.
- ``*_<size>.cube``: the same transforms baked by OCIO's Baker (``resolve_cube``) over an HDR
  input range. The range is covered by a 1D shaper that is *linear* in the input space, so an
  affine transform (a matrix with offset) bakes exactly up to the file's decimal precision;
  the worst error against the exact transform is measured and stored in ``cube_errors.json``.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.exports.source import ExportSource
from ocio_vp.exports.templating import render_template
from ocio_vp.ocio.config import matrix_transform

__all__ = [
    "DEFAULT_CUBE_RANGE",
    "DEFAULT_CUBE_SIZE",
    "bake_cube",
    "cube_bake_error",
    "render_dctl",
    "resolve_transforms",
    "write_clf",
    "write_resolve",
]

CLF_FORMAT = "Academy/ASC Common LUT Format"
DEFAULT_CUBE_SIZE = 33
DEFAULT_CUBE_RANGE = (-0.25, 16.0)
SHAPER_NAME = "ocio-vp cube shaper"


def resolve_transforms(source: ExportSource) -> dict[str, tuple[str, str, str]]:
    """File stem -> (input colorspace, output colorspace, description) for each export."""
    names = source.names
    return {
        "post_correction_Q": (
            names["post_correction_colorspace"],
            names["reference"],
            "Post-correction Q for footage shot on the stage (camera linear in and out).",
        ),
        "wall_out_of_frustum": (
            names["reference"],
            names["out_of_frustum"],
            "Content to LED drive OUTSIDE the camera frustum (M; lights the actors).",
        ),
        "wall_in_frustum": (
            names["reference"],
            names["in_frustum"],
            "Content to LED drive INSIDE the camera frustum (N = M Q^-1 plus black-level offset).",
        ),
    }


def write_clf(
    config: OCIO.Config, src: str, dst: str, path: Path, *, name: str, description: str
) -> Path:
    """Serialise the processor ``src -> dst`` as CLF with OCIO's writer."""
    group = config.getProcessor(src, dst).createGroupTransform()
    metadata = group.getFormatMetadata()
    metadata.setName(name)
    metadata.setID(name)
    metadata.addChildElement("Description", description)
    group.write(CLF_FORMAT, str(path), config)
    return path


def render_dctl(
    *,
    title: str,
    stage: str,
    environment: str,
    description: str,
    matrix: Any,
    offset: Sequence[float] | None = None,
) -> str:
    """DCTL text computing ``matrix . rgb + offset`` (names are escaped for C comments)."""
    matrix = np.asarray(matrix, dtype=np.float64)
    offset_values = np.zeros(3) if offset is None else np.asarray(offset, dtype=np.float64)
    return render_template(
        "resolve_matrix.dctl.j2",
        title=title,
        stage=stage,
        environment=environment,
        description=description,
        matrix=matrix.tolist(),
        offset=offset_values.tolist(),
    )


def _shaper_config(
    config: OCIO.Config, src: str, reference: str, lo: float, hi: float
) -> OCIO.Config:
    """A copy of ``config`` with a shaper colorspace that is ``src`` rescaled from [lo, hi] to
    [0, 1] per channel, so the Baker's 1D shaper is linear in the input space."""
    baking = copy.deepcopy(config)
    scale = 1.0 / (hi - lo)
    to_unit = matrix_transform(np.eye(3) * scale, np.full(3, -lo * scale))
    shaper = OCIO.ColorSpace(
        referenceSpace=OCIO.REFERENCE_SPACE_SCENE,
        name=SHAPER_NAME,
        description=f"{src} mapped linearly from [{lo}, {hi}] to [0, 1] (bake shaper).",
    )
    shaper.setTransform(
        OCIO.GroupTransform([OCIO.ColorSpaceTransform(src=reference, dst=src), to_unit]),
        OCIO.COLORSPACE_DIR_FROM_REFERENCE,
    )
    baking.addColorSpace(shaper)
    return baking


def bake_cube(
    config: OCIO.Config,
    src: str,
    dst: str,
    path: Path,
    *,
    reference: str,
    size: int = DEFAULT_CUBE_SIZE,
    input_range: tuple[float, float] = DEFAULT_CUBE_RANGE,
) -> Path:
    """Bake ``src -> dst`` to a Resolve ``.cube`` (1D linear shaper over ``input_range`` +
    ``size``^3 3D LUT) with OCIO's Baker."""
    lo, hi = (float(v) for v in input_range)
    baker = OCIO.Baker()
    baker.setConfig(_shaper_config(config, src, reference, lo, hi))
    baker.setFormat("resolve_cube")
    baker.setInputSpace(src)
    baker.setTargetSpace(dst)
    baker.setShaperSpace(SHAPER_NAME)
    baker.setShaperSize(max(2, size))
    baker.setCubeSize(size)
    baker.bake(str(path))
    return path


def _apply(processor: OCIO.Processor, rgb: np.ndarray) -> np.ndarray:
    data = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    processor.getDefaultCPUProcessor().applyRGB(data)
    return data.astype(np.float64)


def cube_bake_error(
    config: OCIO.Config,
    src: str,
    dst: str,
    cube_path: Path,
    *,
    size: int,
    input_range: tuple[float, float],
    samples: int = 20000,
    seed: int = 0,
) -> dict[str, Any]:
    """Worst and RMS difference between the baked cube (read back by OCIO's own cube reader)
    and the exact transform, over the lattice cell centres plus uniform random points of the
    input range (float32 evaluation on both sides)."""
    lo, hi = (float(v) for v in input_range)
    rng = np.random.default_rng(seed)
    centres = (np.arange(size - 1) + 0.5) / (size - 1)
    grid = np.stack(np.meshgrid(centres, centres, centres, indexing="ij"), -1).reshape(-1, 3)
    if len(grid) > samples:
        grid = grid[rng.choice(len(grid), samples, replace=False)]
    unit = np.concatenate([grid, rng.uniform(size=(samples, 3)), np.eye(3), np.ones((1, 3))])
    rgb = lo + unit * (hi - lo)
    exact = _apply(config.getProcessor(src, dst), rgb)
    raw = OCIO.Config.CreateRaw()
    cube = OCIO.FileTransform(src=str(cube_path.resolve()), interpolation=OCIO.INTERP_LINEAR)
    baked = _apply(raw.getProcessor(cube), rgb)
    diff = np.abs(baked - exact)
    worst = int(np.argmax(diff.max(axis=1)))
    return {
        "max_abs_error": float(diff.max()),
        "rms_error": float(np.sqrt(np.mean(diff**2))),
        "max_abs_output": float(np.abs(exact).max()),
        "worst_input": rgb[worst].tolist(),
        "samples": len(rgb),
        "cube_size": size,
        "input_range": [lo, hi],
        "evaluated_with": f"OpenColorIO {OCIO.__version__} FileTransform (linear) vs the "
        "config's processor",
    }


def write_resolve(
    source: ExportSource,
    folder: Path,
    *,
    cube_size: int = DEFAULT_CUBE_SIZE,
    cube_range: tuple[float, float] = DEFAULT_CUBE_RANGE,
    **_: Any,
) -> dict[str, Any]:
    """Write the CLFs, the Q DCTL, the baked cubes and ``cube_errors.json`` into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    solution, config = source.solution, source.config
    reference = source.names["reference"]
    errors: dict[str, Any] = {}
    files: list[str] = []
    for stem, (src, dst, description) in resolve_transforms(source).items():
        clf = write_clf(
            config,
            src,
            dst,
            folder / f"{stem}.clf",
            name=f"ocio-vp {stem}",
            description=description,
        )
        cube = bake_cube(
            config,
            src,
            dst,
            folder / f"{stem}_{cube_size}.cube",
            reference=reference,
            size=cube_size,
            input_range=cube_range,
        )
        errors[cube.name] = cube_bake_error(
            config, src, dst, cube, size=cube_size, input_range=cube_range
        )
        files += [clf.name, cube.name]
    dctl = folder / "post_correction_Q.dctl"
    dctl.write_text(
        render_dctl(
            title="post-correction Q",
            stage=solution.stage,
            environment=solution.environment,
            description="Footage shot on the stage (camera linear) -> corrected camera linear.",
            matrix=solution.Q,
        ),
        encoding="utf-8",
    )
    report = {
        "format": "ocio-vp/cube-errors",
        "version": 1,
        "stage": solution.stage,
        "environment": solution.environment,
        "cubes": errors,
    }
    (folder / "cube_errors.json").write_text(
        json.dumps(report, indent=2, allow_nan=False) + "\n", encoding="utf-8"
    )
    files += [dctl.name, "cube_errors.json"]
    return {"files": files, "cube_errors": errors}
