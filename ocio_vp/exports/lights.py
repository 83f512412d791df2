"""``lights``: the fixture drives of one environment for the people who run the lights.

``lights.json`` and ``lights.csv`` list, per fixture and in its channel order, each channel's
DMX universe, fixture mode and address (from the fixture's ``dmx`` patch in the measurements
file; empty when it has none), drive (units of its ``reference_drive``), its level in [0, 1] of
``max_drive``, and the 8- and 16-bit DMX values of that level (:mod:`ocio_vp.fixtures.dmx`);
``lights.json`` adds, for a pixel-mapped fixture, the k x 3 matrix from content RGB to channel
drives and its gamut limit.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ocio_vp.errors import InputError
from ocio_vp.exports.source import DEFAULT_CUBES, CubeOptions, ExportSource
from ocio_vp.fixtures.dmx import content_matrix, dmx_csv, dmx_rows

__all__ = ["write_lights"]

ASSUMPTIONS = (
    "drives assume each channel's light is proportional to its drive: set the fixtures' "
    "dimming curve to linear; DMX levels are drive / max_drive"
)


def write_lights(source: ExportSource, folder: Path, cubes: CubeOptions = DEFAULT_CUBES) -> dict:
    """Write ``lights.json`` and ``lights.csv`` into ``folder``."""
    solution = source.solution
    if not solution.fixtures:
        raise InputError("no fixtures in this solution", source=str(source.directory))
    fixtures, rows = [], []
    for name, block in solution.fixtures.items():
        channel_rows = dmx_rows(name, block)
        rows += channel_rows
        entry: dict[str, Any] = {"name": name, "dmx": block.get("dmx"), "channels": channel_rows}
        if block.get("pixel_mapped"):
            drives = [block["drive"][c] for c in block["channels"]]
            entry["content_matrix"] = content_matrix(drives, solution.w_avg, block["max_drive"])
        fixtures.append(entry)
    document = {
        "stage": solution.stage,
        "environment": solution.environment,
        "assumptions": ASSUMPTIONS,
        "fixtures": fixtures,
    }
    (folder / "lights.json").write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
    (folder / "lights.csv").write_text(dmx_csv(rows), encoding="utf-8")
    return {"json": "lights.json", "csv": "lights.csv", "channels": len(rows)}
