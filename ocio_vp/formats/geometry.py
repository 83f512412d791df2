"""The calibration panel's geometry, shared by the stage section and the panel types."""

from __future__ import annotations

from dataclasses import dataclass

from ocio_vp.formats.jsontypes import JsonObject

__all__ = ["PanelGeometry"]


@dataclass(frozen=True)
class PanelGeometry:
    """The calibration panel as seen from the chart, in metres (the chart faces the panel).

    ``offset_x``/``offset_y`` move the panel centre sideways from the chart's normal.
    """

    width: float
    height: float
    distance: float
    offset_x: float = 0.0
    offset_y: float = 0.0

    def to_dict(self) -> JsonObject:
        """The ``calibration_panel`` block (offsets only when the panel is off-axis)."""
        out: JsonObject = {"width": self.width, "height": self.height, "distance": self.distance}
        if self.offset_x or self.offset_y:
            out.update(offset_x=self.offset_x, offset_y=self.offset_y)
        return out
