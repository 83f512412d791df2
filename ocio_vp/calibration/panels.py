"""Several panel types on one stage: the paper's equations per type, the light on the chart summed.

Each type k has its own [SL]_k, ``M_k``, beta_k and [SRL]_j,k and delivers its part ``w_avg,k``
of the environment's light; the chart on stage is lit by the sum
``x_j = sum_k (1/beta_k) [SRL]_j,k clip(M_k w_avg,k, 0)``, Q is fitted to it, and each
in-frustum type shows the background through its own ``N_k`` and offset, so that the types
match in camera except where one cannot reach a colour (:func:`in_frustum_match`). The whole
account is in docs/panels.md.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eqs. 2-8, Sec. 3.4.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ocio_vp.calibration.equations import (
    black_level_offset,
    in_frustum_drive,
    predict_displayed_chart,
    predict_lit_chart,
    solve_M,
    solve_N,
)
from ocio_vp.calibration.geometry import panel_type_beta
from ocio_vp.errors import InputError
from ocio_vp.formats.diagnostics import InFrustumMatch, TypeMatch
from ocio_vp.formats.linearity import Linearity
from ocio_vp.formats.measurements import Measurements
from ocio_vp.formats.panel_solution import PanelSolution
from ocio_vp.formats.panels import PanelType
from ocio_vp.metrics import chart_errors, white_scale
from ocio_vp.model.correction import PostCorrection

__all__ = [
    "InFrustumDrive",
    "PanelLight",
    "in_frustum_drive_for",
    "in_frustum_match",
    "light_shares",
    "lit_white_errors",
    "other_panels_light",
    "panel_lights",
    "panel_solutions",
    "shown_in_camera",
]


@dataclass(frozen=True)
class PanelLight:
    """One panel type's part of an environment's light: ``M = [SL]^-1`` of the type, its
    calibration panel's ``beta`` and the diffuse light ``w_avg`` it delivers."""

    panel: PanelType
    beta: float
    M: np.ndarray
    w_avg: np.ndarray

    @property
    def name(self) -> str:
        return self.panel.name

    @property
    def drive(self) -> np.ndarray:
        """(3,) the lighting drive ``M w_avg`` (eq. 3), before the panel clips it at 0."""
        return self.M @ self.w_avg

    def lit(self, M: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) the chart lit by this type alone: eq. 3 with the drive it can emit,
        ``(1/beta) [SRL]_j clip(M w_avg, 0)`` (``M`` default its own)."""
        matrix = self.M if M is None else np.asarray(M, dtype=np.float64)
        drive = np.clip(matrix @ self.w_avg, 0.0, None)
        return predict_lit_chart(self.panel.SRL, self.beta, np.eye(3), drive)


def panel_lights(
    measurements: Measurements, w_avgs: Mapping[str, np.ndarray]
) -> tuple[PanelLight, ...]:
    """Every panel type's :class:`PanelLight`, in file order (``w_avgs``: ``{name: (3,)}``).

    Raises
    ------
    InputError
        When a type's [SL] cannot be inverted, naming ``panels[i].primaries``.
    """
    lights = []
    for i, panel in enumerate(measurements.panels):
        try:
            M = solve_M(panel.SL)
        except InputError as error:
            raise InputError(
                error.problem, source=measurements.source, key=f"panels[{i}].primaries"
            ) from None
        w_avg = np.asarray(w_avgs[panel.name], dtype=np.float64)
        lights.append(PanelLight(panel, panel_type_beta(panel), M, w_avg))
    return tuple(lights)


def other_panels_light(lights: Sequence[PanelLight], primary: str) -> np.ndarray:
    """(n, 3) the chart lit by every type but ``primary``: the light its eq. 3 leaves out."""
    others = [light.lit() for light in lights if light.name != primary]
    return np.sum(others, axis=0) if others else np.zeros_like(lights[0].lit())


def light_shares(
    lights: Sequence[PanelLight], white_patch: int, camera_to_xyz: np.ndarray
) -> dict[str, float]:
    """Each type's share (0-1) of the light on the chart's white patch, by luminance."""
    y_row = np.asarray(camera_to_xyz, dtype=np.float64)[1]
    y = {light.name: max(float(y_row @ light.lit()[white_patch]), 0.0) for light in lights}
    total = sum(y.values())
    return {name: (value / total if total > 0 else 0.0) for name, value in y.items()}


def lit_white_errors(
    lights: Sequence[PanelLight], target: np.ndarray, white_patch: int, primary: str
) -> tuple[np.ndarray, np.ndarray]:
    """(3,) the lit white patch against the target's, per channel relative to it, before Q:
    with each type through its own M, and with every type driven with the first in-frustum
    type's M (as a calibration of that type alone would)."""
    M = next(light.M for light in lights if light.name == primary)
    target = np.asarray(target, dtype=np.float64)
    scale = white_scale(target, white_patch)
    white = target[white_patch]
    ours = sum(light.lit()[white_patch] for light in lights)
    theirs = sum(light.lit(M)[white_patch] for light in lights)
    return np.abs(ours - white) / scale, np.abs(theirs - white) / scale


@dataclass(frozen=True)
class InFrustumDrive:
    """An in-frustum type's background drive: ``N`` (None with ``N_reason`` when Q cannot be
    inverted; the type then shows content through its M) and the black-level ``offset``."""

    N: np.ndarray | None
    N_reason: str | None
    offset: np.ndarray | None

    def matrix(self, M: np.ndarray) -> np.ndarray:
        return M if self.N is None else self.N


def in_frustum_drive_for(
    light: PanelLight,
    Q: np.ndarray,
    *,
    black_level: np.ndarray | None,
    method: str,
    max_condition: float,
) -> InFrustumDrive:
    """N from eq. 7 with this type's [SL] (``Q [SL]_k N_k = I``) and its black-level offset."""
    N, reason = solve_N(light.M, Q, max_condition=max_condition, SL=light.panel.SL)
    offset = None
    if black_level is not None:
        offset = black_level_offset(black_level, M=light.M, SL=light.panel.SL, method=method)  # type: ignore[arg-type]
    return InFrustumDrive(N, reason, offset)


def shown_in_camera(
    light: PanelLight,
    drive: InFrustumDrive,
    content: np.ndarray,
    correction: PostCorrection,
    *,
    black_level: np.ndarray | None,
    max_drive: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """``content`` shown in-frustum on this type, as the camera records it after Q (before Q
    where N was not solved), and (n,) whether the type reaches each colour (every drive
    channel in ``[0, max_drive]``). A non-linear Q shows content through ``M Q^-1(c)``."""
    matrix = drive.matrix(light.M)
    if drive.N is not None and not correction.linear:
        content, matrix = correction.inverse(content), light.M
    d = in_frustum_drive(content, matrix=matrix, offset=drive.offset)
    top = np.inf if max_drive is None else max_drive
    reachable = np.all((d >= 0) & (d <= top), axis=-1)
    seen = predict_displayed_chart(
        content,
        SL=light.panel.SL,
        matrix=matrix,
        offset=drive.offset,
        black_level=black_level,
        max_drive=max_drive,
    )
    return (seen if drive.N is None else correction.apply(seen)), reachable


def in_frustum_match(
    lights: Sequence[PanelLight],
    drives: Mapping[str, InFrustumDrive],
    *,
    primary: str,
    target: np.ndarray,
    correction: PostCorrection,
    black_levels: Mapping[str, np.ndarray | None],
    white_patch: int,
    camera_to_xyz: np.ndarray,
) -> tuple[InFrustumMatch | None, list[str]]:
    """How closely the in-frustum types match in camera on the chart, and warnings.

    The target chart, as background content at the exposure where the first type's white
    peaks at drive 1 (:func:`ocio_vp.calibration.diagnostics.in_frustum_drive_range`), is
    shown on every in-frustum type through its N and offset, clipped to what the type can
    emit, then Q; each other type is compared with the first in ΔE2000 (relative to the first
    type's white). None when only one type is in frustum.
    """
    shown = [light for light in lights if light.name in drives]
    if len(shown) < 2:
        return None, []
    reference = next(light for light in shown if light.name == primary)
    peak = float(np.max(reference.M @ np.asarray(target, dtype=np.float64)[white_patch]))
    top = peak if peak > 0 else None
    seen = {
        light.name: shown_in_camera(
            light, drives[light.name], target, correction,
            black_level=black_levels.get(light.name), max_drive=top,
        )
        for light in shown
    }  # fmt: skip
    ref_colours, ref_reach = seen[primary]
    types: dict[str, TypeMatch] = {}
    warnings = []
    for name, (colours, reach) in seen.items():
        if name == primary:
            continue
        de = chart_errors(
            colours, ref_colours, camera_to_xyz=camera_to_xyz, white_patch=white_patch
        ).delta_E_2000
        lost = [int(j) for j in np.flatnonzero(ref_reach & ~reach)]
        gained = [int(j) for j in np.flatnonzero(reach & ~ref_reach)]
        types[name] = TypeMatch(
            delta_E_2000_mean=float(np.mean(de)),
            delta_E_2000_max=float(np.max(de)),
            unreachable=lost,
            unreachable_on_reference=gained,
        )
        for who, other, patches in ((name, primary, lost), (primary, name, gained)):
            if patches:
                worst = float(np.max(de[patches]))
                warnings.append(
                    f"in frustum, panel type {who} cannot show chart colour(s) {patches} that "
                    f"{other} shows (drive outside [0, 1] at the exposure where {primary}'s "
                    f"white peaks at 1): in camera they differ by up to ΔE2000 {worst:.1f}"
                )
    return InFrustumMatch(reference=primary, types=types), warnings


def panel_solutions(
    lights: Sequence[PanelLight],
    drives: Mapping[str, InFrustumDrive],
    shares: Mapping[str, float],
    linearity: Mapping[str, Linearity | None],
) -> dict[str, PanelSolution]:
    """solution.json's ``panels`` block: every type's M, w_avg, drive and share; N and the
    black-level offset for the in-frustum ones."""
    out = {}
    for light in lights:
        drive = drives.get(light.name)
        out[light.name] = PanelSolution(
            name=light.name,
            in_frustum=light.panel.in_frustum,
            SL=light.panel.SL,
            M=light.M,
            beta=light.beta,
            w_avg=light.w_avg,
            drive=light.drive,
            share=shares[light.name],
            N=None if drive is None else drive.N,
            N_reason=None if drive is None else drive.N_reason,
            black_level_offset=None if drive is None else drive.offset,
            linearity=linearity.get(light.name),
        )
    return out
