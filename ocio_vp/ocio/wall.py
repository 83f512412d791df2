"""The wall colorspaces' OCIO tail: the panel-linearity LUT sidecar and the signal encoding.

Chain (reference -> wall signal) of both wall colour spaces::

    gamma2.4, srgb, pq:  matrix  ->  encoding  ->  FileTransform luts/<sidecar>.clf (LUT)
    linear:              matrix  ->  FileTransform luts/<sidecar>.clf (log2 shaper + LUT)

``<sidecar>`` is ``<stage>_panel_linearity_<hash>``; the numbers are :mod:`ocio_vp.wall.encoding`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.deprecation import deprecated_names
from ocio_vp.formats.linearity import Linearity, LutFile
from ocio_vp.formats.solution import Solution
from ocio_vp.ocio import clf
from ocio_vp.ocio.clf import CLF_FORMAT, clf_v3
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM
from ocio_vp.ocio.description import Transform, file, transform_record
from ocio_vp.wall.encoding import (
    DEFAULT_PEAK_NITS,
    LINEAR_HEADROOM,
    LOG_SHAPER_KNEE,
    LUT_ACCURACY,
    LUT_DIR,
    LinearityLut,
    WallEncoding,
    lut_accuracy,
    lut_table,
)

__all__ = [
    "WallOutputs",
    "encoding_transforms",
    "log_shaper_transform",
    "lut_transform",
    "wall_outputs",
]

#: Names served for one more release (ocio_vp.deprecation): moved to ocio_vp.ocio.clf.
__getattr__ = deprecated_names(
    __name__,
    {"sidecar_name": ("ocio_vp.ocio.clf.sidecar_name", "ocio_vp.ocio.clf:sidecar_name")},
)


def encoding_transforms(encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> list:
    """OCIO transforms for the wall encoding (empty for ``linear``):
    :meth:`ocio_vp.wall.encoding.WallEncoding.ocio_transforms`."""
    return WallEncoding(encoding, peak_nits).ocio_transforms()


def log_shaper_transform() -> OCIO.LogAffineTransform:
    """The linear wall's log2 shaper (:func:`ocio_vp.wall.encoding.shaper`) as OCIO's
    LogAffineTransform (a CLF ``Log`` node)."""
    log = OCIO.LogAffineTransform(
        logSideSlope=[1.0 / float(np.log2(1.0 + LINEAR_HEADROOM / LOG_SHAPER_KNEE))] * 3,
        logSideOffset=[0.0] * 3,
        linSideSlope=[1.0 / LOG_SHAPER_KNEE] * 3,
        linSideOffset=[1.0] * 3,
    )
    log.setBase(2.0)
    return log


def lut_transform(lut: LinearityLut):
    """The sidecar as an OCIO GroupTransform: the 1D LUT, after the log2 shaper for a linear
    wall (the other encodings feed it their own signal)."""
    table = lut.table
    lut1d = OCIO.Lut1DTransform(length=table.shape[0], inputHalfDomain=False)
    lut1d.setInterpolation(OCIO.INTERP_LINEAR)
    for i, (r, g, b) in enumerate(table):
        lut1d.setValue(i, float(r), float(g), float(b))
    shaper = [log_shaper_transform()] if WallEncoding(lut.encoding).linear else []
    return OCIO.GroupTransform([*shaper, lut1d])


#: What the LUT takes and returns, per wall encoding (in the CLF and solution.json).
_LUT_DOMAINS = {
    "linear": f"drive [0, {LINEAR_HEADROOM:g}] through a log2 shaper -> drive",
    "gamma2.4": "gamma 2.4 signal [0, 1] -> gamma 2.4 signal",
    "srgb": "sRGB signal [0, 1] -> sRGB signal",
    "pq": "PQ signal [0, 1] -> PQ signal",
}


@dataclass(frozen=True)
class WallOutputs:
    """Transforms to append to the wall colorspaces, sidecar files (relative path -> text),
    the config search path, and the ``linearity`` block as it goes into ``solution.json``."""

    extra_wall_transforms: dict[str, list[Transform]] | None = None
    search_path: str | None = None
    files: dict[str, str] = field(default_factory=dict)
    linearity: Linearity | None = None


def wall_outputs(solution: Solution) -> WallOutputs:
    """Build the LUT sidecar (when a channel needs it) and the encoding transforms."""
    linearity = solution.linearity
    if linearity is None:
        return WallOutputs()
    wall = WallEncoding.of(linearity)
    encoding, peak_nits = wall.name, float(wall.peak_nits or DEFAULT_PEAK_NITS)
    chain = [transform_record(t) for t in wall.ocio_transforms()]
    files: dict[str, str] = {}
    if linearity.corrected:
        lut = lut_table(linearity, encoding, peak_nits=peak_nits)
        group = lut_transform(lut)
        group.getFormatMetadata().addChildElement(
            "Description",
            f"ocio_vp panel-linearity pre-correction for stage {solution.stage}: per-channel "
            f"inverse of the measured ramp response, {_LUT_DOMAINS[encoding]}.",
        )
        text = clf_v3(group.write(formatName=CLF_FORMAT, config=OCIO.Config.CreateRaw()))
        name = clf.sidecar_name(f"{solution.stage}_panel_linearity", text)
        files[f"{LUT_DIR}/{name}"] = text
        chain.append(file(name))
        max_error, bands = lut_accuracy(linearity, lut)
        record = LutFile(
            file=f"{LUT_DIR}/{name}",
            entries=int(lut.table.shape[0]),
            domain=_LUT_DOMAINS[encoding],
            max_error=max_error,
            bands=bands,
            definition=LUT_ACCURACY,
        )
        linearity = linearity.updated(lut=record)
    if not chain:
        return WallOutputs(linearity=linearity)
    return WallOutputs(
        extra_wall_transforms={OUT_OF_FRUSTUM: chain, IN_FRUSTUM: chain},
        search_path=LUT_DIR if files else None,
        files=files,
        linearity=linearity,
    )
