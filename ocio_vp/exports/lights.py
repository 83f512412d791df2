"""``lights``: the fixture drives of one environment for the people who run the lights.

``lights.json`` and ``lights.csv``: per fixture channel its DMX patch, drive, level and 8- and
16-bit DMX values (:mod:`ocio_vp.fixtures.dmx`); ``lights.json`` adds a pixel-mapped fixture's
content-to-drive matrix (docs/fixtures.md).
"""

from __future__ import annotations

from pathlib import Path

from ocio_vp.errors import InputError
from ocio_vp.exports.source import (
    DEFAULT_CUBES,
    CubeOptions,
    ExportSource,
    ExportSummary,
    write_json,
)
from ocio_vp.fixtures.dmx import content_matrix, dmx_csv, dmx_rows
from ocio_vp.formats.jsontypes import JsonObject

__all__ = ["write_lights"]

ASSUMPTIONS = (
    "drives assume each channel's light is proportional to its drive: set the fixtures' "
    "dimming curve to linear; DMX levels are drive / max_drive"
)


def write_lights(
    source: ExportSource, folder: Path, cubes: CubeOptions = DEFAULT_CUBES
) -> ExportSummary:
    """Write ``lights.json`` and ``lights.csv`` into ``folder``."""
    solution = source.solution
    if not solution.fixtures:
        raise InputError("no fixtures in this solution", source=str(source.directory))
    fixtures, rows = [], []
    for name, block in solution.fixtures.items():
        channel_rows = dmx_rows(name, block)
        rows += channel_rows
        dmx = None if block.dmx is None else block.dmx.to_dict()
        entry: JsonObject = {"name": name, "dmx": dmx, "channels": channel_rows}
        if block.pixel_mapped:
            entry["content_matrix"] = content_matrix(block.drives, solution.w_avg, block.max_drive)
        fixtures.append(entry)
    document: JsonObject = {
        "stage": solution.stage,
        "environment": solution.environment,
        "assumptions": ASSUMPTIONS,
        "fixtures": fixtures,
    }
    write_json(folder / "lights.json", document)
    (folder / "lights.csv").write_text(dmx_csv(rows), encoding="utf-8")
    return ExportSummary()  # the line names no file, as for every fixture export
