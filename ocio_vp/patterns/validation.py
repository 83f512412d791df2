"""The validation sequence: an environment's chart sent through its own config, in-frustum.

``ocio-vp patterns --validate calib/<environment>``: the target chart (``diagnostics.charts.target``),
scaled so its white patch asks for :data:`WHITE_DRIVE` of full drive and pulled into the LEDs'
gamut where it must be (:func:`into_gamut`), run through ``config.ocio`` from the reference to
the in-frustum colorspace (what the wall is sent on set), each colour held full-field. Layout and
why: docs/patterns.md (*Validation sequence*) and docs/validation.md.
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import numpy as np

from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.formats.solution import Solution, load_solution
from ocio_vp.patterns.design import PatternOptions, SequenceBuilder
from ocio_vp.patterns.sequence import PatternSequence, Validation
from ocio_vp.wall.encoding import WallEncoding

__all__ = [
    "GAMUT_MARGIN",
    "WHITE_DRIVE",
    "content_scale",
    "in_frustum_light",
    "into_gamut",
    "validation_sequence",
    "wall_signal",
]


def _wall_encoding_of(solution: Solution) -> tuple[str, float | None]:
    """The old ``wall_encoding_of``: (encoding, peak_nits or None) sent to the wall."""
    encoding = WallEncoding.of(solution.linearity)
    return encoding.name, encoding.peak_nits


#: Names served for one more release (ocio_vp.deprecation).
__getattr__ = deprecated_names(
    __name__,
    {
        "wall_encoding_of": (
            "ocio_vp.wall.WallEncoding.of(solution.linearity) (its name and peak_nits)",
            lambda: _wall_encoding_of,
        )
    },
)

#: The chart's white patch is shown at this fraction of full drive (headroom for saturated
#: patches whose drive exceeds the white's in one channel).
WHITE_DRIVE = 0.7


def _wall_spaces(solution: Solution) -> tuple[str, str]:
    """The reference and in-frustum colour spaces solution.json names."""
    reference, inner = solution.ocio.reference, solution.ocio.in_frustum
    if not reference or not inner:
        raise InputError("solution.json names no reference or in-frustum colorspace", key="ocio")
    return reference, inner


def wall_signal(config_path: str | Path, solution: Solution, content: np.ndarray) -> np.ndarray:
    """(n, 3) what the config sends the wall for ``content`` (n, 3) in its reference space:
    the in-frustum colorspace's output (signal for an encoded wall, drive for a linear one)."""
    import PyOpenColorIO as OCIO

    reference, inner = _wall_spaces(solution)
    try:
        config = OCIO.Config.CreateFromFile(str(config_path))
        cpu = config.getProcessor(reference, inner).getDefaultCPUProcessor()
    except OCIO.Exception as error:
        raise InputError(f"OpenColorIO: {error}"[:200], source=config_path) from None
    pixels = np.ascontiguousarray(np.asarray(content, dtype=np.float32).reshape(-1, 3))
    cpu.applyRGB(pixels)
    return pixels.astype(np.float64)


def content_scale(solution: Solution, target: np.ndarray) -> float:
    """The factor (4 significant digits) that puts the target's white patch at
    :data:`WHITE_DRIVE` through the in-frustum matrix (N, or M where N was not solved)."""
    white = solution.diagnostics.white_patch
    white = white if 0 <= white < len(target) else int(np.argmax(target.sum(axis=1)))
    peak = float(np.max(solution.in_frustum_matrix @ target[white]))
    if not peak > 0:
        raise InputError("the chart's white patch asks the wall for no light", key="diagnostics")
    return float(f"{WHITE_DRIVE / peak:.4g}")


def in_frustum_light(solution: Solution, content: np.ndarray) -> np.ndarray:
    """(n, 3) the light (linear drive) the config asks the wall for: ``N(c) + offset``, with
    a non-linear post-correction's exact ``N(c) = M Q^-1(c)`` where N is solved."""
    content = np.asarray(content, dtype=np.float64)
    correction = solution.correction
    if solution.N is not None and not correction.linear:
        light = correction.inverse(content) @ solution.M.T
    else:
        light = content @ solution.in_frustum_matrix.T
    return light + solution.in_frustum_offset


#: A pulled patch's light stays this far inside [0, 1] of full drive (the wall's black and peak
#: are where linearity LUTs and encodings are least exact).
GAMUT_MARGIN = 0.005


def into_gamut(solution: Solution, content: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(content the wall can show in-frustum, the saturation kept per patch in [0, 1]).

    A patch whose in-frustum light (N(c) + offset, :func:`in_frustum_light`) leaves [GAMUT_MARGIN, 1 - GAMUT_MARGIN] in some channel is mixed with
    the grey of the same R + G + B in the chart white's colour, ``g + k (c - g)``, with the
    largest ``k`` (bisection, 1e-4) that brings its light inside: the colour the wall comes
    closest to at that hue and brightness. The intent of the patch is then this colour, so
    validation judges what the wall can show. Patches inside keep ``k = 1``; a patch whose grey
    is outside too (darker than the black-level offset allows) is left as it is, not shown."""
    content = np.asarray(content, dtype=np.float64)
    white = int(solution.diagnostics.white_patch)
    white = white if 0 <= white < len(content) else int(np.argmax(content.sum(axis=1)))
    tint = content[white] / max(float(content[white].sum()), 1e-12)

    def inside(c: np.ndarray) -> np.ndarray:
        light = in_frustum_light(solution, c)
        return np.all((light >= GAMUT_MARGIN) & (light <= 1.0 - GAMUT_MARGIN), axis=1)

    grey = content.sum(axis=1, keepdims=True) * tint
    kept = np.ones(len(content))
    out = content.copy()
    todo = ~inside(content) & inside(grey)
    lo, hi = np.zeros(len(content)), np.ones(len(content))
    for _ in range(14):  # 2^-14 < 1e-4
        mid = (lo + hi) / 2
        ok = inside(grey + mid[:, None] * (content - grey))
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    kept[todo] = lo[todo]
    out[todo] = grey[todo] + lo[todo, None] * (content[todo] - grey[todo])
    return out, kept


def validation_sequence(environment_dir: str | Path, options: PatternOptions) -> PatternSequence:
    """The validation sequence of one solved environment (module docstring).

    ``options`` give the timing, size and file format; its encoding and peak must be the
    solve's (they are taken from it when ``options`` leave them at linear / none).

    Raises
    ------
    InputError
        No solve there, a solve without the target chart, an encoding other than the solve's,
        or a config OpenColorIO cannot run.
    """
    folder = Path(environment_dir)
    solution = load_solution(folder)
    source = folder / "solution.json"
    charts = solution.diagnostics.charts
    target = np.zeros((0,)) if charts is None else charts.target
    if target.ndim != 2 or target.shape[1:] != (3,) or not np.all(np.isfinite(target)):
        raise InputError("no target chart in diagnostics.charts.target", source=source)
    wall = WallEncoding.of(solution.linearity)  # what the solve's config sends the wall
    encoding, peak = wall.name, wall.peak_nits
    asked = (options.encoding, options.peak_nits)
    if asked != ("linear", None) and asked != (encoding, peak):
        raise InputError(
            f"this solve sends the wall {encoding}"
            + (f" at {peak:g} cd/m2" if peak else "")
            + "; leave --wall-encoding/--peak-nits out or give the same",
            key="--wall-encoding",
        )
    options = dataclasses.replace(options, encoding=encoding, peak_nits=peak)
    config = folder / solution.ocio.config_file
    scale = content_scale(solution, target)
    target, kept = into_gamut(solution, target * scale)
    signals = wall_signal(config, solution, np.vstack([np.zeros((1, 3)), target]))
    drives = wall.decode(signals)
    if not np.all(np.isfinite(drives)):
        raise InputError("the config sends a non-finite drive for the chart", source=config)
    builder = SequenceBuilder(options)
    builder.lead("lead_in")
    builder.sync()
    half = (len(target) + 1) // 2
    for i, drive in enumerate(drives):
        content = tuple(float(v) for v in ([0.0] * 3 if i == 0 else target[i - 1]))
        if i == 0:
            builder.add("black", "black", drive)
            continue
        builder.add(f"chart_{i - 1:02d}", "chart", drive, index=i - 1, content=content)
        if i == half:
            builder.sync()
    builder.sync()
    builder.lead("lead_out")
    from ocio_vp.formats.provenance import solution_identity

    digest = hashlib.sha256(source.read_bytes()).hexdigest()
    identity = solution_identity(folder, solution)
    reference, inner = _wall_spaces(solution)
    validation = Validation(
        environment=solution.environment,
        stage=solution.stage,
        solution_sha256=digest,
        in_frustum=inner,
        reference=reference,
        content_scale=scale,
        pulled=tuple((j, float(f"{k:.4g}")) for j, k in enumerate(kept) if k < 1.0),
        model=identity.model,
        solved=identity.solved,
    )
    return builder.build(validation=validation)
