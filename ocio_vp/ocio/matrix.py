"""OCIO MatrixTransforms written so that the same solve gives the same file on every machine."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.ocio import description
from ocio_vp.ocio.description import Transform

__all__ = ["format_matrix", "matrix_record", "matrix_transform"]


def matrix_transform(
    matrix: np.ndarray,
    offset: Sequence[float] | np.ndarray | None = None,
    direction: OCIO.TransformDirection = OCIO.TRANSFORM_DIR_FORWARD,
) -> OCIO.MatrixTransform:
    """An OCIO MatrixTransform computing ``matrix @ rgb + offset`` (alpha untouched), as
    :func:`matrix_record` writes it."""
    m44, off = _m44(matrix, offset)
    return OCIO.MatrixTransform(matrix=m44, offset=off, direction=direction)


def matrix_record(
    matrix: np.ndarray, offset: Sequence[float] | np.ndarray | None = None, *, inverse: bool = False
) -> Transform:
    """The MatrixTransform record of ``matrix @ rgb + offset``, to 12 significant digits
    (beyond, the digits are the solve's rounding and differ between machines)."""
    return description.matrix(*_m44(matrix, offset), inverse=inverse)


def _m44(
    matrix: np.ndarray, offset: Sequence[float] | np.ndarray | None
) -> tuple[list[float], list[float]]:
    m44 = np.eye(4)
    m44[:3, :3] = _significant(np.asarray(matrix, dtype=np.float64))
    off = np.zeros(4)
    if offset is not None:
        off[:3] = _significant(np.asarray(offset, dtype=np.float64))
    return [float(v) for v in m44.ravel()], [float(v) for v in off]


def _zeroed(values: np.ndarray) -> np.ndarray:
    """``values`` with the entries below 1e-12 of the largest (rounding) set to 0."""
    top = float(np.max(np.abs(values), initial=0.0))
    return np.where(np.abs(values) <= 1e-12 * top, 0.0, values)


def _significant(values: np.ndarray) -> np.ndarray:
    """``values`` to 12 significant digits, rounding (:func:`_zeroed`) as 0."""
    values = _zeroed(values)
    return np.array([float(f"{v:.12g}") for v in values.ravel()]).reshape(values.shape)


def format_matrix(matrix: np.ndarray | None) -> str:
    """A matrix as config descriptions print it: 6 digits, rounding (:func:`_zeroed`) as 0."""
    if matrix is None:
        return "none"
    matrix = _zeroed(np.asarray(matrix, dtype=np.float64))
    return "[" + "; ".join(" ".join(f"{v:.6g}" for v in row) for row in matrix) + "]"
