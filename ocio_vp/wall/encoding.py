"""The wall's signal: the linearity LUT table and the signal encoding, in numpy.

The OCIO transforms built from them are in :mod:`ocio_vp.ocio.wall`.

Chain (reference -> wall signal), for both ``LED Wall - Outer Frustum`` (M) and
``LED Wall - Inner Frustum`` (N + offset)::

    matrix  ->  FileTransform luts/<stage>_panel_linearity_<hash>.clf  ->  encoding

The LUT is the inverse of each channel's measured response (:mod:`ocio_vp.wall.linearity`), in
linear drive (1.0 = the level of ``primaries``). A plain 1D LUT clamps its input to [0, 1],
and a half-domain LUT has 65536 entries (over the 4095 that stay a 1D texture on GPU hosts), so
the sidecar is a *shaper + LUT*: a scale by ``1/H`` (a CLF Matrix node) then a 4095-entry LUT
over drive [0, H]. Above drive 1.0 the table is the identity, which linear interpolation
reproduces exactly, so HDR drive up to ``H`` passes unchanged; ``H`` follows the encoding:

- ``linear``: ``H`` = :data:`LINEAR_HEADROOM` (16, four stops above the ramp's top step);
- ``gamma2.4``: ``H`` = 1 (the encoded signal cannot exceed 1.0; the wall clips there anyway);
- ``pq``: ``H`` = ceil(10000 / peak_nits) (PQ's own ceiling, drive 1.0 shown at ``peak_nits``).

``H`` is a whole number and the LUT has ``floor(4094 / H) * H + 1`` entries so that drive 1.0 is
a knot. The price is resolution below 1.0: ``floor(4094 / H)`` intervals per unit of drive
(4094 for gamma 2.4, 255 for linear, 409 for PQ at 1000 nits).

Drive below 0 (outside the LED gamut) is sent as black, as the wall would show it.

Encodings: ``gamma2.4`` is ``drive^(1/2.4)`` (OCIO ExponentTransform, inverse direction;
BT.1886 with a zero black), ``pq`` is SMPTE ST 2084 of ``drive * peak_nits`` (a scale to
OCIO's nits/100 then the builtin ``CURVE - LINEAR_to_ST-2084``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ocio_vp.wall.linearity import CHANNELS, inverse_response, response_model

if TYPE_CHECKING:
    from ocio_vp.formats.solution import Solution

__all__ = [
    "DEFAULT_PEAK_NITS",
    "LINEAR_HEADROOM",
    "LUT_SIZE",
    "WALL_ENCODINGS",
    "apply_lut",
    "check_encoding",
    "encode",
    "lut_accuracy",
    "lut_domain_max",
    "lut_table",
    "with_wall_encoding",
]

WALL_ENCODINGS = ("linear", "gamma2.4", "pq")
DEFAULT_PEAK_NITS = 1000.0
#: LUT domain above drive 1.0 for a linear (float) wall signal: four stops of headroom.
LINEAR_HEADROOM = 16.0
#: <= 4095 entries: the LUT stays a 1D texture on GPU hosts (OCIO's limit for 1D textures).
LUT_SIZE = 4095
LUT_DIR = "luts"
CLF_FORMAT = "Academy/ASC Common LUT Format"
#: Dense check grid for the LUT's accuracy (drive in [0, 1]).
_CHECK_POINTS = 20001

_PQ = {  # SMPTE ST 2084:2014 constants
    "m1": 2610 / 16384,
    "m2": 2523 / 4096 * 128,
    "c1": 3424 / 4096,
    "c2": 2413 / 4096 * 32,
    "c3": 2392 / 4096 * 32,
}


def check_encoding(encoding: str, peak_nits: float) -> None:
    if encoding not in WALL_ENCODINGS:
        raise ValueError(f"unknown wall encoding {encoding!r}; expected one of {WALL_ENCODINGS}")
    if not (np.isfinite(peak_nits) and 0 < peak_nits <= 10000):
        raise ValueError(f"peak_nits must be in (0, 10000], got {peak_nits!r}")


def lut_domain_max(encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> float:
    """``H``: the largest drive the LUT passes (see the module docstring)."""
    check_encoding(encoding, peak_nits)
    if encoding == "gamma2.4":
        return 1.0
    if encoding == "pq":  # a whole number, so drive 1.0 falls on a LUT knot
        return float(max(1, math.ceil(10000.0 / peak_nits - 1e-9)))
    return LINEAR_HEADROOM


def encode(drive: np.ndarray, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> np.ndarray:
    """Numpy model of the wall encoding: linear drive (..., 3) -> wall signal.

    Examples
    --------
    >>> [round(float(v), 6) for v in encode(np.array([0.1, 1.0]), "pq", peak_nits=1000)]
    [0.508078, 0.751827]
    >>> round(float(encode(np.array(0.5), "gamma2.4")), 6)
    0.749154
    """
    check_encoding(encoding, peak_nits)
    drive = np.asarray(drive, dtype=np.float64)
    if encoding == "linear":
        return drive
    if encoding == "gamma2.4":
        return np.maximum(drive, 0.0) ** (1 / 2.4)
    y = np.maximum(drive * peak_nits / 10000.0, 0.0) ** _PQ["m1"]
    return ((_PQ["c1"] + _PQ["c2"] * y) / (1 + _PQ["c3"] * y)) ** _PQ["m2"]


# --------------------------------------------------------------------------------------------
# The LUT sidecar.


def lut_table(
    linearity: Mapping[str, Any], *, domain_max: float, size: int = LUT_SIZE
) -> np.ndarray:
    """The LUT (n, 3) over drive ``[0, domain_max]``: ``r^-1(x)`` for corrected channels,
    the identity for the others and above drive 1.0.

    ``n <= size`` is chosen so that drive 1.0 is a knot (``domain_max`` is a whole number):
    the identity above it is then reproduced exactly by linear interpolation.
    """
    per_unit = (size - 1) // int(domain_max)
    x = np.linspace(0.0, domain_max, per_unit * int(domain_max) + 1)
    table = np.repeat(x[:, None], 3, axis=1)
    for k, name in enumerate(CHANNELS):
        channel = linearity["channels"][name]
        if channel["corrected"]:
            table[:, k] = inverse_response(
                np.asarray(channel["drive"]), np.asarray(channel["response"]), x
            )
    return table


def apply_lut(table: np.ndarray, domain_max: float, rgb: np.ndarray) -> np.ndarray:
    """Numpy model of the sidecar: scale by ``1/domain_max``, clamp to [0, 1], interpolate."""
    rgb = np.asarray(rgb, dtype=np.float64)
    n = table.shape[0]
    position = np.clip(rgb / domain_max, 0.0, 1.0) * (n - 1)
    index = np.minimum(np.floor(position).astype(int), n - 2)
    frac = position - index
    out = np.empty_like(position)
    for k in range(3):
        column = table[:, k]
        i = index[..., k]
        out[..., k] = column[i] * (1 - frac[..., k]) + column[i + 1] * frac[..., k]
    return out


def lut_accuracy(linearity: Mapping[str, Any], table: np.ndarray, domain_max: float) -> float:
    """max |r(LUT(x)) - x| over drive [0, 1]: how linear the modelled panel is after the LUT."""
    x = np.linspace(0.0, 1.0, _CHECK_POINTS)
    corrected = apply_lut(table, domain_max, np.repeat(x[:, None], 3, axis=1))
    worst = 0.0
    for k, name in enumerate(CHANNELS):
        channel = linearity["channels"][name]
        if channel["corrected"]:
            model = response_model(np.asarray(channel["drive"]), np.asarray(channel["response"]))
            # the LUT's output can pass 1.0 by an ulp; the response is linear there
            drive = np.clip(corrected[:, k], 0.0, 1.0)
            worst = max(worst, float(np.max(np.abs(model(drive) - x))))
    return worst


def with_wall_encoding(
    solution: Solution, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS
) -> Solution:
    """A copy of ``solution`` whose ``linearity`` block records the wall signal encoding."""
    check_encoding(encoding, peak_nits)
    if encoding == "linear" and solution.linearity is None:
        return solution
    linearity = dict(solution.linearity or {"measured": False, "model": "linear (assumed)"})
    linearity["wall_encoding"] = {"name": encoding}
    if encoding == "pq":
        linearity["wall_encoding"]["peak_nits"] = float(peak_nits)
    return dataclasses.replace(solution, linearity=linearity)
