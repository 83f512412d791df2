"""Write solved environments to disk: ``OUT/<environment>/config.ocio`` and ``solution.json``.

All environments are written into a staging folder first and renamed into place only when
every one of them succeeded, so a failure never leaves a half-written output folder.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from ocio_vp.formats.solution import Solution, solution_to_json
from ocio_vp.ocio.config import build_config, ocio_names, write_config
from ocio_vp.ocio.root_polynomial import root_polynomial_outputs
from ocio_vp.ocio.wall import wall_outputs
from ocio_vp.staging import publish_dirs, staged_dir
from ocio_vp.wall.encoding import LUT_DIR

__all__ = ["write_environment", "write_solutions"]


def write_environment(solution: Solution, directory: Path) -> Solution:
    """Write one environment's files into ``directory`` (which must exist).

    Returns the solution with its ``ocio`` block filled in, as written to ``solution.json``.
    """
    wall = wall_outputs(solution)  # panel-linearity LUT sidecar and wall signal encoding
    solution = dataclasses.replace(solution, ocio=ocio_names(), linearity=wall.linearity)
    q_luts = root_polynomial_outputs(solution)  # a non-linear Q's LUT sidecars, else None
    files, search_path, q_files = dict(wall.files), wall.search_path, None
    if q_luts is not None:
        files.update(q_luts.files)
        search_path, q_files = LUT_DIR, (q_luts.q_file, q_luts.q_inverse_file)
        diagnostics = {**solution.diagnostics, "root_polynomial_ocio": q_luts.block}
        solution = dataclasses.replace(solution, diagnostics=diagnostics)
    config = build_config(
        solution,
        extra_wall_transforms=wall.extra_wall_transforms,
        search_path=search_path,
        q_files=q_files,
    )
    for relative, text in files.items():
        (directory / relative).parent.mkdir(parents=True, exist_ok=True)
        (directory / relative).write_text(text, encoding="utf-8")
    write_config(config, directory)
    (directory / "solution.json").write_text(solution_to_json(solution), encoding="utf-8")
    return solution


def write_solutions(
    solutions: Sequence[Solution],
    out_dir: str | Path,
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> list[Solution]:
    """Write every solution to ``out_dir/<environment>/``, all or nothing.

    An existing environment folder is replaced only if ocio-vp wrote it and it holds nothing
    else, and none may be one of ``inputs`` (see :mod:`ocio_vp.staging`).
    """
    out_dir = Path(out_dir)
    written = []
    with staged_dir(out_dir) as stage:
        for solution in solutions:
            folder = stage / solution.environment
            folder.mkdir()
            written.append(write_environment(solution, folder))
        pairs = [(stage / s.environment, out_dir / s.environment) for s in solutions]
        publish_dirs(pairs, inputs=inputs)
    return written
