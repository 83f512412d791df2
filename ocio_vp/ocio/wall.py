"""The wall colorspaces' OCIO tail: the panel-linearity LUT sidecar and the signal encoding.

Chain (reference -> wall signal), for both ``LED Wall - Outer Frustum`` (M) and
``LED Wall - Inner Frustum`` (N + offset)::

    matrix  ->  FileTransform luts/<stage>_panel_linearity_<hash>.clf  ->  encoding

The numbers (LUT table, encoding curves, domain) are in :mod:`ocio_vp.wall.encoding`; this module
turns them into OCIO transforms and sidecar text for :mod:`ocio_vp.ocio.writer`.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import PyOpenColorIO as OCIO

from ocio_vp.formats.solution import Solution
from ocio_vp.ocio.clf import clf_v3
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM, matrix_transform
from ocio_vp.wall.encoding import (
    CLF_FORMAT,
    DEFAULT_PEAK_NITS,
    LUT_DIR,
    check_encoding,
    lut_accuracy,
    lut_domain_max,
    lut_table,
)

__all__ = ["WallOutputs", "encoding_transforms", "lut_transform", "sidecar_name", "wall_outputs"]


def encoding_transforms(encoding: str, *, peak_nits: float = DEFAULT_PEAK_NITS) -> list:
    """OCIO transforms for the wall encoding (empty for ``linear``)."""
    check_encoding(encoding, peak_nits)
    if encoding == "linear":
        return []
    if encoding == "gamma2.4":
        return [
            OCIO.ExponentTransform(value=[2.4, 2.4, 2.4, 1.0], direction=OCIO.TRANSFORM_DIR_INVERSE)
        ]
    # The builtin takes linear nits/100.
    return [
        matrix_transform(np.eye(3) * (peak_nits / 100.0)),
        OCIO.BuiltinTransform(style="CURVE - LINEAR_to_ST-2084"),
    ]


def lut_transform(table: np.ndarray, domain_max: float):
    """The sidecar as an OCIO GroupTransform: a shaper scale then the 1D LUT."""
    lut = OCIO.Lut1DTransform(length=table.shape[0], inputHalfDomain=False)
    lut.setInterpolation(OCIO.INTERP_LINEAR)
    for i, (r, g, b) in enumerate(table):
        lut.setValue(i, float(r), float(g), float(b))
    transforms = [] if domain_max == 1.0 else [matrix_transform(np.eye(3) / domain_max)]
    return OCIO.GroupTransform([*transforms, lut])


def sidecar_name(stem: str, text: str) -> str:
    """``<stem>_<hash>.clf``: OCIO caches files by path for the whole process, so two configs
    whose sidecars differ must not share a file name (a host session loading two calibrations
    of one stage would otherwise apply the first one's LUT to both)."""
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()[:12]
    return f"{stem}_{digest}.clf"


@dataclass(frozen=True)
class WallOutputs:
    """Transforms to append to the wall colorspaces, sidecar files (relative path -> text),
    the config search path, and the ``linearity`` block as it goes into ``solution.json``."""

    extra_wall_transforms: dict[str, list] | None = None
    search_path: str | None = None
    files: dict[str, str] = field(default_factory=dict)
    linearity: dict[str, Any] | None = None


def wall_outputs(solution: Solution) -> WallOutputs:
    """Build the LUT sidecar (when a channel needs it) and the encoding transforms."""
    linearity = solution.linearity
    if linearity is None:
        return WallOutputs()
    linearity = dict(linearity)
    encoding_info = linearity.get("wall_encoding") or {"name": "linear"}
    encoding = encoding_info["name"]
    peak_nits = float(encoding_info.get("peak_nits", DEFAULT_PEAK_NITS))
    lut_name = None
    files: dict[str, str] = {}
    channels = linearity.get("channels") or {}
    if any(channels[c]["corrected"] for c in channels):
        domain_max = lut_domain_max(encoding, peak_nits=peak_nits)
        table = lut_table(linearity, domain_max=domain_max)
        group = lut_transform(table, domain_max)
        group.getFormatMetadata().addChildElement(
            "Description",
            f"ocio_vp panel-linearity pre-correction for stage {solution.stage}: per-channel "
            f"inverse of the measured ramp response; drive [0, {domain_max:g}] -> drive.",
        )
        text = clf_v3(group.write(formatName=CLF_FORMAT, config=OCIO.Config.CreateRaw()))
        name = sidecar_name(f"{solution.stage}_panel_linearity", text)
        files[f"{LUT_DIR}/{name}"] = text
        lut_name = name
        linearity["lut"] = {
            "file": f"{LUT_DIR}/{name}",
            "entries": int(table.shape[0]),
            "domain_max": domain_max,
            "shaper": f"scale by 1/{domain_max:g}" if domain_max != 1.0 else "none",
            "max_error": lut_accuracy(linearity, table, domain_max),
        }

    def chain() -> list:  # fresh objects for each colorspace
        lut = [] if lut_name is None else [OCIO.FileTransform(src=lut_name)]
        return lut + encoding_transforms(encoding, peak_nits=peak_nits)

    if not chain():
        return WallOutputs(linearity=linearity)
    return WallOutputs(
        extra_wall_transforms={OUT_OF_FRUSTUM: chain(), IN_FRUSTUM: chain()},
        search_path=LUT_DIR if files else None,
        files=files,
        linearity=linearity,
    )
