"""Resolve ``.cube`` files that meet a stated accuracy, or are not written.

A cube is a per-channel 1D shaper followed by a ``size``^3 3D LUT holding the exact transform
(the config's processor) at the knots. The written file is read back by OCIO and compared with
the exact transform (trilinear and tetrahedral, content in [0, 1]^3 and the whole input range);
it is kept only when the worst error is at most :data:`CUBE_LIMIT`, else the caller says why and
points to the exact CLF (docs/exports.md).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.ocio.bake import processor_function

__all__ = [
    "CUBE_LIMIT",
    "SHAPERS",
    "CubeAccuracy",
    "CubeResult",
    "bake_cube",
    "cube_error",
    "fit_cube",
]

#: Largest accepted error: one code value of a 10-bit signal (absolute up to 1.0, relative above).
CUBE_LIMIT = 1.0 / 1023.0
SHAPERS = ("linear", "log2")
SHAPER_SIZE = 4096
#: log2 shaper: log2(x - lo + LOG_OFFSET), so black keeps a finite slope.
LOG_OFFSET = 2.0**-10
SAMPLES = 40000


@dataclass(frozen=True)
class CubeAccuracy:
    """A baked cube's measured error (:func:`cube_error`) and, once tried by :func:`fit_cube`,
    its shaper, size and the limit it was held to."""

    samples_per_box: int
    input_range: tuple[float, float]
    #: ``<box>_<interpolation>`` (content_0_1 / input_range, trilinear / tetrahedral): worst error.
    boxes: dict[str, float]
    max_error: float
    worst_input: tuple[float, ...]
    evaluated_with: str
    shaper: str | None = None
    cube_size: int | None = None
    limit: float | None = None

    @property
    def content_error(self) -> float:
        """The worst error over content in [0, 1] (either interpolation)."""
        return max(self.boxes["content_0_1_trilinear"], self.boxes["content_0_1_tetrahedral"])

    def to_dict(self) -> JsonObject:
        """The ``accuracy`` of a cube in the manifests (keys in this order)."""
        out: JsonObject = {"samples_per_box": self.samples_per_box,
                           "input_range": list(self.input_range), **self.boxes,
                           "max_error": self.max_error, "worst_input": list(self.worst_input),
                           "evaluated_with": self.evaluated_with}  # fmt: skip
        if self.shaper is not None:
            out.update(shaper=self.shaper, cube_size=self.cube_size, limit=self.limit)
        return out


@dataclass(frozen=True)
class CubeResult:
    """The outcome of :func:`fit_cube`: the file (None when not written) and its accuracy."""

    path: Path | None
    shaper: str | None
    errors: CubeAccuracy | None
    reason: str | None = None


def shaper_table(kind: str, lo: float, hi: float, size: int = SHAPER_SIZE) -> np.ndarray:
    """The 1D shaper: ``size`` values in [0, 1] for inputs evenly spaced over [lo, hi].

    Examples
    --------
    >>> shaper_table("linear", -1.0, 1.0, 5).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    x = np.linspace(lo, hi, size)
    if kind == "linear":
        table = (x - lo) / (hi - lo)
    elif kind == "log2":
        log = np.log2(x - lo + LOG_OFFSET)
        table = (log - log[0]) / (log[-1] - log[0])
    else:
        raise ValueError(f"unknown shaper {kind!r}; expected one of {SHAPERS}")
    table[0], table[-1] = 0.0, 1.0
    return table


def _lattice(table: np.ndarray, lo: float, hi: float, size: int) -> np.ndarray:
    """Input RGB of every 3D knot (red fastest, the .cube order): the piecewise-linear shaper
    (as a host interpolates the 1D table) inverted at the knots."""
    x = np.linspace(lo, hi, table.size)
    knots = np.interp(np.linspace(0.0, 1.0, size), table, x)
    b, g, r = np.meshgrid(knots, knots, knots, indexing="ij")
    return np.stack([r, g, b], axis=-1).reshape(-1, 3)


def bake_cube(
    processor: OCIO.Processor,
    path: Path,
    *,
    size: int,
    input_range: tuple[float, float],
    shaper: str = "linear",
    title: str = "ocio-vp",
) -> Path:
    """Write ``processor`` as a Resolve ``.cube`` (1D shaper + ``size``^3 3D LUT)."""
    lo, hi = (float(v) for v in input_range)
    table = shaper_table(shaper, lo, hi)
    values = processor_function(processor)(_lattice(table, lo, hi, size))
    if not np.all(np.isfinite(values)):
        raise ValueError("the transform returns non-finite values inside the cube's range")
    safe_title = "".join(c if c.isprintable() else "?" for c in title)
    lines = [
        f"# {safe_title}",
        f"LUT_1D_SIZE {table.size}",
        f"LUT_1D_INPUT_RANGE {lo!r} {hi!r}",
        f"LUT_3D_SIZE {size}",
        "LUT_3D_INPUT_RANGE 0.0 1.0",
    ]
    # as Python floats: the same text as numpy scalars formatted one by one, in less time
    lines += map("{0:.9g} {0:.9g} {0:.9g}".format, table.tolist())
    lines += map("{:.9g} {:.9g} {:.9g}".format, *values.T.tolist())
    path.write_text("\n".join(lines) + "\n", encoding="ascii")
    return path


def cube_error(
    processor: OCIO.Processor,
    path: Path,
    *,
    input_range: tuple[float, float],
    samples: int = SAMPLES,
    seed: int = 0,
) -> CubeAccuracy:
    """Worst ``|cube - exact| / max(1, |exact|)`` by interpolation and box (see the module
    docstring), with the input where the worst one occurs."""
    lo, hi = (float(v) for v in input_range)
    rng = np.random.default_rng(seed)
    raw = OCIO.Config.CreateRaw()
    boxes: dict[str, float] = {}
    worst, worst_input = -1.0, np.zeros(3)  # every sample's error >= 0 replaces it
    hosts = {  # the file read once for each interpolation (each box's samples go through it)
        name: processor_function(
            raw.getProcessor(OCIO.FileTransform(src=str(path.resolve()), interpolation=how))
        )
        for name, how in (
            ("trilinear", OCIO.INTERP_LINEAR),
            ("tetrahedral", OCIO.INTERP_TETRAHEDRAL),
        )
    }
    exact_function = processor_function(processor)
    for box, (a, b) in (("content_0_1", (max(lo, 0.0), min(hi, 1.0))), ("input_range", (lo, hi))):
        rgb = rng.uniform(a, b, size=(samples, 3))
        exact = exact_function(rgb)
        for name, host in hosts.items():
            error = np.abs(host(rgb) - exact) / np.maximum(1.0, np.abs(exact))
            per_sample = error.max(axis=1)
            boxes[f"{box}_{name}"] = float(per_sample.max())
            if per_sample.max() > worst:
                worst, worst_input = float(per_sample.max()), rgb[int(np.argmax(per_sample))]
    return CubeAccuracy(
        samples_per_box=samples,
        input_range=(lo, hi),
        boxes=boxes,
        max_error=worst,
        worst_input=tuple(float(v) for v in worst_input),
        evaluated_with=f"OpenColorIO {OCIO.__version__} (.cube reader vs the processor)",
    )


def fit_cube(
    processor: OCIO.Processor,
    path: Path,
    *,
    size: int,
    input_range: tuple[float, float],
    title: str = "ocio-vp",
    limit: float = CUBE_LIMIT,
) -> CubeResult:
    """Bake ``processor`` with each shaper in turn; keep the first cube within ``limit``.

    Trial files get their own names (OCIO caches files by path for the whole process) and are
    removed; ``path`` exists afterwards only when a cube met the limit.
    """
    best: CubeAccuracy | None = None
    for shaper in SHAPERS:
        trial = path.with_name(f".{path.stem}.{shaper}.trial.cube")
        try:
            bake_cube(processor, trial, size=size, input_range=input_range, shaper=shaper,
                      title=title)  # fmt: skip
        except ValueError as error:
            return CubeResult(None, None, None, reason=str(error))
        errors = dataclasses.replace(
            cube_error(processor, trial, input_range=input_range),
            shaper=shaper,
            cube_size=size,
            limit=limit,
        )
        if errors.max_error <= limit:
            trial.replace(path)
            return CubeResult(path, shaper, errors)
        trial.unlink()
        if best is None or errors.max_error < best.max_error:
            best = errors
    assert best is not None
    return CubeResult(
        None,
        None,
        best,
        reason=f"a {size}^3 cube cannot follow this transform's clip or curve: the best bake "
        f"({best.shaper} shaper) is off by {best.max_error:.3g} (content in [0, 1]: "
        f"{best.content_error:.3g}) at input "
        f"{[round(v, 4) for v in best.worst_input]}, over the limit {limit:.3g} (1/1023)",
    )
