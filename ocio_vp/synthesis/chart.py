"""The chart's spectral reflectances (colour-science's ``SDS_COLOURCHECKERS``), made consistent
with the measurements file's ``white_reflectance``.

The synthesized target must describe the *physical* chart photographed on the stage for
``lit_chart``: ``--chart`` names its edition's data. The data's white patch rarely reads exactly
the file's ``white_reflectance``, so the whole chart is scaled by their ratio: the synthesized
white patch then equals ``white_reflectance x w_avg`` as the solver assumes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError
from ocio_vp.spectra import DEFAULT_CHART, checker_reflectances, unknown_name

__all__ = ["DEFAULT_CHART", "ScaledChart", "chart_spectra", "scaled_to_white"]


def chart_spectra(name: str = DEFAULT_CHART) -> np.ndarray:
    """(n, W) reflectances of ``colour.SDS_COLOURCHECKERS[name]`` in reading order."""
    import colour

    if name not in colour.SDS_COLOURCHECKERS:
        raise InputError(unknown_name("chart", name, colour.SDS_COLOURCHECKERS), key="--chart")
    return checker_reflectances(name)


@dataclass(frozen=True)
class ScaledChart:
    """Reflectances (n, W) times ``scale``; ``white`` is the data's own white reading."""

    reflectances: np.ndarray
    scale: float
    white: float


def scaled_to_white(
    reflectances: ArrayLike, white_patch: int, white_reflectance: float, green: ArrayLike
) -> ScaledChart:
    """Scale a chart so its white patch reads ``white_reflectance`` through ``green``.

    The white's reading is ``sum green R_white / sum green`` (a flat light through the camera's
    green channel, as the simulator defines ``white_reflectance``).

    Examples
    --------
    >>> chart = scaled_to_white(np.full((24, 81), 0.45), 18, 0.9, np.ones(81))
    >>> round(chart.scale, 6), round(float(chart.reflectances[0, 0]), 6)
    (2.0, 0.9)
    """
    reflectances = np.asarray(reflectances, dtype=np.float64)
    green = np.asarray(green, dtype=np.float64)
    white = float(green @ reflectances[white_patch] / green.sum())
    if not white > 0:
        raise InputError(f"the chart's patch {white_patch} is black, not a white", key="--chart")
    scale = float(white_reflectance) / white
    return ScaledChart(reflectances * scale, scale, white)
