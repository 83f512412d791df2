"""Geometry of the calibration: the scale factor beta and the diffuse integral w_avg.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22.
https://doi.org/10.1145/3543664.3543681 (Section 3.3, the scale factor beta and w_avg).

Howell, J. R. A Catalog of Radiation Heat Transfer Configuration Factors, factor B-3
("differential planar element to parallel rectangle, normal through a corner").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import Environment, Measurements, PanelGeometry
from ocio_vp.formats.panels import PanelType, primary_panel

__all__ = [
    "environment_panel_w_avg",
    "environment_w_avg",
    "form_factor_numerical",
    "form_factor_parallel_rectangle",
    "panel_beta",
    "panel_type_beta",
    "stage_beta",
    "w_avg_from_white_patch",
]


def _corner_form_factor(
    a: np.ndarray | np.float64, b: np.ndarray | np.float64, c: float
) -> np.ndarray:
    """Form factor to a rectangle [0, a] x [0, b] at distance c, one corner on the normal.

    Signed in ``a`` and ``b`` so that rectangles anywhere in the plane can be composed by
    superposition (the function is odd in each of them).
    """
    A = np.asarray(a, dtype=np.float64) / c
    B = np.asarray(b, dtype=np.float64) / c
    sa = np.sqrt(1.0 + A * A)
    sb = np.sqrt(1.0 + B * B)
    return (A / sa * np.arctan(B / sa) + B / sb * np.arctan(A / sb)) / (2.0 * np.pi)


def form_factor_parallel_rectangle(
    width: float, height: float, distance: float, offset_x: float = 0.0, offset_y: float = 0.0
) -> float:
    """Diffuse form factor from a small patch to a parallel rectangle facing it (closed form).

    The patch sits on the z axis looking at the rectangle, whose centre is at
    ``(offset_x, offset_y, distance)``. The value is the fraction of a uniform, full sphere of
    light's diffuse irradiance that the rectangle alone delivers: the paper's beta.

    Parameters
    ----------
    width, height
        Size of the rectangle (any length unit, the same as ``distance``).
    distance
        Perpendicular distance from the patch to the rectangle's plane, > 0.
    offset_x, offset_y
        Lateral offset of the rectangle's centre from the patch normal.

    Returns
    -------
    float
        The form factor, in (0, 1).

    Examples
    --------
    >>> round(form_factor_parallel_rectangle(1.0, 1.0, 1.0), 5)  # the paper's 1 m panel at 1 m
    0.23946
    >>> round(form_factor_parallel_rectangle(1.2, 1.2, 1.0), 5)  # the paper's beta ~ 0.311
    0.31128
    """
    if not (width > 0 and height > 0 and distance > 0):
        raise InputError(
            f"panel width, height and distance must be > 0, got {width!r}, {height!r}, {distance!r}"
        )
    x0, x1 = offset_x - width / 2.0, offset_x + width / 2.0
    y0, y1 = offset_y - height / 2.0, offset_y + height / 2.0

    def corner(x: float, y: float) -> float:
        # Quadrant rectangle [0, x] x [0, y] with signs: superpose four of them.
        size_x, size_y = np.abs(np.float64(x)), np.abs(np.float64(y))
        return float(np.sign(x) * np.sign(y) * _corner_form_factor(size_x, size_y, distance))

    return corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)


def form_factor_numerical(
    width: float,
    height: float,
    distance: float,
    offset_x: float = 0.0,
    offset_y: float = 0.0,
    samples: int = 2000,
) -> float:
    """The same form factor by midpoint-rule integration over the rectangle (a check).

    ``F = 1/pi * integral over the panel of cos(theta_patch) cos(theta_panel) / r^2 dA``.
    """
    xs = offset_x + (np.arange(samples) + 0.5) / samples * width - width / 2.0
    ys = offset_y + (np.arange(samples) + 0.5) / samples * height - height / 2.0
    x, y = np.meshgrid(xs, ys, indexing="xy")
    r2 = x * x + y * y + distance * distance
    integrand = distance * distance / (r2 * r2)  # cos * cos / r^2 with cos = d / r
    return float(integrand.sum() * (width / samples) * (height / samples) / np.pi)


def panel_beta(panel: PanelGeometry) -> float:
    """beta for a :class:`PanelGeometry` (the paper's scale factor, Section 3.3)."""
    return form_factor_parallel_rectangle(
        panel.width, panel.height, panel.distance, panel.offset_x, panel.offset_y
    )


def panel_type_beta(panel: PanelType) -> float:
    """beta of one panel type of a file with ``panels``: its ``beta`` wins over its geometry."""
    if panel.beta is not None:
        return float(panel.beta)
    if panel.panel is None:  # the parser requires calibration_panel or beta
        raise ValueError(f"panel type {panel.name!r} has neither beta nor calibration_panel")
    return panel_beta(panel.panel)


def stage_beta(measurements: Measurements) -> float:
    """beta for a stage: an explicit ``beta`` in the file wins over the panel geometry (with
    ``panels``: the first in-frustum type's, whose [SRL] the measurements' ``SRL`` is)."""
    if measurements.panels:
        return panel_type_beta(primary_panel(measurements.panels))
    stage = measurements.stage
    if stage.beta is not None:
        return float(stage.beta)
    assert stage.panel is not None  # guaranteed by validation
    return panel_beta(stage.panel)


def w_avg_from_white_patch(
    target_chart: ArrayLike, white_patch: int = DEFAULT_WHITE_PATCH, white_reflectance: float = 0.9
) -> np.ndarray:
    """The diffuse integral w_avg from the target chart's white patch (paper, Section 3.3).

    ``w_avg = p_white / reflectance``: the white patch of a chart at the HDRI's centre of
    projection sees the diffuse integral of the frontal hemisphere, reduced by its reflectance.
    """
    chart = np.asarray(target_chart, dtype=np.float64)
    return chart[..., white_patch, :] / float(white_reflectance)


def environment_w_avg(measurements: Measurements, environment: Environment) -> np.ndarray:
    """w_avg for an environment: the file's value if given, else from the white patch."""
    if environment.w_avg is not None:
        return np.asarray(environment.w_avg, dtype=np.float64)
    stage = measurements.stage
    w_avg = w_avg_from_white_patch(
        environment.target_chart, stage.white_patch, stage.white_reflectance
    )
    if not np.any(w_avg > 0):
        raise InputError(
            f"white patch {stage.white_patch} of the target chart is black; give w_avg",
            source=measurements.source,
            key=f"environments[{_index(measurements, environment)}].target_chart",
        )
    return w_avg


def environment_panel_w_avg(
    measurements: Measurements, environment: Environment
) -> dict[str, np.ndarray]:
    """With ``panels``: the diffuse light each panel type must deliver, ``{name: (3,)}``.

    The file's (or an HDRI's, :func:`ocio_vp.hdri.environments_with_hdri`) per-panel w_avg;
    a stage of one panel type may take it from the white patch like a file without panels.

    Raises
    ------
    InputError
        When the environment has none and the stage has several panel types.
    """
    if environment.panel_w_avg is not None:
        return {n: np.asarray(v, dtype=np.float64) for n, v in environment.panel_w_avg.items()}
    if len(measurements.panels) == 1:
        return {measurements.panels[0].name: environment_w_avg(measurements, environment)}
    index = _index(measurements, environment)
    raise InputError(
        "with several panel types, give w_avg per panel type ({"
        + ", ".join(f"{p.name}: [r, g, b]" for p in measurements.panels)
        + "}), or an HDRI (--hdri ENV=FILE) and a region for every panel type",
        source=measurements.source,
        key=f"environments[{index}].w_avg",
    )


def _index(measurements: Measurements, environment: Environment) -> int:
    """Where ``environment`` is in the file, by name (the solve may hold a changed copy: an
    HDRI's w_avg, a panel type's view of it)."""
    return [e.name for e in measurements.environments].index(environment.name)
