"""A root-polynomial post-correction in OCIO: Q and Q^-1 baked as shaper + 3D LUT CLF sidecars.

A root-polynomial Q (:mod:`ocio_vp.correction.root_polynomial`) is not a matrix, so the config
carries it as LUTs: a per-channel log2 shaper with a linear toe (OCIO ``LogCameraTransform``,
a CLF ``Log`` node), a 65^3 tetrahedral 3D LUT holding ``shaper(F(shaper^-1(grid)))``, and the
inverse shaper. F is Q for footage (the ``Stage Footage`` colorspace and the ``Post-Correction
Q`` named transform) and Q^-1 (exact, Newton: :func:`~ocio_vp.correction.invert_root_polynomial`)
ahead of M for the in-frustum drive, so that drive = M Q^-1(c) + offset. Log in, log out suits a
degree-1 homogeneous model: along any chromaticity the baked function is a shift, which the
interpolation reproduces exactly, and the square roots become linear in log space.

The shaper covers 0 (the toe maps 0 to the LUT's first entry) to :data:`SHAPER_TOP` linear;
inputs outside are clamped by the LUT (finite, but not the model: negatives act as 0). The bake
error is measured on random colours the model reaches (Q of non-negative camera RGB, exposures
1/64..16) and written to ``solution.json`` (``diagnostics.method_notes.root_polynomial.ocio``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.correction.root_polynomial import apply_root_polynomial, invert_root_polynomial
from ocio_vp.formats.solution import Solution
from ocio_vp.ocio.clf import CLF_FORMAT, clf_v3
from ocio_vp.ocio.wall import sidecar_name
from ocio_vp.wall.encoding import LUT_DIR

__all__ = [
    "LUT_SIZE",
    "SHAPER_BREAK",
    "SHAPER_TOP",
    "RootPolynomialOutputs",
    "baked_transform",
    "root_polynomial_outputs",
]

#: 3D LUT grid size (OCIO's largest useful; the bake error at 65 is ~0.1 % of the colour).
LUT_SIZE = 65
#: Linear value where the shaper's log part starts (below: a straight line through 0).
SHAPER_BREAK = 2.0**-8
#: Largest linear value the LUTs represent (scene-linear HDR content, white = 1).
SHAPER_TOP = 16.0

_LOG_LOW = np.log2(SHAPER_BREAK) - 1.0 / np.log(2.0)  # puts linear 0 at shaper 0
_SLOPE = 1.0 / (np.log2(SHAPER_TOP) - _LOG_LOW)


def _shaper(direction=OCIO.TRANSFORM_DIR_FORWARD) -> OCIO.LogCameraTransform:
    shaper = OCIO.LogCameraTransform(linSideBreak=[SHAPER_BREAK] * 3, base=2.0)
    shaper.setLogSideSlopeValue([_SLOPE] * 3)
    shaper.setLogSideOffsetValue([-_LOG_LOW * _SLOPE] * 3)
    shaper.setDirection(direction)
    return shaper


def _shaper_np(x: np.ndarray) -> np.ndarray:
    """The shaper in float64 (the same curve as :func:`_shaper`)."""
    y_break = _SLOPE * (np.log2(SHAPER_BREAK) - _LOG_LOW)
    toe = y_break + _SLOPE / (np.log(2.0) * SHAPER_BREAK) * (x - SHAPER_BREAK)
    return np.where(
        x >= SHAPER_BREAK, _SLOPE * (np.log2(np.maximum(x, SHAPER_BREAK)) - _LOG_LOW), toe
    )


def _shaper_inverse_np(y: np.ndarray) -> np.ndarray:
    y_break = _SLOPE * (np.log2(SHAPER_BREAK) - _LOG_LOW)
    toe = SHAPER_BREAK + (y - y_break) * np.log(2.0) * SHAPER_BREAK / _SLOPE
    return np.where(y >= y_break, np.exp2(y / _SLOPE + _LOG_LOW), toe)


def baked_transform(function, size: int = LUT_SIZE) -> OCIO.GroupTransform:
    """shaper -> 3D LUT of ``shaper(function(shaper^-1(grid)))`` -> inverse shaper."""
    axis = np.linspace(0.0, 1.0, size)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    values = _shaper_np(function(_shaper_inverse_np(grid)))
    if not np.all(np.isfinite(values)):
        raise ValueError("root-polynomial bake produced non-finite LUT entries")
    lut = OCIO.Lut3DTransform(gridSize=size)
    lut.setData(np.ascontiguousarray(values, dtype=np.float32).ravel())  # blue fastest
    lut.setInterpolation(OCIO.INTERP_TETRAHEDRAL)
    return OCIO.GroupTransform([_shaper(), lut, _shaper(OCIO.TRANSFORM_DIR_INVERSE)])


def _apply(transform: OCIO.Transform, rgb: np.ndarray) -> np.ndarray:
    cpu = OCIO.Config.CreateRaw().getProcessor(transform).getDefaultCPUProcessor()
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


def bake_errors(C, q, q_inverse, target_chart, n: int = 20000) -> dict[str, Any]:
    """Bake errors of the Q and Q^-1 LUTs, in % of each colour's largest channel.

    ``in_gamut``: content inside the target chart's gamut (random positive mixtures of its
    patches) at exposures 1/64..16, and its exact preimages. ``whole_cube``: Q of random
    non-negative camera RGB, saturated corners included (where the model bends most).
    """
    rng = np.random.default_rng(0)
    chart = np.asarray(target_chart, dtype=np.float64)
    exposure = np.exp2(rng.uniform(-6, 4, (n, 1)))
    content = rng.dirichlet(np.full(len(chart), 0.3), n) @ chart
    content = content / content.max(axis=1, keepdims=True).max() * exposure
    x = rng.uniform(0.0, 1.0, (n, 3)) * exposure
    out = {}
    for name, c in (("in_gamut", content), ("whole_cube", apply_root_polynomial(C, x))):
        pre = invert_root_polynomial(C, c)
        keep = np.all((c >= 0) & (c <= SHAPER_TOP) & (pre >= 0) & (pre <= SHAPER_TOP), axis=1)
        c, pre = apply_root_polynomial(C, pre[keep]), pre[keep]
        out[name] = {"Q": _stats(_apply(q, pre), c), "Q_inverse": _stats(_apply(q_inverse, c), pre)}
    probe = np.random.default_rng(1).uniform(-1.0, 16.0, (4096, 3))
    out["finite_on_minus1_to_16"] = bool(
        np.all(np.isfinite(_apply(q, probe))) and np.all(np.isfinite(_apply(q_inverse, probe)))
    )
    return out


@dataclass(frozen=True)
class RootPolynomialOutputs:
    """Sidecar files (relative path -> CLF text), their names, and the measured bake errors."""

    q_file: str
    q_inverse_file: str
    files: dict[str, str] = field(default_factory=dict)
    block: dict[str, Any] = field(default_factory=dict)


def _clf(group: OCIO.GroupTransform, description: str) -> str:
    group.getFormatMetadata().addChildElement("Description", description)
    return clf_v3(group.write(formatName=CLF_FORMAT, config=OCIO.Config.CreateRaw()))


def root_polynomial_outputs(solution: Solution) -> RootPolynomialOutputs | None:
    """Q and Q^-1 sidecars for a root-polynomial solve (None for a 3x3 Q or an unsolved N)."""
    notes = solution.diagnostics.get("method_notes") or {}
    model = notes.get("root_polynomial")
    if model is None or solution.N is None:
        return None
    C = np.asarray(model["coefficients"], dtype=np.float64)
    q = baked_transform(lambda x: apply_root_polynomial(C, x))
    q_inverse = baked_transform(lambda c: invert_root_polynomial(C, c))
    errors = bake_errors(C, q, q_inverse, solution.diagnostics["charts"]["target"])
    domain = f"scene-linear [0, {SHAPER_TOP:g}] through a log2 shaper, {LUT_SIZE}^3 3D LUT"
    files, names = {}, []
    for stem, group, what in (
        ("post_correction_q", q, "Q"),
        ("post_correction_q_inverse", q_inverse, "Q^-1"),
    ):
        text = _clf(
            group,
            f"ocio_vp root-polynomial {what} (degree {model['degree']}) for "
            f"stage {solution.stage}, environment {solution.environment}: {domain}.",
        )
        name = sidecar_name(f"{solution.stage}_{solution.environment}_{stem}", text)
        files[f"{LUT_DIR}/{name}"] = text
        names.append(name)
    block = {
        "files": list(files),
        "lut_size": LUT_SIZE,
        "domain": domain,
        "bake_error": errors,
    }
    return RootPolynomialOutputs(q_file=names[0], q_inverse_file=names[1], files=files, block=block)
