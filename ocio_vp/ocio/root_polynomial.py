"""A root-polynomial post-correction in OCIO: Q and Q^-1 baked on scale x direction as CLF sidecars.

A root-polynomial Q (:mod:`ocio_vp.correction.root_polynomial`) is not a matrix, so the config
carries it as LUTs. Q and Q^-1 are homogeneous of degree 1 (``F(k x) = k F(x)``), so each is
baked as a function of the colour's *direction* only, with the scale carried exactly by OCIO ops:

1. ``Matrix``: a slight mix towards grey, ``(1 - e) x + e mean(x)`` (e = 1 % on the camera side,
   5 % on the content side), so every non-negative colour has positive channels;
2. ``Log`` (log2): in log space a change of exposure is a shift along the diagonal;
3. ``Matrix``: to (scale ``s`` = mean log2, ``a`` = log2 r/g, ``b`` = log2 b/g), mapped to [0, 1];
4. ``LUT1D``: on ``s``, the scale into the 3D LUT's first cell along its first axis; on ``a``
   and ``b`` a warp that puts 60 % of the grid on the log-ratios of the content (the target
   chart's gamut and its preimages, +-0.5 stop) and the rest, with growing steps, out to
   +-10 stops (the whole non-negative cube);
5. ``LUT3D`` (65^3, tetrahedral) holding ``s + log2(mix(F(direction(a, b))))``;
6. ``Log`` inverse (2^x), then ``Matrix``: the inverse of the output's mix.

The LUT's values are exactly affine in ``s``, tetrahedral interpolation reproduces an affine
function exactly, and the interpolation in (a, b) does not depend on where ``s`` falls in its
cell. So the scale axis adds no error (exposures from 2^-32 to 2^16 are the same bake) and
needs only one cell: its first two slices hold the scale range's two ends, the third repeats
the second (a clamp, so rounding at the cell's top edge changes nothing) and the other 62 are
zeros, never reached (the 1D LUT keeps ``s`` in the first cell). A cube is what OCIO and CLF
accept, so the file still holds 65^3 entries, but only 2 x 65^2 distinct ones are computed
and formatted, and the zeros keep each file at about 2 MB (6.6 MB with every slice filled).
The error is that of interpolating a smooth function of two log-ratios on a 65 x 65 grid.
Measured (the bake error, in % of each colour's largest channel, six environments): mean
0.015-0.023 %, max <= 0.065 % for content in the target chart's gamut at any exposure, where
the former per-channel log shaper had up to 0.75 %. Q^-1 is exact Newton
(:func:`~ocio_vp.correction.invert_root_polynomial`); only the 65^2 directions are solved.

Zeros and negatives: the log clamps non-positive values to float's smallest, so black gives
~2^-32 (effectively black), and a channel negative enough to stay negative after the mix acts
as the most saturated colour of the domain: finite, but not the model (``ocio-vp apply`` runs
the exact model). The bake error is measured on random colours when the config is written and
stored in ``solution.json`` (``diagnostics.root_polynomial_ocio.bake_error``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.errors import InputError
from ocio_vp.formats.solution import Solution
from ocio_vp.model.correction import PostCorrection
from ocio_vp.ocio.clf import CLF_FORMAT, clf_v3
from ocio_vp.ocio.wall import sidecar_name
from ocio_vp.wall.encoding import LUT_DIR

__all__ = [
    "CAMERA_MIX",
    "CONTENT_MIX",
    "LUT_SIZE",
    "RATIO_RANGE",
    "SCALE_RANGE",
    "RootPolynomialOutputs",
    "baked_transform",
    "content_box",
    "root_polynomial_outputs",
]

#: 3D LUT grid size: worst in-gamut bake error ~0.06 % at 65, ~0.11 % at 49, ~0.22 % at 33.
LUT_SIZE = 65
#: Entries of the 1D warp on the log-ratios (OCIO keeps a 1D texture on GPU hosts up to 4095).
WARP_SIZE = 4095
#: Mix towards grey on the camera side (Q's input, Q^-1's output) and on the content side.
CAMERA_MIX = 0.01
CONTENT_MIX = 0.05
#: log2 of the (geometric-mean) scale the LUT covers: 2^-32 (black) to 2^16.
SCALE_RANGE = (-32.0, 16.0)
#: |log2 r/g| and |log2 b/g| the LUT covers; beyond, the ratio is clamped.
RATIO_RANGE = 10.0
#: Fraction of the grid on the content's log-ratios, and the margin around them (stops).
CONTENT_FRACTION = 0.6
CONTENT_MARGIN = 0.5
#: The 3D LUT holds log2 values in steps of 2^-16 stop, as integers (exact in float32 and
#: quick to write as text; the rounding, <= 5e-6 relative, is 100x below the bake error).
LUT_STEPS_PER_STOP = 2.0**16
#: Slices of the 3D LUT's scale axis that hold values: the one cell the shaper maps the scale
#: into, and one more (a clamp) so that rounding at the cell's top edge reads the same values;
#: the other slices are zeros, never reached (the 1D LUT clamps the scale to the first cell).
_SCALE_SLICES = 3
#: Smallest mixed output relative to the direction's scale (directions whose output leaves the
#: positive cone: outside the content, where Q is not injective or its image not positive).
_OUTPUT_FLOOR = 2.0**-24


def _mix(e: float) -> np.ndarray:
    """``(1 - e) I + e/3 ones``: every channel of a non-negative colour gets ``e`` of its mean."""
    return (1.0 - e) * np.eye(3) + e / 3.0 * np.ones((3, 3))


def _log_ratios(rgb: np.ndarray, e: float) -> np.ndarray:
    """(n, 2) (log2 r/g, log2 b/g) of the mixed colours (rows with a non-positive mix dropped)."""
    mixed = np.asarray(rgb, dtype=np.float64).reshape(-1, 3) @ _mix(e).T
    u = np.log2(mixed[np.all(mixed > 0, axis=1)])
    return np.stack([u[:, 0] - u[:, 1], u[:, 2] - u[:, 1]], axis=-1)


def content_box(rgb: np.ndarray, e: float) -> np.ndarray:
    """(2, 2) [low; high] log-ratios (a, b) of ``rgb`` mixed by ``e``, +- the margin."""
    ratios = _log_ratios(rgb, e)
    low = np.maximum(ratios.min(axis=0) - CONTENT_MARGIN, -RATIO_RANGE + 1.0)
    high = np.minimum(ratios.max(axis=0) + CONTENT_MARGIN, RATIO_RANGE - 1.0)
    return np.stack([low, high])


def _nodes(low: float, high: float, size: int) -> np.ndarray:
    """LUT nodes on one log-ratio axis: uniform on [low, high], then steps growing
    quadratically (continuous slope) out to +-RATIO_RANGE."""
    n_out = round((size - 1) * (1 - CONTENT_FRACTION) / 2)
    n_in = size - 1 - 2 * n_out
    h = (high - low) / n_in
    t = np.arange(1, n_out + 1)
    g_low = (RATIO_RANGE + low - n_out * h) / n_out**2
    g_high = (RATIO_RANGE - high - n_out * h) / n_out**2
    return np.concatenate(
        [
            (low - h * t - g_low * t**2)[::-1],
            low + h * np.arange(n_in + 1),
            high + h * t + g_high * t**2,
        ]
    )


def _m44(matrix: np.ndarray, offset=(0.0, 0.0, 0.0)) -> OCIO.MatrixTransform:
    m = np.eye(4)
    m[:3, :3] = matrix
    return OCIO.MatrixTransform(m.ravel().tolist(), [*map(float, offset), 0.0])


def _to_lut_domain() -> OCIO.MatrixTransform:
    """log2 rgb -> ((s - low) / span, a / (2 R) + 1/2, b / (2 R) + 1/2)."""
    low, high = SCALE_RANGE
    basis = np.array([[1 / 3, 1 / 3, 1 / 3], [1.0, -1.0, 0.0], [0.0, -1.0, 1.0]])
    scale = np.diag([1 / (high - low), 1 / (2 * RATIO_RANGE), 1 / (2 * RATIO_RANGE)])
    return _m44(scale @ basis, (-low / (high - low), 0.5, 0.5))


def _warp(nodes_a: np.ndarray, nodes_b: np.ndarray) -> OCIO.Lut1DTransform:
    """1D LUT: s into the 3D LUT's first cell (``s / (size - 1)``); on a and b, the position of
    the value among the 3D LUT's nodes."""
    p = np.linspace(0.0, 1.0, WARP_SIZE)
    ratio = RATIO_RANGE * (2 * p - 1)
    k = np.linspace(0.0, 1.0, len(nodes_a))
    first_cell = p / (len(nodes_a) - 1)
    values = np.stack([first_cell, np.interp(ratio, nodes_a, k), np.interp(ratio, nodes_b, k)], -1)
    lut = OCIO.Lut1DTransform(length=WARP_SIZE)
    lut.setData(np.ascontiguousarray(values, dtype=np.float32).ravel())
    return lut


def _direction_table(function, nodes_a, nodes_b, e_in: float, e_out: float) -> np.ndarray:
    """(size^2, 3) log2 of the mixed ``function`` on the grid's directions (mean log2 = 0)."""
    a, b = (v.ravel() for v in np.meshgrid(nodes_a, nodes_b, indexing="ij"))
    u_g = -(a + b) / 3
    direction = np.exp2(np.stack([a + u_g, u_g, b + u_g], axis=-1)) @ np.linalg.inv(_mix(e_in)).T
    mixed = np.asarray(function(direction), dtype=np.float64) @ _mix(e_out).T
    return np.log2(np.maximum(np.nan_to_num(mixed, nan=0.0), _OUTPUT_FLOOR))


def baked_transform(
    function, box: np.ndarray, e_in: float, e_out: float, size: int = LUT_SIZE
) -> OCIO.GroupTransform:
    """The op chain of the module docstring for a degree-1 homogeneous ``function``.

    ``box`` is :func:`content_box` of the inputs to be baked most finely; ``e_in`` and
    ``e_out`` the mixes towards grey of the input and the output.
    """
    nodes_a = _nodes(box[0, 0], box[1, 0], size)
    nodes_b = _nodes(box[0, 1], box[1, 1], size)
    table = _direction_table(function, nodes_a, nodes_b, e_in, e_out)
    # integers, exact in float32 (< 2^24); both scale ends are even multiples of the step, so
    # adding them after rounding gives the same integers as rounding the sums
    steps = np.rint(table * LUT_STEPS_PER_STOP)
    low, high = (steps + end * LUT_STEPS_PER_STOP for end in SCALE_RANGE)
    if not (np.all(np.isfinite(steps)) and max(np.abs(low).max(), np.abs(high).max()) < 2**24):
        raise ValueError("root-polynomial bake produced non-finite LUT entries")
    values = np.zeros((size, size * size, 3), dtype=np.float32)  # s slowest, then a, b
    values[0], values[1:_SCALE_SLICES] = low, high  # one cell on s, one of clamp, then zeros
    lut = OCIO.Lut3DTransform(gridSize=size)
    lut.setData(values.ravel())
    lut.setInterpolation(OCIO.INTERP_TETRAHEDRAL)
    antilog = OCIO.LogTransform(base=2.0, direction=OCIO.TRANSFORM_DIR_INVERSE)
    return OCIO.GroupTransform(
        [
            _m44(_mix(e_in)),
            OCIO.LogTransform(base=2.0),
            _to_lut_domain(),
            _warp(nodes_a, nodes_b),
            lut,
            _m44(np.eye(3) / LUT_STEPS_PER_STOP),
            antilog,
            _m44(np.linalg.inv(_mix(e_out))),
        ]
    )


def _cpu(transform: OCIO.Transform) -> OCIO.CPUProcessor:
    return OCIO.Config.CreateRaw().getProcessor(transform).getDefaultCPUProcessor()


def _apply(cpu: OCIO.CPUProcessor, rgb: np.ndarray) -> np.ndarray:
    pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu.applyRGB(pixels)
    return pixels.astype(np.float64)


def _stats(got: np.ndarray, ref: np.ndarray) -> dict[str, float]:
    """Errors in % of each colour's largest channel (white-relative for white)."""
    err = 100 * np.abs(got - ref).max(axis=1) / np.abs(ref).max(axis=1)
    return {
        "max_percent": float(err.max()),
        "p99_percent": float(np.quantile(err, 0.99)),
        "mean_percent": float(err.mean()),
        "samples": len(err),
    }


def _in_gamut(chart: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Random positive mixtures of the chart's patches (colours inside its gamut), max 1."""
    content = rng.dirichlet(np.full(len(chart), 0.3), n) @ chart
    return content / content.max(axis=1, keepdims=True)


def bake_errors(
    correction: PostCorrection, q, q_inverse, target_chart, n: int = 5000
) -> dict[str, Any]:
    """Bake errors of the Q and Q^-1 LUTs, in % of each colour's largest channel.

    ``in_gamut``: content inside the target chart's gamut (random positive mixtures of its
    patches) at exposures 1/64..16, and its exact preimages. ``whole_cube``: Q of random
    non-negative camera RGB, saturated corners included (where the model bends most), where
    Q^-1 finds a non-negative preimage again.
    """
    rng = np.random.default_rng(0)
    chart = np.asarray(target_chart, dtype=np.float64)
    exposure = np.exp2(rng.uniform(-6, 4, (n, 1)))
    content = _in_gamut(chart, n, rng) * exposure
    x = rng.uniform(0.0, 1.0, (n, 3)) * exposure
    q_cpu = _cpu(q)
    q_inverse_cpu = None if q_inverse is None else _cpu(q_inverse)
    out: dict[str, Any] = {}
    for name, c in (("in_gamut", content), ("whole_cube", correction.apply(x))):
        if q_inverse_cpu is None:
            pre = x if name == "whole_cube" else None
            if pre is not None:
                out[name] = {"Q": _stats(_apply(q_cpu, pre), correction.apply(pre))}
            continue
        pre = correction.inverse(c)
        residual = np.max(np.abs(correction.apply(pre) - c), axis=1) / np.max(np.abs(c), axis=1)
        keep = np.all((c >= 0) & (pre >= 0), axis=1) & (residual < 1e-9)
        c, pre = correction.apply(pre[keep]), pre[keep]
        out[name] = {
            "Q": _stats(_apply(q_cpu, pre), c),
            "Q_inverse": _stats(_apply(q_inverse_cpu, c), pre),
        }
    probe = np.random.default_rng(1).uniform(-1.0, 16.0, (4096, 3))
    finite = np.all(np.isfinite(_apply(q_cpu, probe)))
    if q_inverse_cpu is not None:
        finite = finite and np.all(np.isfinite(_apply(q_inverse_cpu, probe)))
    out["finite_on_minus1_to_16"] = bool(finite)
    return out


@dataclass(frozen=True)
class RootPolynomialOutputs:
    """Sidecar files (relative path -> CLF text), their names, and the measured bake errors."""

    q_file: str
    q_inverse_file: str | None
    files: dict[str, str] = field(default_factory=dict)
    block: dict[str, Any] = field(default_factory=dict)


_LUT3D_ARRAY = re.compile(r'(<LUT3D\b[^>]*>\s*<Array dim=")2 2 2 3(">)[^<]*(</Array>)')


def _lut3d_text(values: np.ndarray) -> str:
    """Rows ``"r g b"`` of integer LUT3D entries (size, size^2, 3); a slice equal to the one
    before it (the scale axis's clamp) reuses that slice's text instead of formatting it again."""
    texts: list[str] = []
    for i, block in enumerate(values):
        if i and np.array_equal(block, values[i - 1]):
            texts.append(texts[-1])
        else:
            texts.append(("%d %d %d\n" * len(block)) % tuple(block.ravel().tolist()))
    return "".join(texts)


def _clf(group: OCIO.GroupTransform, description: str) -> str:
    """CLF text of ``group``. OCIO writes everything but the 3D LUT's numbers (integers, see
    :data:`LUT_STEPS_PER_STOP`), which are formatted here, each distinct slice once (OCIO's
    writer formats all 65^3 entries, ~20x slower); the tests read the written files with
    OCIO's processor and ``ociochecklut``."""
    ops = list(group)
    (index,) = [i for i, op in enumerate(ops) if isinstance(op, OCIO.Lut3DTransform)]
    lut = ops[index]
    placeholder = OCIO.Lut3DTransform(gridSize=2)
    placeholder.setInterpolation(lut.getInterpolation())
    shell = OCIO.GroupTransform([*ops[:index], placeholder, *ops[index + 1 :]])
    shell.getFormatMetadata().addChildElement("Description", description)
    text = clf_v3(shell.write(formatName=CLF_FORMAT, config=OCIO.Config.CreateRaw()))
    size = lut.getGridSize()
    values = np.asarray(lut.getData(), dtype=np.float32).astype(np.int64)
    numbers = _lut3d_text(values.reshape(size, size * size, 3))
    text, count = _LUT3D_ARRAY.subn(
        lambda m: f"{m.group(1)}{size} {size} {size} 3{m.group(2)}\n{numbers}{m.group(3)}", text
    )
    if count != 1:
        raise RuntimeError("unexpected CLF layout from OCIO's writer (no single LUT3D array)")
    return text


def root_polynomial_outputs(solution: Solution) -> RootPolynomialOutputs | None:
    """Q and Q^-1 sidecars of a non-linear post-correction (None for a 3x3 Q). Q^-1 is baked
    only where N is solved (the in-frustum drive is then ``M Q^-1(c)``)."""
    correction = solution.correction
    if correction.linear:
        return None
    if solution.N is not None and not correction.invertible:
        raise InputError(
            f"the {correction.kind} post-correction has no inverse, yet N is given: N = M Q^-1 "
            "needs one (re-solve, or set N to null)",
            key="post_correction",
        )
    chart = np.asarray(solution.diagnostics["charts"]["target"], dtype=np.float64)
    invertible = solution.N is not None and correction.invertible
    content = np.vstack([chart, _in_gamut(chart, 2000, np.random.default_rng(5))])
    camera_side = (
        correction.inverse(content)
        if invertible
        else solution.diagnostics["charts"]["lit_baseline"]
    )
    camera_box = content_box(np.asarray(camera_side, dtype=np.float64), CAMERA_MIX)
    content_box_ = content_box(chart, CONTENT_MIX)  # positive mixtures stay inside its ratios
    q = baked_transform(correction.apply, camera_box, CAMERA_MIX, CONTENT_MIX)
    q_inverse = (
        baked_transform(correction.inverse, content_box_, CONTENT_MIX, CAMERA_MIX)
        if invertible
        else None
    )
    errors = bake_errors(correction, q, q_inverse, chart)
    domain = (
        f"scale x direction: log2, a {LUT_SIZE}^3 tetrahedral 3D LUT on (scale, log2 r/g, "
        f"log2 b/g), exposures 2^{SCALE_RANGE[0]:g}..2^{SCALE_RANGE[1]:g}, "
        f"log-ratios +-{RATIO_RANGE:g} stops"
    )
    files, names = {}, []
    groups = [("post_correction_q", q, "Q")]
    if q_inverse is not None:
        groups.append(("post_correction_q_inverse", q_inverse, "Q^-1"))
    for stem, group, what in groups:
        text = _clf(
            group,
            f"ocio_vp {correction.kind} {what} ({correction.describe()}) for stage "
            f"{solution.stage}, environment {solution.environment}: {domain}.",
        )
        name = sidecar_name(f"{solution.stage}_{solution.environment}_{stem}", text)
        files[f"{LUT_DIR}/{name}"] = text
        names.append(name)
    block = {
        "files": list(files),
        "lut_size": LUT_SIZE,
        "domain": domain,
        "content_log_ratios": {"camera": camera_box.tolist(), "content": content_box_.tolist()},
        "bake_error": errors,
    }
    return RootPolynomialOutputs(
        q_file=names[0],
        q_inverse_file=names[1] if len(names) > 1 else None,
        files=files,
        block=block,
    )
