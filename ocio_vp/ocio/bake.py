"""A non-linear post-correction in OCIO: LUT chains on scale x direction, exact where it is linear.

A root-polynomial Q or an emitter-protected one (:mod:`ocio_vp.model`) is not a matrix, so the
config carries it (and its inverse) as a chain of CLF v3 operators in sidecar files
(:func:`chain_transform`): exact to float precision where the model is linear, nodes where it
bends. docs/root_polynomial.md (*The config: LUT chains*) describes the chain, its nodes and the
range it carries. How close a chain comes to the model is measured when the config is written
(:func:`model_outputs`: ΔE2000 on the camera range of :mod:`ocio_vp.model.footage_range`),
stored in ``solution.json`` (``diagnostics.post_correction_ocio``) and quoted in the config's
descriptions.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.deprecation import warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.formats.diagnostics import PostCorrectionOCIO
from ocio_vp.formats.solution import Solution
from ocio_vp.metrics import sample_camera_to_xyz
from ocio_vp.model.correction import PostCorrection, ProtectedCorrection, newton_inverse
from ocio_vp.model.footage_range import (
    AGREEMENT_P99,
    AGREEMENT_WORST,
    Agreement,
    agreement,
    calibration_footage_range,
)
from ocio_vp.ocio.clf import CLF_FORMAT, clf_v3, sidecar_name
from ocio_vp.wall.encoding import LUT_DIR

__all__ = [
    "AGREEMENT_P99",
    "AGREEMENT_WORST",
    "CAMERA_MIX",
    "CONTENT_MIX",
    "LINEAR_BREAK",
    "LUT_SIZE",
    "RATIO_RANGE",
    "SCALE_RANGE",
    "LutChain",
    "ModelOutputs",
    "bake",
    "bake_inverse",
    "chain_transform",
    "chart_content",
    "clf_text",
    "content_range",
    "forward_chain",
    "inverse_chain",
    "model_outputs",
    "processor_function",
]

#: 3D LUT grid size (CLF and OCIO take cubes; the scale axis uses only its first slices).
LUT_SIZE = 65
#: Entries of the 1D warp (OCIO keeps a 1D texture on GPU hosts up to 4095).
WARP_SIZE = 4095
#: Mix towards grey on the footage side (Q's input) and on the corrected side (Q^-1's input).
CAMERA_MIX = 0.1
CONTENT_MIX = 0.05
#: The footage side's log is linear below this fraction of the mixed white's mean channel.
LINEAR_BREAK = 2.0**-9
#: log2 of the scale the chains cover: the warp's entries fall on multiples of 2^-6 stop.
SCALE_RANGE = (-40.0, -40.0 + (WARP_SIZE - 1) / 64.0)
#: |log2 r/g| and |log2 b/g| the chains cover; beyond, the ratio is clamped.
RATIO_RANGE = 10.0
#: The 3D LUT holds log2 values in steps of 2^-12 stop (integers, exact in float32 up to
#: +-4096 stops; the rounding, <= 9e-5 relative, is far below the interpolation's error).
LUT_STEPS_PER_STOP = 2.0**12
_LUT_LIMIT = 2.0**24 / LUT_STEPS_PER_STOP - 1.0
#: Scale nodes around the footage side's break (stops from log2 of the break).
BREAK_NODES = (-5.0, -3.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0, 5.0, 8.0)
#: Scale nodes across the emitter protection's brightness fade, and the share of them where it
#: runs for the chart's directions.
FADE_NODES = 40
FADE_CHART_SHARE = 0.6
#: Shares of the direction nodes: by curvature, uniform over the chart's directions, uniform.
DIRECTION_SHARES = (0.55, 0.3, 0.15)
#: Directions whose input has a channel below -PHYSICAL of its largest are no light a camera
#: records: the curvature there does not draw nodes.
PHYSICAL = 0.02
#: Grid the curvature of the departure from L is measured on (per axis).
CURVATURE_GRID = 96
_BASIS = np.array([[1 / 3, 1 / 3, 1 / 3], [1.0, -1.0, 0.0], [0.0, -1.0, 1.0]])


def _mix(e: float) -> np.ndarray:
    """``(1 - e) I + e/3 ones``: every channel of a non-negative colour gets ``e`` of its mean."""
    return (1.0 - e) * np.eye(3) + e / 3.0 * np.ones((3, 3))


def _m44(matrix: np.ndarray, offset: Sequence[float] = (0.0,) * 4) -> OCIO.MatrixTransform:
    m = np.eye(4)
    m[:3, :3] = matrix
    return OCIO.MatrixTransform([float(v) for v in m.ravel()], [float(v) for v in offset])


# ---------------------------------------------------------------------------------------------
# The chain


@dataclass(frozen=True)
class LutChain:
    """One bake's design: the mix ``e``, the reference matrix ``L``, the log's linear break
    (None: a plain log2), and the nodes on each axis of the 3D LUT (``s_nodes`` may be fewer
    than ``size``: the slices beyond are never reached)."""

    mix: float
    reference: np.ndarray
    linear_break: float | None
    s_nodes: np.ndarray
    a_nodes: np.ndarray
    b_nodes: np.ndarray
    size: int = LUT_SIZE

    @property
    def T(self) -> np.ndarray:
        return _mix(self.mix)

    def log(self, y: np.ndarray) -> np.ndarray:
        """The chain's log of (..., 3) ``y`` (float64), as OCIO computes it."""
        y = np.asarray(y, dtype=np.float64)
        if self.linear_break is None:
            return np.log2(np.maximum(y, np.finfo(np.float32).tiny))
        b = self.linear_break
        return np.where(y > b, np.log2(np.maximum(y, b)), np.log2(b) + (y - b) / (b * np.log(2)))

    def antilog(self, v: np.ndarray) -> np.ndarray:
        if self.linear_break is None:
            return np.exp2(v)
        b = self.linear_break
        return np.where(v > np.log2(b), np.exp2(v), b + (v - np.log2(b)) * b * np.log(2))

    def inputs(self, s: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Inputs ``x`` whose coordinates are (s, a, b) (broadcast)."""
        g = s - (a + b) / 3.0
        logs = np.stack(np.broadcast_arrays(a + g, g, b + g), axis=-1)
        return self.antilog(logs) @ np.linalg.inv(self.T).T

    def values(self, function: Callable[[np.ndarray], np.ndarray], x: np.ndarray) -> np.ndarray:
        """The LUT's value ``l(T L^-1 F(x))`` (stops) for inputs ``x``."""
        out = np.asarray(function(x), dtype=np.float64) @ (self.T @ np.linalg.inv(self.reference)).T
        v = self.log(np.nan_to_num(out, nan=0.0, posinf=1e300, neginf=-1e300))
        return np.clip(v, -_LUT_LIMIT, _LUT_LIMIT)

    def describe(self) -> str:
        log = "log2" if self.linear_break is None else f"log2, linear below {self.linear_break:.3g}"
        return (
            f"mix {self.mix:g} towards grey, {log}, a {self.size}^3 tetrahedral 3D LUT on "
            f"(scale, log2 r/g, log2 b/g) with {len(self.s_nodes)} scale nodes over "
            f"2^{SCALE_RANGE[0]:g}..2^{SCALE_RANGE[1]:g} and log-ratios +-{RATIO_RANGE:g} stops"
        )


def _log_transform(linear_break: float | None, inverse: bool = False) -> OCIO.Transform:
    direction = OCIO.TRANSFORM_DIR_INVERSE if inverse else OCIO.TRANSFORM_DIR_FORWARD
    if linear_break is None:
        return OCIO.LogTransform(base=2.0, direction=direction)
    log = OCIO.LogCameraTransform(linSideBreak=[float(linear_break)] * 3, direction=direction)
    log.setBase(2.0)
    return log


def _to_lut_domain() -> OCIO.MatrixTransform:
    """l -> ((s - low) / span, a / (2 R) + 1/2, b / (2 R) + 1/2)."""
    low, high = SCALE_RANGE
    scale = np.diag([1 / (high - low), 1 / (2 * RATIO_RANGE), 1 / (2 * RATIO_RANGE)])
    return _m44(scale @ _BASIS, [-low / (high - low), 0.5, 0.5, 0.0])


def _warp(chain: LutChain) -> OCIO.Lut1DTransform:
    """1D LUT: each axis's value to its position among the 3D LUT's nodes."""
    p = np.linspace(0.0, 1.0, WARP_SIZE)
    low, high = SCALE_RANGE
    k = np.arange(chain.size) / (chain.size - 1)
    ratio = RATIO_RANGE * (2 * p - 1)
    values = np.stack(
        [
            np.interp(low + p * (high - low), chain.s_nodes, k[: len(chain.s_nodes)]),
            np.interp(ratio, chain.a_nodes, k),
            np.interp(ratio, chain.b_nodes, k),
        ],
        axis=-1,
    )
    lut = OCIO.Lut1DTransform(length=WARP_SIZE)
    lut.setData(np.ascontiguousarray(values, dtype=np.float32).ravel())
    return lut


def _snap(nodes: np.ndarray, low: float, high: float) -> np.ndarray:
    """``nodes`` moved onto the warp's own grid (so the warp is exactly linear between them),
    strictly increasing."""
    step = (high - low) / (WARP_SIZE - 1)
    index = np.rint((np.asarray(nodes) - low) / step).astype(int)
    index = np.maximum.accumulate(np.clip(index, 0, WARP_SIZE - 1))
    for i in range(1, len(index)):  # keep them distinct
        index[i] = max(index[i], index[i - 1] + 1)
    return low + step * index


def bake(function: Callable[[np.ndarray], np.ndarray], chain: LutChain) -> np.ndarray:
    """The 3D LUT of ``function`` on ``chain``: (size, size^2, 3) integer steps (s slowest,
    then a, b), the slice after the last scale node repeating it and the rest zeros."""
    n, used = chain.size, len(chain.s_nodes)
    s, a, b = np.meshgrid(chain.s_nodes, chain.a_nodes, chain.b_nodes, indexing="ij")
    x = chain.inputs(s, a, b).reshape(-1, 3)
    return _lut_array(chain.values(function, x).reshape(used, n * n, 3), chain)


def _lut_array(values: np.ndarray, chain: LutChain) -> np.ndarray:
    n, used = chain.size, len(chain.s_nodes)
    out = np.zeros((n, n * n, 3), dtype=np.float32)
    out[:used] = np.rint(values * LUT_STEPS_PER_STOP)
    if used < n:
        out[used] = out[used - 1]  # a clamp: rounding at the last cell's top edge reads the same
    return out


def chain_transform(chain: LutChain, lut: np.ndarray | None) -> OCIO.GroupTransform:
    """The chain's OCIO operators for a baked ``lut`` (:func:`bake`): mix ``T``, log, to
    (scale, a, b) in [0, 1], the warp, the 3D LUT, steps to stops, antilog, ``L T^-1``. With
    ``lut`` None a 2^3 placeholder stands for the 3D LUT (for :func:`clf_text`)."""
    if lut is None:
        lut3d = OCIO.Lut3DTransform(gridSize=2)
    else:
        lut3d = OCIO.Lut3DTransform(gridSize=chain.size)
        lut3d.setData(np.ascontiguousarray(lut, dtype=np.float32).ravel())
    lut3d.setInterpolation(OCIO.INTERP_TETRAHEDRAL)
    return OCIO.GroupTransform(
        [
            _m44(chain.T),
            _log_transform(chain.linear_break),
            _to_lut_domain(),
            _warp(chain),
            lut3d,
            _m44(np.eye(3) / LUT_STEPS_PER_STOP),
            _log_transform(chain.linear_break, inverse=True),
            _m44(chain.reference @ np.linalg.inv(chain.T)),
        ]
    )


# ---------------------------------------------------------------------------------------------
# Node design


def _equidistribute(grid: np.ndarray, density: np.ndarray, count: int) -> np.ndarray:
    """``count`` nodes over ``grid`` (its ends included) spaced by the inverse of ``density``."""
    cdf = np.concatenate([[0.0], np.cumsum((density[1:] + density[:-1]) / 2 * np.diff(grid))])
    return np.interp(np.linspace(0.0, 1.0, count), cdf / cdf[-1], grid)


def _direction_nodes(curvature: np.ndarray, box: tuple[float, float], size: int) -> np.ndarray:
    """Nodes on one log-ratio axis: :data:`DIRECTION_SHARES` of them by the square root of the
    curvature (where linear interpolation errs most), uniform over ``box``, uniform."""
    grid = np.linspace(-RATIO_RANGE, RATIO_RANGE, len(curvature))
    by_curvature, by_box, flat = DIRECTION_SHARES
    root = np.convolve(np.sqrt(np.maximum(curvature, 0.0)), np.ones(3) / 3, mode="same")
    total = np.trapezoid(root, grid)
    span = 2 * RATIO_RANGE
    density = np.full(len(grid), flat / span)
    density += by_curvature * root / total if total > 0 else by_curvature / span
    low, high = box
    density += by_box * ((grid >= low) & (grid <= high)) / max(high - low, 1e-6)
    nodes = _equidistribute(grid, density, size)
    nodes[np.argmin(np.abs(nodes))] = 0.0  # grey (and black) on a node: exact there
    return _snap(nodes, -RATIO_RANGE, RATIO_RANGE)


def _curvature(
    function: Callable[[np.ndarray], np.ndarray], chain: LutChain, scales: list[float]
) -> tuple[np.ndarray, np.ndarray]:
    """Largest |second difference| along a and along b of the departure from L (stops per
    stop^2), over a :data:`CURVATURE_GRID`^2 grid of directions at each of ``scales``."""
    grid = np.linspace(-RATIO_RANGE, RATIO_RANGE, CURVATURE_GRID)
    a, b = np.meshgrid(grid, grid, indexing="ij")
    along_a, along_b = np.zeros(len(grid)), np.zeros(len(grid))
    for s in scales:
        x = chain.inputs(np.full_like(a, s), a, b).reshape(-1, 3)
        d = (chain.values(function, x) - chain.log(x @ chain.T.T)).reshape(len(grid), len(grid), 3)
        # only where light can be (no channel below -PHYSICAL of the largest): elsewhere the
        # model's departure is whatever its formula gives to colours no camera records
        light = x.min(axis=1) >= -PHYSICAL * np.abs(x).max(axis=1)
        d = np.where(
            light.reshape(len(grid), len(grid), 1), np.clip(d, -RATIO_RANGE, RATIO_RANGE), np.nan
        )
        da = np.nan_to_num(np.abs(d[2:] - 2 * d[1:-1] + d[:-2])).max(axis=(1, 2))
        db = np.nan_to_num(np.abs(d[:, 2:] - 2 * d[:, 1:-1] + d[:, :-2])).max(axis=(0, 2))
        along_a[1:-1] = np.maximum(along_a[1:-1], da)
        along_b[1:-1] = np.maximum(along_b[1:-1], db)
    h2 = (grid[1] - grid[0]) ** 2
    return along_a / h2, along_b / h2


def _ratio_box(colours: np.ndarray, mix: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) log-ratios (a, b) of ``colours`` mixed by ``mix``, ``margin`` stops
    wider, over those whose mixed channels are all positive; empty arrays for none."""
    y = np.asarray(colours, dtype=np.float64).reshape(-1, 3) @ _mix(mix).T
    y = y[np.all(y > 0, axis=1)]
    if len(y) == 0:
        return np.empty(0), np.empty(0)
    c = np.log2(y) @ _BASIS.T
    return c.min(axis=0)[1:] - margin, c.max(axis=0)[1:] + margin


def _design(
    curvatures: Sequence[tuple[Callable[[np.ndarray], np.ndarray], np.ndarray, list[float]]],
    *,
    mix: float,
    reference: np.ndarray,
    linear_break: float | None,
    s_nodes: list[float],
    colours: np.ndarray,
    size: int = LUT_SIZE,
) -> LutChain:
    """A :class:`LutChain` whose direction nodes follow the largest curvature of each
    (function, its reference matrix, scales) of ``curvatures``, with a share on ``colours``."""
    low, high = SCALE_RANGE
    nodes = _snap(np.asarray([low, *sorted(s_nodes), high], dtype=np.float64), low, high)
    flat = np.linspace(-RATIO_RANGE, RATIO_RANGE, LUT_SIZE)
    along_a = along_b = np.zeros(CURVATURE_GRID)
    for function, function_reference, scales in curvatures:
        probe = LutChain(mix, function_reference, linear_break, nodes, flat, flat)
        ca, cb = _curvature(function, probe, scales)
        along_a, along_b = np.maximum(along_a, ca), np.maximum(along_b, cb)
    box_low, box_high = _ratio_box(colours, mix, 0.25)
    if len(box_low) == 0:  # no colour of the stage to be finest on: a box around neutral
        box_low, box_high = -np.ones(2), np.ones(2)
    else:
        limit = RATIO_RANGE - 0.5
        box_low, box_high = np.clip(box_low, -limit, limit), np.clip(box_high, -limit, limit)
    return LutChain(
        mix,
        reference,
        linear_break,
        nodes,
        _direction_nodes(along_a, (box_low[0], box_high[0]), size),
        _direction_nodes(along_b, (box_low[1], box_high[1]), size),
        size,
    )


def _reference(correction: PostCorrection) -> np.ndarray:
    """L: the matrix a correction reduces to where it is linear (the identity where the matrix
    has no inverse; for the emitter protection, the identity it hands over to)."""
    if isinstance(correction, ProtectedCorrection) or not correction.invertible:
        return np.eye(3)
    return correction.matrix


def _fade_band(correction, T: np.ndarray, colours: np.ndarray) -> tuple[float, float]:
    """Scales (mean log2 of ``T x``) over which the emitter protection's brightness fade runs
    for the directions of ``colours``: the fade is at fixed brightness, so where it falls in
    scale depends on the direction."""
    y = np.asarray(colours, dtype=np.float64) @ T.T
    y = y[np.all(y > 0, axis=1)]
    brightness = correction.domain.brightness(y @ np.linalg.inv(T).T)
    keep = brightness > 0
    h = np.log2(brightness[keep]) - np.log2(y[keep]).mean(axis=1)
    low, high = correction.bright
    return float(np.log2(low) - h.max() - 0.05), float(np.log2(high) - h.min() + 0.05)


def _light(T: np.ndarray) -> np.ndarray:
    """Camera RGB of directions of light (a grid of log-ratios of ``T x``; no channel below
    -:data:`PHYSICAL` of the largest)."""
    grid = np.linspace(-RATIO_RANGE, RATIO_RANGE, CURVATURE_GRID)
    a, b = np.meshgrid(grid, grid, indexing="ij")
    g = -(a + b) / 3
    x = np.exp2(np.stack([a + g, g, b + g], axis=-1).reshape(-1, 3)) @ np.linalg.inv(T).T
    return x[x.min(axis=1) >= -PHYSICAL * np.abs(x).max(axis=1)]


def _spread(chart: tuple[float, float], light: tuple[float, float], count: int) -> list[float]:
    """``count`` nodes: :data:`FADE_CHART_SHARE` of them over ``chart``, the rest over the rest
    of ``light`` (which holds it), in proportion to its length on each side."""
    start, end = chart
    low, high = min(light[0], start), max(light[1], end)
    inside = round(count * FADE_CHART_SHARE)
    rest = count - inside
    below = round(rest * (start - low) / max(start - low + high - end, 1e-9))
    nodes = [*np.linspace(low, start, below + 1)[:-1], *np.linspace(start, end, inside)]
    return nodes + list(np.linspace(end, high, rest - below + 1)[1:])


def _fade_nodes(correction, T: np.ndarray, colours: np.ndarray) -> list[float]:
    """:data:`FADE_NODES` scale nodes across the brightness fade (:func:`_spread`: the chart's
    directions, and every direction of light: saturated colours reach it at a lower mean)."""
    chart = _fade_band(correction, T, colours)
    light = _fade_band(correction, T, _light(T) @ T.T)
    return _spread(chart, light, FADE_NODES)


def forward_chain(
    correction: PostCorrection, white: np.ndarray, colours: np.ndarray, size: int = LUT_SIZE
) -> LutChain:
    """The footage-side chain of ``correction`` (Q): ``white`` the lit white patch and
    ``colours`` the chart's colours, as the camera records them on the stage.

    Scale nodes around the log's break, and for the emitter protection across its fade; the
    direction nodes follow the curvature of the (inner) model's departure from its matrix."""
    T = _mix(CAMERA_MIX)
    level = float(np.mean(T @ np.asarray(white, dtype=np.float64)))
    # black's scale, log2(break) - 1/ln 2, on a node of the warp's grid: black maps to a node
    # whose value (a multiple of the LUT's step) the inverse log returns to exactly 0
    low, high = SCALE_RANGE
    step = (high - low) / (WARP_SIZE - 1)
    black = low + step * round((np.log2(LINEAR_BREAK * level) - 1 / np.log(2) - low) / step)
    linear_break = float(np.exp2(black + 1 / np.log(2)))
    s_nodes = [black, *(np.log2(linear_break) + o for o in BREAK_NODES)]
    scales = [np.log2(level) - 2.0, np.log2(level)]
    curvatures = [(correction.apply, _reference(correction), scales)]
    if isinstance(correction, ProtectedCorrection):
        fade = _fade_nodes(correction, T, np.vstack([colours, white]))
        s_nodes = [s for s in s_nodes if s < fade[0] - 0.3] + fade + [fade[-1] + 1, fade[-1] + 3]
        # the inner model's departure from its matrix, and (below the fade, where only the
        # negative-light fade acts) the protection's from the identity
        curvatures = [
            (correction.inner.apply, _reference(correction.inner), scales),
            (correction.apply, np.eye(3), [fade[0] - 1.0]),
        ]
    return _design(
        curvatures,
        mix=CAMERA_MIX,
        reference=_reference(correction),
        linear_break=linear_break,
        s_nodes=s_nodes,
        colours=colours,
        size=size,
    )


#: Share of the inverse's direction nodes on the content's log-ratios (+-CONTENT_MARGIN stop).
CONTENT_FRACTION = 0.6
CONTENT_MARGIN = 0.5
#: Scale nodes across the emitter protection's fade on the corrected side.
INVERSE_FADE_NODES = 24


def _content_nodes(low: float, high: float, size: int) -> np.ndarray:
    """Nodes on one log-ratio axis of the inverse: uniform on [low, high]
    (:data:`CONTENT_FRACTION` of them), then steps growing quadratically out to the range."""
    n_out = round((size - 1) * (1 - CONTENT_FRACTION) / 2)
    n_in = size - 1 - 2 * n_out
    h = (high - low) / n_in
    t = np.arange(1, n_out + 1)
    g_low = (RATIO_RANGE + low - n_out * h) / n_out**2
    g_high = (RATIO_RANGE - high - n_out * h) / n_out**2
    nodes = np.concatenate(
        [
            (low - h * t - g_low * t**2)[::-1],
            low + h * np.arange(n_in + 1),
            high + h * t + g_high * t**2,
        ]
    )
    return _snap(nodes, -RATIO_RANGE, RATIO_RANGE)


def inverse_chain(
    correction: PostCorrection, content: np.ndarray, size: int = LUT_SIZE
) -> LutChain:
    """The corrected-side chain of Q^-1; ``content`` the colours it is finest on (the target
    chart and mixtures of it). A plain log2: content is light, its mixed channels positive."""
    low, high = _ratio_box(content, CONTENT_MIX, CONTENT_MARGIN)
    if len(low) == 0:
        # the target chart is in the content: only a chart none of whose patches (its white
        # included) is non-negative and lit gets here; refuse rather than guess a box
        raise InputError("no target chart colour has light in every channel: Q^-1 cannot be baked")
    limit = RATIO_RANGE - 1.0
    low, high = np.maximum(low, -limit), np.minimum(high, limit)
    s_nodes = list(SCALE_RANGE)
    if isinstance(
        correction, ProtectedCorrection
    ):  # the fade, where the preimage's brightness crosses it
        s_nodes[1:1] = _fade_band_content(correction, content)
    reference = np.linalg.inv(_reference(correction))
    return LutChain(
        CONTENT_MIX,
        reference,
        None,
        _snap(np.asarray(s_nodes), *SCALE_RANGE),
        _content_nodes(low[0], high[0], size),
        _content_nodes(low[1], high[1], size),
        size,
    )


def _content_scales(correction, x: np.ndarray) -> tuple[float, float]:
    """Scales of the corrected side where footage of the directions of ``x`` crosses the
    emitter protection's fade: its images at the fade's two brightnesses."""
    x = x[correction.domain.brightness(x) > 0]
    unit = x / correction.domain.brightness(x)[:, None]
    T = _mix(CONTENT_MIX)
    scales = []
    for level in correction.bright:
        y = correction.apply(unit * level) @ T.T
        y = y[np.all(y > 0, axis=1)]
        scales.append(np.log2(y).mean(axis=1))
    return float(scales[0].min() - 0.25), float(scales[1].max() + 0.25)


def _fade_band_content(correction, content: np.ndarray) -> list[float]:
    """:data:`INVERSE_FADE_NODES` scale nodes of the corrected side across the fade, spread as
    :func:`_fade_nodes` does (the content's directions, and the images of every direction of
    light)."""
    chart = _content_scales(correction, correction.inverse(np.asarray(content)))
    light = _content_scales(correction, _light(_mix(CAMERA_MIX)))
    return _spread(chart, light, INVERSE_FADE_NODES)


#: Newton steps per slice of the inverse (each started from the slice below: a few suffice;
#: a colour with no preimage, where the model folds, keeps its best iterate).
INVERSE_ITERATIONS = 8


def _solved(function, c: np.ndarray, start: np.ndarray | None, matrix: np.ndarray) -> np.ndarray:
    return newton_inverse(
        function, c, matrix, homogeneous=False, start=start, max_iterations=INVERSE_ITERATIONS
    )


def bake_inverse(correction: PostCorrection, chain: LutChain) -> np.ndarray:
    """The 3D LUT of Q^-1 on ``chain`` (:func:`inverse_chain`), as :func:`bake` returns it.

    A homogeneous Q^-1 is solved once on the directions (Newton, :meth:`inverse`) and shifted
    along the scale; the emitter protection's, slice by slice across its fade, each slice
    started from the one below it (scaled), below the fade from its homogeneous part and above
    it the identity."""
    n = chain.size
    a, b = np.meshgrid(chain.a_nodes, chain.b_nodes, indexing="ij")
    s_nodes = chain.s_nodes
    values = np.empty((len(s_nodes), n * n, 3))
    if not isinstance(correction, ProtectedCorrection):
        c = chain.inputs(np.zeros_like(a), a, b).reshape(-1, 3)
        x = correction.inverse(c)
        level = chain.values(lambda _: x, c)
        for i, s in enumerate(s_nodes):
            values[i] = level + s
        return _lut_array(np.clip(values, -_LUT_LIMIT, _LUT_LIMIT), chain)
    below = s_nodes[1] - 3.0  # under the fade for every direction: homogeneous there
    c = chain.inputs(np.full_like(a, below), a, b).reshape(-1, 3)
    x = _solved(correction.apply, c, None, correction.inner.matrix)
    values[0] = chain.values(lambda _: x * np.exp2(s_nodes[0] - below), c)
    previous = below
    for i, s in enumerate(s_nodes[1:-1], start=1):
        c = chain.inputs(np.full_like(a, s), a, b).reshape(-1, 3)
        x = _solved(correction.apply, c, x * np.exp2(s - previous), correction.inner.matrix)
        values[i] = chain.values(_returning(x), c)
        previous = s
    c = chain.inputs(np.full_like(a, s_nodes[-1]), a, b).reshape(-1, 3)
    values[-1] = chain.values(lambda _: c, c)  # the identity above the fade
    return _lut_array(values, chain)


# ---------------------------------------------------------------------------------------------
# CLF text


_LUT3D_ARRAY = re.compile(r'(<LUT3D\b[^>]*>\s*<Array dim=")2 2 2 3(">)[^<]*(</Array>)')


def _lut3d_text(values: np.ndarray) -> str:
    """Rows ``"r g b"`` of integer LUT3D entries (size, size^2, 3); a slice equal to the one
    before it (the zeros past the last scale node) reuses that slice's text."""
    texts: list[str] = []
    for i, block in enumerate(values):
        if i and np.array_equal(block, values[i - 1]):
            texts.append(texts[-1])
        else:
            texts.append(
                ("%d %d %d\n" * len(block)) % tuple(block.astype(np.int64).ravel().tolist())
            )
    return "".join(texts)


def clf_text(chain: LutChain, lut: np.ndarray, description: str) -> str:
    """CLF text of the chain. OCIO writes every operator but the 3D LUT's numbers (integers,
    :data:`LUT_STEPS_PER_STOP`), which are formatted here, each distinct slice once (OCIO's
    writer formats all 65^3 entries, much slower); the tests read the files back with OCIO."""
    shell = chain_transform(chain, None)
    shell.getFormatMetadata().addChildElement("Description", description)
    text = clf_v3(shell.write(formatName=CLF_FORMAT, config=OCIO.Config.CreateRaw()))
    numbers = _lut3d_text(np.asarray(lut, dtype=np.float32).reshape(chain.size, -1, 3))
    size = chain.size
    text, count = _LUT3D_ARRAY.subn(
        lambda m: f"{m.group(1)}{size} {size} {size} 3{m.group(2)}\n{numbers}{m.group(3)}", text
    )
    if count != 1:
        raise RuntimeError("unexpected CLF layout from OCIO's writer (no single LUT3D array)")
    return text


# ---------------------------------------------------------------------------------------------
# The sidecars of a solution, and how close they come to the model


def _cpu(transform: OCIO.Transform) -> Callable[[np.ndarray], np.ndarray]:
    return processor_function(OCIO.Config.CreateRaw().getProcessor(transform))


def _returning(x: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """A function of one argument that returns ``x`` whatever it is given."""
    return lambda _: x


def processor_function(processor: OCIO.Processor) -> Callable[[np.ndarray], np.ndarray]:
    """An OCIO processor as a function on (n, 3) RGB: its default CPU processor, float32 in,
    float64 out (what a host computes)."""
    cpu = processor.getDefaultCPUProcessor()

    def apply(rgb: np.ndarray) -> np.ndarray:
        pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
        cpu.applyRGB(pixels)
        return pixels.astype(np.float64)

    return apply


@dataclass(frozen=True)
class ModelOutputs:
    """Sidecar files (relative path -> CLF text), the Q and Q^-1 file names (Q^-1 None where
    the correction has no inverse), Q's agreement with the model, and the
    ``post_correction_ocio`` block of ``solution.json`` (Q^-1's agreement there)."""

    q_file: str
    q_inverse_file: str | None
    forward: Agreement
    files: dict[str, str] = field(default_factory=dict)
    block: PostCorrectionOCIO | None = None

    @property
    def inverse(self) -> Agreement | None:
        """Deprecated: Q^-1's agreement with the model (``block.inverse_agreement``)."""
        warn_deprecated("ModelOutputs.inverse", "ModelOutputs.block.inverse_agreement")
        return None if self.block is None else self.block.inverse_agreement

    def note(self) -> str:
        """One sentence for descriptions: how close the chain is, and what to use where it is
        not close enough."""
        p99, worst = self.forward.overall
        text = (
            f"The LUT chain agrees with the exact model within {p99:.2g} ΔE2000 (p99) and "
            f"{worst:.2g} (worst) over the camera range (surfaces at 1/16-4x, near black with "
            "noise, highlights to 16x white, the wall's primaries)"
        )
        if self.forward.within(AGREEMENT_P99, AGREEMENT_WORST):
            return text + "."
        over = [
            k
            for k in self.forward.worst
            if k != "all"
            and (self.forward.worst[k] > AGREEMENT_WORST or self.forward.p99[k] > AGREEMENT_P99)
        ]
        return (
            f"{text}: beyond {AGREEMENT_P99:g}/{AGREEMENT_WORST:g} on {', '.join(over)}, where "
            "the model bends faster than the LUT's nodes. For exact results use the DCTL "
            "(Resolve export) or ocio-vp apply."
        )


def chart_content(chart: np.ndarray) -> np.ndarray:
    """The target chart and random positive mixtures of its patches (the inverse's content)."""
    mixtures = _mixture_weights(len(chart)) @ chart
    return np.vstack([chart, mixtures / mixtures.max(axis=1, keepdims=True)])


@functools.lru_cache(maxsize=4)
def _mixture_weights(patches: int) -> np.ndarray:
    """(2000, patches) fixed random mixture weights: the same for every environment of a
    stage, so drawn once per process rather than once per environment."""
    weights = np.random.default_rng(5).dirichlet(np.full(patches, 0.3), 2000)
    weights.setflags(write=False)
    return weights


def model_outputs(solution: Solution) -> ModelOutputs | None:
    """The Q (and, where it has one, Q^-1) sidecars of a non-linear post-correction, None for
    a matrix. Q^-1 is baked whenever the correction is invertible: the in-frustum drive is
    ``[SL]^-1 Q^-1(c)`` where N is solved, and it is the explicit inverse of ``Stage
    Footage``."""
    correction = solution.correction
    if correction.linear:
        return None
    if solution.N is not None and not correction.invertible:
        raise InputError(
            f"the {correction.kind} post-correction has no inverse, yet N is given: N = M Q^-1 "
            "needs one (re-solve, or set N to null)",
            key="post_correction",
        )
    charts = solution.diagnostics.charts
    if charts is None:
        raise InputError("no charts to bake the post-correction on", key="diagnostics.charts")
    white = solution.diagnostics.white_patch
    lit, target = charts.lit_baseline, charts.target
    footage = calibration_footage_range(
        lit_chart=lit, white_patch=white, target_white=target[white], SL=solution.SL,
        camera_to_xyz=sample_camera_to_xyz(),
    )  # fmt: skip
    forward = forward_chain(correction, lit[white], np.vstack([lit, target]))
    lut = bake(_model_function(correction), forward)
    measured = agreement(footage, correction.apply, _cpu(chain_transform(forward, lut)))
    chains = [("post_correction_q", forward, lut, "Q")]
    measured_inverse = None
    if correction.invertible:
        backward = inverse_chain(correction, chart_content(target))
        inverse_lut = bake_inverse(correction, backward)
        q_inverse = _cpu(chain_transform(backward, inverse_lut))
        content = content_range(footage, correction)
        measured_inverse = agreement(content, lambda c: c, lambda c: correction.apply(q_inverse(c)))
        chains.append(("post_correction_q_inverse", backward, inverse_lut, "Q^-1"))
    return _outputs(solution, chains, measured, measured_inverse)


def _model_function(correction) -> Callable[[np.ndarray], np.ndarray]:
    """``correction.apply`` on (n, 3) float64 rows, evaluated by the model's per-pixel function
    (:func:`ocio_vp.model.pixels.pixel_function`: the same formulas to float64 rounding, several
    times faster on a LUT's 65^3 grid); the bake's agreement is still measured against
    ``correction.apply`` itself."""
    from ocio_vp.model.pixels import pixel_function

    f = pixel_function(correction, np.float64)
    return lambda x: f(np.ascontiguousarray(np.asarray(x, dtype=np.float64).T)).T


def content_range(footage, correction):
    """The corrected images of the footage range's surfaces, highlights and emitters (near
    black noise is not content), those the corrected side's chain holds (every mixed channel
    positive): what the inverse chain is checked on."""
    from ocio_vp.model.footage_range import FootageRange

    T = _mix(CONTENT_MIX)
    sets = {}
    for name, x in footage.sets.items():
        if name != "near_black":
            c = correction.apply(x)
            sets[name] = c[np.all(c @ T.T > 0, axis=1)]
    return FootageRange(sets, footage.camera_to_xyz, footage.white)


def _outputs(solution, chains, measured, measured_inverse) -> ModelOutputs:
    correction = solution.correction
    files, names, designs = {}, [], {}
    for stem, chain, lut, what in chains:
        text = clf_text(
            chain,
            lut,
            f"ocio_vp {correction.kind} {what} ({correction.describe()}) for stage "
            f"{solution.stage}, environment {solution.environment}: {chain.describe()}.",
        )
        name = sidecar_name(f"{solution.stage}_{solution.environment}_{stem}", text)
        files[f"{LUT_DIR}/{name}"] = text
        names.append(name)
        designs[what] = chain.describe()
    block = PostCorrectionOCIO(
        files=list(files),
        lut_size=LUT_SIZE,
        chains=designs,
        agreement=measured,
        inverse_agreement=measured_inverse,
    )
    return ModelOutputs(
        q_file=names[0],
        q_inverse_file=names[1] if len(names) > 1 else None,
        forward=measured,
        files=files,
        block=block,
    )
