"""The wall's signal: the encodings and the panel-linearity LUT, in numpy.

The OCIO transforms built from them are in :mod:`ocio_vp.ocio.wall`. Encodings: ``gamma2.4``
is ``drive^(1/2.4)`` (BT.1886 with a zero black); ``srgb`` is the IEC 61966-2-1 piecewise
curve; ``pq`` is SMPTE ST 2084 of ``drive * peak_nits``. The LUT sidecar, spaced in the wall's
own signal (through the encoding, or a log2 shaper for a linear wall), is described in
docs/linearity.md ("The LUT sidecar").
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ocio_vp.choices import DEFAULT_PEAK_NITS, WALL_ENCODINGS
from ocio_vp.formats.jsontypes import JsonMapping, JsonObject
from ocio_vp.formats.linearity import Linearity, WallEncodingBlock, assumed_linearity
from ocio_vp.wall.linearity import CHANNELS, inverse_response, response_model

if TYPE_CHECKING:
    import PyOpenColorIO as OCIO

    from ocio_vp.formats.solution import Solution

__all__ = [
    "ACCURACY_BANDS",
    "DEFAULT_PEAK_NITS",
    "LINEAR_HEADROOM",
    "LOG_SHAPER_KNEE",
    "LUT_ACCURACY",
    "LUT_SIZE",
    "WALL_ENCODINGS",
    "LinearityLut",
    "WallEncoding",
    "apply_lut",
    "check_encoding",
    "decode",
    "encode",
    "lut_accuracy",
    "lut_drive",
    "lut_table",
    "shaper",
    "with_wall_encoding",
]

#: LUT domain above drive 1.0 for a linear (float) wall signal: four stops of headroom.
LINEAR_HEADROOM = 16.0
#: Where the linear wall's log2 shaper turns from linear to logarithmic (fraction of drive 1.0).
LOG_SHAPER_KNEE = 1e-4
#: <= 4095 entries: the LUT stays a 1D texture on GPU hosts (OCIO's limit for 1D textures).
LUT_SIZE = 4095
LUT_DIR = "luts"
#: Levels (fraction of drive 1.0) the LUT's accuracy is reported over: ``max_error`` is the
#: worst relative error from 0.2% of peak up, the bands say where it is.
ACCURACY_BANDS = ((0.001, 0.002), (0.002, 0.02), (0.02, 1.0))
#: What :func:`lut_accuracy` measures (the ``definition`` of ``linearity.lut``).
LUT_ACCURACY = "max |r(LUT(x)) - x| / x, x = linear drive (1.0 = top step)"
_CHECK_POINTS = 20001
_SHAPER_SCALE = np.log2(1.0 + LINEAR_HEADROOM / LOG_SHAPER_KNEE)  # the shaper's t at drive H

_PQ = {  # SMPTE ST 2084:2014 constants
    "m1": 2610 / 16384,
    "m2": 2523 / 4096 * 128,
    "c1": 3424 / 4096,
    "c2": 2413 / 4096 * 32,
    "c3": 2392 / 4096 * 32,
}
_SRGB_BREAK = 0.0031308  # IEC 61966-2-1: linear segment below this (signal 0.04045)


def check_encoding(encoding: str, peak_nits: float) -> None:
    if encoding not in WALL_ENCODINGS:
        raise ValueError(f"unknown wall encoding {encoding!r}; expected one of {WALL_ENCODINGS}")
    if not (np.isfinite(peak_nits) and 0 < peak_nits <= 10000):
        raise ValueError(f"peak_nits must be in (0, 10000], got {peak_nits!r}")


def encode(drive: np.ndarray, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> np.ndarray:
    """Numpy model of the wall encoding: linear drive (...) -> wall signal (negatives -> 0).

    Examples
    --------
    >>> [round(float(v), 6) for v in encode(np.array([0.1, 1.0]), "pq", peak_nits=1000)]
    [0.508078, 0.751827]
    >>> round(float(encode(np.array(0.5), "gamma2.4")), 6)
    0.749154
    >>> [round(float(v), 6) for v in encode(np.array([0.001, 0.5]), "srgb")]
    [0.01292, 0.735357]
    """
    check_encoding(encoding, peak_nits)
    drive = np.asarray(drive, dtype=np.float64)
    if encoding == "linear":
        return drive
    d = np.maximum(drive, 0.0)
    if encoding == "gamma2.4":
        return d ** (1 / 2.4)
    if encoding == "srgb":
        return np.where(d <= _SRGB_BREAK, 12.92 * d, 1.055 * d ** (1 / 2.4) - 0.055)
    y = (d * peak_nits / 10000.0) ** _PQ["m1"]
    return ((_PQ["c1"] + _PQ["c2"] * y) / (1 + _PQ["c3"] * y)) ** _PQ["m2"]


def decode(
    signal: np.ndarray, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS
) -> np.ndarray:
    """Inverse of :func:`encode`: wall signal (...) -> linear drive (signal below 0 -> 0).

    Examples
    --------
    >>> round(float(decode(np.array(0.508078), "pq")), 6)
    0.1
    >>> round(float(decode(np.array(0.735357), "srgb")), 6)
    0.5
    """
    check_encoding(encoding, peak_nits)
    signal = np.asarray(signal, dtype=np.float64)
    if encoding == "linear":
        return signal
    t = np.maximum(signal, 0.0)
    if encoding == "gamma2.4":
        return t**2.4
    if encoding == "srgb":
        return np.where(t <= 12.92 * _SRGB_BREAK, t / 12.92, ((t + 0.055) / 1.055) ** 2.4)
    p = t ** (1 / _PQ["m2"])
    y = np.maximum(p - _PQ["c1"], 0.0) / (_PQ["c2"] - _PQ["c3"] * p)
    return y ** (1 / _PQ["m1"]) * 10000.0 / peak_nits


def shaper(drive: np.ndarray, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> np.ndarray:
    """The LUT's input ``t`` for linear drive: the encoded signal, or the linear wall's log2
    shaper (see the module docstring). ``t`` in [0, 1] spans the LUT.

    Examples
    --------
    >>> [round(float(v), 6) for v in shaper(np.array([0.0, 1.0, LINEAR_HEADROOM]), "linear")]
    [0.0, 0.76863, 1.0]
    """
    if encoding != "linear":
        return encode(drive, encoding, peak_nits=peak_nits)
    drive = np.asarray(drive, dtype=np.float64)
    return np.log2(1.0 + np.maximum(drive, 0.0) / LOG_SHAPER_KNEE) / _SHAPER_SCALE


def _unshape(t: np.ndarray, encoding: str, peak_nits: float) -> np.ndarray:
    if encoding != "linear":
        return decode(t, encoding, peak_nits=peak_nits)
    return (np.exp2(np.asarray(t, dtype=np.float64) * _SHAPER_SCALE) - 1.0) * LOG_SHAPER_KNEE


#: OCIO's ``encoding`` attribute of the wall colorspaces, per wall signal (docs/linearity.md).
_OCIO_ENCODINGS = {
    "linear": "scene-linear",
    "gamma2.4": "sdr-video",
    "srgb": "sdr-video",
    "pq": "hdr-video",
}


@dataclasses.dataclass(frozen=True)
class WallEncoding:
    """The signal the wall receives: its ``name`` (one of :data:`WALL_ENCODINGS`) and, for PQ,
    the wall's ``peak_nits`` at drive 1.0 (None for the others).

    One object for every step that needs the wall's signal: :meth:`encode`/:meth:`decode`
    (numpy), :meth:`ocio_transforms` (the same curve in OpenColorIO), and the
    ``linearity.wall_encoding`` block of ``solution.json`` (:meth:`to_dict`,
    :meth:`from_dict`).

    >>> WallEncoding("pq", 1000.0).signal_top
    10.0
    >>> WallEncoding.from_dict(None).linear
    True
    """

    name: str = "linear"
    peak_nits: float | None = None

    def __post_init__(self) -> None:
        peak = self.peak_nits
        if self.name == "pq":
            peak = DEFAULT_PEAK_NITS if peak is None else float(peak)
            check_encoding(self.name, peak)
        else:
            check_encoding(self.name, DEFAULT_PEAK_NITS)
            peak = None
        object.__setattr__(self, "peak_nits", peak)

    @classmethod
    def from_dict(cls, block: JsonMapping | None) -> WallEncoding:
        """The ``wall_encoding`` block (None or missing: a linear wall)."""
        if not block:
            return cls()
        peak = block.get("peak_nits")
        if peak is not None and (isinstance(peak, bool) or not isinstance(peak, (int, float))):
            raise ValueError(f"peak_nits: expected a number, got {peak!r:.40}")
        return cls(str(block.get("name", "linear")), None if peak is None else float(peak))

    @classmethod
    def of(cls, linearity: Linearity | None) -> WallEncoding:
        """The encoding a ``linearity`` block records (a linear wall when it records none)."""
        block = None if linearity is None else linearity.wall_encoding
        return cls() if block is None else cls(block.name, block.peak_nits)

    def block(self) -> WallEncodingBlock:
        """The ``wall_encoding`` record of a ``linearity`` block."""
        return WallEncodingBlock(self.name, self.peak_nits)

    def to_dict(self) -> JsonObject:
        return {"name": self.name} | (
            {} if self.peak_nits is None else {"peak_nits": self.peak_nits}
        )

    @property
    def linear(self) -> bool:
        return self.name == "linear"

    @property
    def _peak(self) -> float:
        return DEFAULT_PEAK_NITS if self.peak_nits is None else self.peak_nits

    def encode(self, drive: np.ndarray) -> np.ndarray:
        """Linear drive -> wall signal (:func:`encode`)."""
        return encode(drive, self.name, peak_nits=self._peak)

    def decode(self, signal: np.ndarray) -> np.ndarray:
        """Wall signal -> linear drive (:func:`decode`)."""
        return decode(signal, self.name, peak_nits=self._peak)

    @property
    def signal_top(self) -> float | None:
        """The drive at which the signal reaches 1.0 (PQ: 10000 nits / peak); None for linear."""
        if self.linear:
            return None
        return 10000.0 / self._peak if self.name == "pq" else 1.0

    @property
    def ocio_encoding(self) -> str:
        """OCIO's ``encoding`` attribute of a colorspace carrying this signal."""
        return _OCIO_ENCODINGS[self.name]

    def ocio_transforms(self) -> list[OCIO.Transform]:
        """Linear drive -> this signal as OpenColorIO transforms (none for linear)."""
        import PyOpenColorIO as OCIO

        if self.linear:
            return []
        inverse = OCIO.TRANSFORM_DIR_INVERSE
        if self.name == "gamma2.4":
            return [OCIO.ExponentTransform(value=[2.4, 2.4, 2.4, 1.0], direction=inverse)]
        if self.name == "srgb":  # IEC 61966-2-1 as OCIO's moncurve (gamma 2.4, offset 0.055)
            # the moncurve continues its linear part below 0: clamp first (negative is black)
            return [
                OCIO.RangeTransform(minInValue=0.0, minOutValue=0.0),
                OCIO.ExponentWithLinearTransform(
                    gamma=[2.4, 2.4, 2.4, 1.0], offset=[0.055, 0.055, 0.055, 0.0],
                    direction=inverse,
                ),
            ]  # fmt: skip
        scale = self._peak / 100.0  # the builtin takes linear nits/100
        matrix = [scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, 1]
        return [
            OCIO.MatrixTransform(matrix=[float(v) for v in matrix]),
            OCIO.BuiltinTransform(style="CURVE - LINEAR_to_ST-2084"),
        ]

    def describe(self) -> str:
        """The wall's signal in words, for the terminal."""
        if self.name == "pq":
            return f"PQ (SMPTE ST 2084), drive 1.0 = {self._peak:g} cd/m2"
        if self.linear:
            return "linear drive (1.0 = the measured primaries' full drive)"
        return f"{self.name} signal of the linear drive (1.0 = the measured primaries' full drive)"


# --------------------------------------------------------------------------------------------
# The LUT sidecar.


@dataclasses.dataclass(frozen=True)
class LinearityLut:
    """The panel-linearity LUT: ``table`` (n, 3) sampled at ``t = linspace(0, 1, n)`` of the
    :func:`shaper`; its output is the wall signal (``encoding`` != linear) or the drive."""

    table: np.ndarray
    encoding: str
    peak_nits: float = DEFAULT_PEAK_NITS


def lut_table(
    linearity: Linearity,
    encoding: str = "linear",
    *,
    peak_nits: float = DEFAULT_PEAK_NITS,
    size: int = LUT_SIZE,
) -> LinearityLut:
    """The LUT: at each ``t``, ``r^-1`` of the drive ``t`` stands for, re-encoded; the
    identity for channels that are not corrected and above drive 1.0."""
    check_encoding(encoding, peak_nits)
    drive = _unshape(np.linspace(0.0, 1.0, size), encoding, peak_nits)
    table = np.repeat(drive[:, None], 3, axis=1)
    for k, name in enumerate(CHANNELS):
        channel = (linearity.channels or {})[name]
        if channel.corrected:
            table[:, k] = inverse_response(channel.drive, channel.response, drive)
    if encoding != "linear":
        table = encode(table, encoding, peak_nits=peak_nits)
    return LinearityLut(table=table, encoding=encoding, peak_nits=float(peak_nits))


def apply_lut(lut: LinearityLut, drive: np.ndarray) -> np.ndarray:
    """Numpy model of the wall tail: linear drive (..., 3) -> shaper -> LUT (clamped to its
    [0, 1] input, linear interpolation) = the wall signal."""
    t = shaper(drive, lut.encoding, peak_nits=lut.peak_nits)
    n = lut.table.shape[0]
    position = np.clip(t, 0.0, 1.0) * (n - 1)
    index = np.minimum(np.floor(position).astype(int), n - 2)
    frac = position - index
    out = np.empty_like(position)
    for k in range(3):
        column = lut.table[:, k]
        i = index[..., k]
        out[..., k] = column[i] * (1 - frac[..., k]) + column[i + 1] * frac[..., k]
    return out


def lut_drive(lut: LinearityLut, drive: np.ndarray) -> np.ndarray:
    """The drive the panel receives for linear ``drive``: :func:`apply_lut`, decoded."""
    return decode(apply_lut(lut, drive), lut.encoding, peak_nits=lut.peak_nits)


def lut_accuracy(linearity: Linearity, lut: LinearityLut) -> tuple[float, list[dict[str, float]]]:
    """How linear the modelled panel is after the LUT: the relative error
    ``|r(LUT(x)) - x| / x`` (:data:`LUT_ACCURACY`) over ``x`` from 0.1% to 100% of drive 1.0
    (log-spaced).

    Returns the worst error above 0.2% of peak (over the corrected channels), and per band of
    :data:`ACCURACY_BANDS` the worst and the level it occurs at (``from``, ``to``,
    ``max_error``, ``at``).
    """
    x = np.geomspace(ACCURACY_BANDS[0][0], 1.0, _CHECK_POINTS)
    out = lut_drive(lut, np.repeat(x[:, None], 3, axis=1))
    error = np.zeros_like(x)
    for k, name in enumerate(CHANNELS):
        channel = (linearity.channels or {})[name]
        if channel.corrected:
            model = response_model(channel.drive, channel.response)
            # the LUT's output can pass 1.0 by an ulp; the response is linear there
            error = np.maximum(error, np.abs(model(np.clip(out[:, k], 0.0, 1.0)) - x) / x)
    bands: list[dict[str, float]] = []
    for lo, hi in ACCURACY_BANDS:
        inside = (x >= lo) & (x <= hi)
        i = int(np.argmax(np.where(inside, error, -1.0)))
        bands.append({"from": lo, "to": hi, "max_error": float(error[i]), "at": float(x[i])})
    return max(b["max_error"] for b in bands[1:]), bands


def with_wall_encoding(
    solution: Solution, encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS
) -> Solution:
    """A copy of ``solution`` whose ``linearity`` block records the wall signal encoding.

    On a stage of several panel types (``solution.panels``), a type whose measurements gave it
    an ``encoding`` of its own keeps it (the first in-frustum type's is the top-level one);
    every other type gets ``encoding``.
    """
    check_encoding(encoding, peak_nits)
    if solution.panels:
        return _with_panel_encodings(solution, encoding, peak_nits)
    if encoding == "linear" and solution.linearity is None:
        return solution
    linearity = solution.linearity or assumed_linearity()
    wall = WallEncoding(encoding, peak_nits).block()
    return dataclasses.replace(solution, linearity=linearity.updated(wall_encoding=wall))


def _with_panel_encodings(solution: Solution, encoding: str, peak_nits: float) -> Solution:
    """:func:`with_wall_encoding` for every panel type without an encoding of its own."""

    def encoded(linearity: Linearity | None) -> Linearity | None:
        if linearity is not None and linearity.wall_encoding is not None:
            return linearity  # the panel type's own, from the measurements
        single = dataclasses.replace(solution, linearity=linearity, panels=None)
        return with_wall_encoding(single, encoding, peak_nits=peak_nits).linearity

    panels = {
        name: dataclasses.replace(panel, linearity=encoded(panel.linearity))
        for name, panel in (solution.panels or {}).items()
    }
    return dataclasses.replace(solution, linearity=encoded(solution.linearity), panels=panels)
