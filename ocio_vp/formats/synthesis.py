"""The ``synthesized`` record of an environment whose target chart was computed, not
photographed (written by ``ocio-vp target-chart``; keys and rules: docs/measurements.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from ocio_vp.formats.checker import Key, Validator
from ocio_vp.formats.jsontypes import JsonObject, JsonValue

__all__ = [
    "SYNTHESIS_SOURCES",
    "SynthesisRecord",
    "parse_synthesis",
    "synthesis_to_dict",
    "synthesis_warnings",
]

#: Where the environment's light came from.
SYNTHESIS_SOURCES = ("hdri", "average-rgb")
_REQUIRED = ("source", "colorspace", "illuminant", "camera", "chart", "assumptions")
_OPTIONAL = ("hdri", "cct", "duv", "warnings")


@dataclass(frozen=True)
class SynthesisRecord:
    """How a synthesized target chart was made (each key: docs/measurements.md)."""

    source: str
    colorspace: str
    illuminant: str
    camera: str
    chart: str
    assumptions: tuple[str, ...]
    hdri: str | None = None
    cct: float | None = None
    duv: float | None = None
    warnings: tuple[str, ...] = ()


def _texts(ctx: Validator, value: JsonValue, key: Key, *, empty: bool) -> tuple[str, ...]:
    listed = ctx.items(value, key, "texts", empty=empty)
    return tuple(ctx.text(v, (*key, i)) for i, v in enumerate(listed))


def parse_synthesis(
    ctx: Validator, value: JsonValue, key: tuple[str | int, ...]
) -> SynthesisRecord:
    """Validate an environment's ``synthesized`` mapping (``ctx``: a measurements ``Validator``)."""
    raw = ctx.mapping(value, key, required=_REQUIRED, optional=_OPTIONAL)
    source = ctx.choice(raw["source"], (*key, "source"), SYNTHESIS_SOURCES)
    cct = None
    if "cct" in raw:
        cct = ctx.number(raw["cct"], (*key, "cct"), strict=True)
    duv = None
    if "duv" in raw:
        duv = ctx.number(raw["duv"], (*key, "duv"), minimum=-1.0)
        if duv > 1.0:
            raise ctx.error((*key, "duv"), f"expected a number in [-1, 1], got {duv!r}")
    return SynthesisRecord(
        source=source,
        colorspace=ctx.text(raw["colorspace"], (*key, "colorspace")),
        illuminant=ctx.text(raw["illuminant"], (*key, "illuminant")),
        camera=ctx.text(raw["camera"], (*key, "camera")),
        chart=ctx.text(raw["chart"], (*key, "chart")),
        assumptions=_texts(ctx, raw["assumptions"], (*key, "assumptions"), empty=False),
        hdri=ctx.text(raw["hdri"], (*key, "hdri")) if "hdri" in raw else None,
        cct=cct,
        duv=duv,
        warnings=_texts(ctx, raw.get("warnings", []), (*key, "warnings"), empty=True),
    )


def synthesis_to_dict(record: SynthesisRecord) -> JsonObject:
    """The record as plain types, in file key order (optional keys only when set)."""
    data: JsonObject = {
        "source": record.source,
        "hdri": record.hdri,
        "colorspace": record.colorspace,
        "illuminant": record.illuminant,
        "cct": record.cct,
        "duv": record.duv,
        "camera": record.camera,
        "chart": record.chart,
        "assumptions": list(record.assumptions),
        "warnings": list(record.warnings),
    }
    return {k: v for k, v in data.items() if v not in (None, [])}


def synthesis_warnings(record: SynthesisRecord) -> list[str]:
    """What ``solve`` tells the user about a synthesized target (first line always present)."""
    where = f"the HDRI {record.hdri}" if record.hdri else "an average RGB"
    light = record.illuminant
    if record.cct is not None and record.duv is not None:
        light += f" (CCT {record.cct:.0f} K, Duv {record.duv:+.4f})"
    first = (
        f"the target chart is SYNTHESIZED from {where}, not photographed: light assumed {light}, "
        f"camera {record.camera}, chart {record.chart}; Q is only as right as these "
        "assumptions (diagnostics.synthesized_target)"
    )
    return [first, *(f"synthesized target: {w}" for w in record.warnings)]
