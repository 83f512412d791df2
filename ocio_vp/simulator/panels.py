"""A simulated stage of two panel types: the wall and a ceiling of another panel model.

The ceiling is a second :class:`~ocio_vp.simulator.stage.SpectralStage` with its own LEDs, its
own calibration panel and no black level, its processor matched to the wall's white. A
**scene** (:data:`SCENES`) lights it with one spectrum from above (the ceiling's part) and
another from the sides (the wall's): docs/simulator.md (*A ceiling of another panel model*).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeAlias

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import Environment, Measurements, PanelGeometry, Stage
from ocio_vp.formats.panels import PanelRegion, PanelType
from ocio_vp.simulator.data import ENVIRONMENTS, light_spectrum
from ocio_vp.simulator.stage import (
    EnvironmentLight,
    Leds,
    SpectralStage,
    camera_rgb,
    environment_spectrum,
    named_lights,
    spectral_stage,
    white_reflectance,
)
from ocio_vp.simulator.truth import HeldOutErrors, held_out_errors
from ocio_vp.spectra import align, unknown_name

#: An environment of a two-type stage: a name of ``SCENES``, any light of
#: :data:`~ocio_vp.simulator.stage.EnvironmentLight` (the same everywhere), or
#: ``{"wall": spectrum, "ceiling": spectrum}``.
SceneLight: TypeAlias = "EnvironmentLight | Mapping[str, ArrayLike]"
#: Which environments: a name, names, or safe name -> light (None: every scene).
Scenes: TypeAlias = "str | Sequence[str] | Mapping[str, SceneLight] | None"

__all__ = [
    "CEILING_PANEL",
    "CEILING_REGION",
    "DEFAULT_CEILING_GAIN",
    "DEFAULT_CEILING_LEDS",
    "DEFAULT_CEILING_SHARE",
    "SCENES",
    "WALL_REGION",
    "PanelStage",
    "Scene",
    "panel_held_out_errors",
    "panel_stage",
    "scene_light",
    "simulate_panel_measurements",
    "wall_only_measurements",
]

#: The ceiling's LEDs: another panel model than the wall's (peak/FWHM nm, red, green, blue).
DEFAULT_CEILING_LEDS = ((618.0, 24.0), (538.0, 40.0), (470.0, 26.0))
#: How much brighter the ceiling is than the wall at the same drive (1: matched).
DEFAULT_CEILING_GAIN = 1.0
#: The ceiling's calibration panel: a 1.2 m x 0.6 m tile at 1.5 m (beta 0.087).
CEILING_PANEL = PanelGeometry(width=1.2, height=0.6, distance=1.5)
#: Share of a uniform environment's diffuse light that comes from above.
DEFAULT_CEILING_SHARE = 0.35
#: Where the two types are as seen from the chart (for ``--hdri``): the ceiling above 40 deg.
WALL_REGION = PanelRegion(elevation=(-90.0, 40.0))
CEILING_REGION = PanelRegion(elevation=(40.0, 90.0))


@dataclass(frozen=True)
class Scene:
    """Light from above (``above``) and from the sides (``sides``), each a function of the
    stage returning a (W,) spectrum; ``share``: the part of the diffuse light from above."""

    name: str
    description: str
    above: Callable[[], np.ndarray]
    sides: Callable[[], np.ndarray]
    share: float
    broadband: bool = True


def _daylight(cct: float) -> np.ndarray:
    import colour

    xy = colour.temperature.CCT_to_xy_CIE_D(cct * 1.4388 / 1.4380)
    return align(colour.sd_CIE_illuminant_D_series(xy))


def _planckian(cct: float) -> np.ndarray:
    import colour

    return align(colour.sd_blackbody(cct))


def _ground() -> np.ndarray:
    """Overcast light from the sides: half horizon sky (D65), half bounced off grass."""
    import colour

    d65 = align(colour.SDS_ILLUMINANTS["D65"])
    grass = align(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"]["foliage"])
    return 0.5 * d65 / d65.max() + 0.5 * grass * d65 / (grass * d65).max()


#: Scenes with light from above and from the sides (sky, sun, ground, lamps).
SCENES: dict[str, Scene] = {
    s.name: s
    for s in (
        Scene("overcast", "overcast sky (D65) above, horizon sky and grass from the sides",
              partial(_daylight, 6504.0), _ground, 0.65),
        Scene("clear_sky", "blue sky (CIE D 12000 K) above, the sun (D50) from the side",
              partial(_daylight, 12000.0), partial(light_spectrum, "D50"), 0.3),
        Scene("golden_hour", "sky (CIE D 9000 K) above, a low sun (Planckian 3000 K) from the side",
              partial(_daylight, 9000.0), partial(_planckian, 3000.0), 0.35),
        Scene("interior", "triband fluorescent (FL11) ceiling lights, tungsten (A) lamps",
              partial(light_spectrum, "FL11"), partial(light_spectrum, "A"), 0.55),
        Scene("night_street", "white LED street lights (LED-B3) above, sodium (HPS) from the side",
              partial(light_spectrum, "LED-B3"), partial(light_spectrum, "HPS"), 0.5, broadband=False),
    )
}  # fmt: skip


@dataclass(frozen=True)
class PanelStage:
    """The two panel types (``wall`` in frustum, ``ceiling`` not), sharing camera and chart."""

    wall: SpectralStage
    ceiling: SpectralStage

    @property
    def types(self) -> tuple[tuple[str, SpectralStage], ...]:
        return (("wall", self.wall), ("ceiling", self.ceiling))


def panel_stage(
    wall: SpectralStage | None = None,
    *,
    ceiling_leds: Leds = DEFAULT_CEILING_LEDS,
    gain: float = DEFAULT_CEILING_GAIN,
    panel: PanelGeometry = CEILING_PANEL,
    white: str = "xyz",
    **wall_options: Any,
) -> PanelStage:
    """A wall (``wall``, or :func:`~ocio_vp.simulator.stage.spectral_stage` of
    ``wall_options``) and a ceiling of ``ceiling_leds`` (as :func:`spectral_stage`'s ``leds``)
    with the same camera and chart, ``gain`` times as bright as the wall at the same drive.

    ``white``: how the ceiling's processor was matched to the wall at drive [1, 1, 1]:
    ``"xyz"`` (default) to the wall's white as a spectroradiometer measures it (CIE 1931 XYZ,
    as panel vendors calibrate), ``"camera"`` to the wall's white as this camera sees it (the
    most a calibration of the wall alone could hope for).
    """
    from ocio_vp.synthesis.camera import cie_cmfs

    if wall is None:
        wall = spectral_stage(**wall_options)
    elif wall_options:
        raise TypeError(f"give either wall= or wall options, not both: {sorted(wall_options)}")
    if not 0.01 <= gain <= 100.0:
        raise InputError(f"expected a gain in [0.01, 100], got {gain!r}", key="gain")
    if white not in ("xyz", "camera"):
        raise InputError(f"expected 'xyz' or 'camera', got {white!r}", key="white")
    try:
        ceiling = spectral_stage(
            camera=wall.camera_name,
            leds=ceiling_leds,
            chart=wall.chart_name,
            panel=panel,
            panel_albedo=None,
            name=wall.name,
        )
    except InputError as error:
        if error.key != "leds":
            raise
        raise InputError(error.problem, key="ceiling_leds") from None  # not the wall's LEDs
    observer = wall.camera  # camera: the ceiling is already matched to D65 as the wall is
    if white == "xyz":
        observer = cie_cmfs()
    target = observer.T @ wall.leds.sum(axis=1)
    gains = np.linalg.solve(observer.T @ ceiling.leds, target)
    if np.any(gains <= 0):
        raise InputError("the ceiling's LEDs cannot mix to the wall's white", key="ceiling_leds")
    return PanelStage(wall, dataclasses.replace(ceiling, leds=ceiling.leds * gains * gain))


def scene_light(stage: SpectralStage, environment: SceneLight) -> dict[str, np.ndarray]:
    """``{"wall": (W,), "ceiling": (W,)}``: the light from the sides and from above, summing to
    the environment as :func:`environment_spectrum` scales it (white diffuser green = 1).

    ``environment``: a name of :data:`SCENES`, a name of
    :data:`~ocio_vp.simulator.data.ENVIRONMENTS` or a (W,) spectrum (the same light everywhere:
    :data:`DEFAULT_CEILING_SHARE` of it from above), or a mapping
    ``{"wall": spectrum, "ceiling": spectrum}``.
    """
    if isinstance(environment, Mapping):
        parts = {k: np.asarray(environment[k], dtype=np.float64) for k in ("wall", "ceiling")}
    elif isinstance(environment, str) and environment in SCENES:
        scene = SCENES[environment]
        above, sides = scene.above(), scene.sides()
        green = [camera_rgb(stage, s)[1] for s in (above, sides)]
        parts = {
            "ceiling": above / green[0] * scene.share,
            "wall": sides / green[1] * (1 - scene.share),
        }
    elif not isinstance(environment, str) or environment in ENVIRONMENTS:
        total = environment_spectrum(stage, environment)
        parts = {
            "ceiling": DEFAULT_CEILING_SHARE * total,
            "wall": (1 - DEFAULT_CEILING_SHARE) * total,
        }
    else:
        raise InputError(
            unknown_name("environment", environment, {**SCENES, **ENVIRONMENTS}), key="environment"
        )
    scale = camera_rgb(stage, parts["wall"] + parts["ceiling"])[1]
    return {k: v / scale for k, v in parts.items()}


def _panel_type(name: str, spectral: SpectralStage, region: PanelRegion) -> PanelType:
    return PanelType(
        name=name,
        in_frustum=name == "wall",
        SL=spectral.SL,
        SRL=spectral.beta * spectral.SRL_unscaled,
        panel=spectral.panel,
        beta=None if spectral.panel is not None else spectral.beta,
        regions=(region,),
    )


def simulate_panel_measurements(stage: PanelStage, environments: Scenes = None) -> Measurements:
    """The measurements file of ``stage`` (``panels``: wall, ceiling) for ``environments``
    (default every scene of :data:`SCENES`; see :func:`scene_light` for what else they may be).

    Per environment: the target chart under the whole light, each type's true w_avg (camera
    RGB of its part of the light), and the wall's black level with both types lighting the
    stage through their own M.
    """
    from ocio_vp.formats.measurements import check_safe_name

    wall = stage.wall
    panels = (
        _panel_type("wall", wall, WALL_REGION),
        _panel_type("ceiling", stage.ceiling, CEILING_REGION),
    )
    envs = []
    for name, environment in named_lights(environments, tuple(SCENES)):
        check_safe_name(name, key="environment")
        light = scene_light(wall, environment)
        w_avg = {k: camera_rgb(wall, v) for k, v in light.items()}
        emitted = sum(
            s.leds @ np.clip(np.linalg.solve(s.SL, w_avg[k]), 0.0, None) for k, s in stage.types
        )
        albedo = wall.panel_albedo  # the dark in-frustum wall reflects both types' light
        envs.append(
            Environment(
                name=name,
                target_chart=camera_rgb(
                    wall, wall.reflectances * (light["wall"] + light["ceiling"])
                ),
                panel_w_avg=w_avg,
                panel_black_level=None
                if albedo is None
                else {"wall": albedo * camera_rgb(wall, emitted)},
            )
        )
    return Measurements(
        stage=Stage(
            name=wall.name,
            white_patch=wall.white_patch,
            white_reflectance=white_reflectance(wall),
        ),
        SL=panels[0].SL,
        SRL=panels[0].SRL,
        environments=tuple(envs),
        panels=panels,
        source=None,
    )


def panel_held_out_errors(
    stage: PanelStage,
    environment: SceneLight,
    *,
    M: Mapping[str, np.ndarray],
    correct: Callable[[np.ndarray], np.ndarray],
    reflectances: np.ndarray,
) -> HeldOutErrors:
    """How a solve renders ``reflectances`` (k, W) on the two-type stage, against the light.

    Each type shows its part of the environment through the matrix ``M[type]`` (a per-type
    calibration gives each its own; a calibration of the wall alone drives the ceiling with
    the wall's M) and emits that drive clipped at 0 through its true LEDs; the camera sees the
    samples lit by both, ``correct`` post-corrects them (the product's own
    ``solution.correction.apply``); the reference is the samples under the environment
    (:func:`~ocio_vp.simulator.truth.held_out_errors`).
    """
    wall = stage.wall
    light = scene_light(wall, environment)
    w_avg = {k: camera_rgb(wall, v) for k, v in light.items()}
    ceiling = stage.ceiling
    emitted = ceiling.leds @ np.clip(np.asarray(M["ceiling"]) @ w_avg["ceiling"], 0.0, None)
    return held_out_errors(
        wall,
        light["wall"] + light["ceiling"],
        M=M["wall"],
        w_avg=w_avg["wall"],
        Q=np.eye(3),
        reflectances=reflectances,
        extra_emission=emitted,
        correct=correct,
    )


def wall_only_measurements(measurements: Measurements) -> Measurements:
    """What a calibration of the first in-frustum type alone sees: its primaries and lit
    chart, the whole environment's w_avg (every type's summed) and its black level, no
    ``panels``. Its M then drives every type (the baseline the per-type solve is judged
    against)."""
    first = next(p for p in measurements.panels if p.in_frustum)
    environments = tuple(
        Environment(
            name=e.name,
            target_chart=e.target_chart,
            w_avg=None if e.panel_w_avg is None else sum(e.panel_w_avg.values(), np.zeros(3)),
            black_level=(e.panel_black_level or {}).get(first.name),
        )
        for e in measurements.environments
    )
    stage = dataclasses.replace(measurements.stage, panel=first.panel, beta=first.beta)
    return Measurements(
        stage=stage,
        SL=first.SL,
        SRL=first.SRL,
        environments=environments,
        ramps=first.ramps,
        source=measurements.source,
    )
