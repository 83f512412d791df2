"""Spectral stage simulator: measurements and ground truth from spectra (colour-science data).

:func:`spectral_stage` builds a stage's spectra (:func:`paper_stage`: the default one, Nikon
5100, paper-like 630/525/460 nm LEDs, ColorChecker N Ohta, 1 m x 1 m panel at 1 m, albedo
4%); :func:`simulate_measurements` gives its complete measurements file.

The model and its units (radiance on one wavelength grid, camera RGB as ``sum S R E``, the
wall white-balanced to D65 at drive [1, 1, 1], ``[SRL]_j = beta sum S R_j L_k``, the black level
``b_camera = albedo [SL] clip(M w_avg, 0)``) are in docs/simulator.md (*Model*).

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eqs. 1-8, Sec. 3.4.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import DEFAULT_WHITE_PATCH, SAMPLE_WALL_GAIN
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import Environment, Measurements, PanelGeometry, Stage
from ocio_vp.simulator.data import (
    DEFAULT_CAMERA,
    DEFAULT_CHART,
    DEFAULT_LEDS,
    ENVIRONMENTS,
    PAPER_ENVIRONMENTS,
    camera_sensitivities,
    chart_reflectances,
    gaussian_leds,
    wavelengths,
)
from ocio_vp.spectra import spectral_shape, unknown_name

if TYPE_CHECKING:
    import colour

#: An environment's light: a name from ``ENVIRONMENTS``, a colour ``SpectralDistribution`` or
#: a (W,) array on the simulator's grid.
EnvironmentLight: TypeAlias = "str | colour.SpectralDistribution | ArrayLike"
#: Which environments to simulate: a name, names, or safe name -> light (None: the paper's).
Environments: TypeAlias = "str | Sequence[str] | Mapping[str, EnvironmentLight] | None"
#: An LED set: three (peak, FWHM) pairs (nm), (W, 3) spectra, or a colour
#: ``MultiSpectralDistributions`` of three channels (None: the default LEDs).
Leds: TypeAlias = "ArrayLike | colour.MultiSpectralDistributions | None"
_Light = TypeVar("_Light")

__all__ = [
    "DEFAULT_PANEL",
    "DEFAULT_PANEL_ALBEDO",
    "ENVIRONMENTS",
    "PAPER_ENVIRONMENTS",
    "SpectralStage",
    "camera_rgb",
    "environment_spectrum",
    "paper_stage",
    "paper_stage_measurements",
    "simulate_measurements",
    "spectral_stage",
    "white_reflectance",
]

#: The paper's calibration panel: 1 m x 1 m at 1 m (beta = 0.23946).
DEFAULT_PANEL = PanelGeometry(width=1.0, height=1.0, distance=1.0)
#: The paper observed panel albedos of ~4-10%; the default stage uses the low end.
DEFAULT_PANEL_ALBEDO = 0.04


@dataclass(frozen=True)
class SpectralStage:
    """A simulated stage: spectra on :func:`~ocio_vp.simulator.data.wavelengths`.

    ``camera`` (W, 3) sensitivities; ``leds`` (W, 3) radiance of the R, G, B channels at drive
    1; ``reflectances`` (n, W) the chart; ``beta`` the calibration panel's form factor;
    ``panel_albedo`` the in-frustum panels' reflectance (``None``: no black level).
    """

    name: str
    camera: np.ndarray
    leds: np.ndarray
    reflectances: np.ndarray
    panel: PanelGeometry | None
    beta: float
    panel_albedo: float | None = None
    white_patch: int = DEFAULT_WHITE_PATCH
    camera_name: str = DEFAULT_CAMERA
    chart_name: str = DEFAULT_CHART
    led_description: str = ""
    #: The wall's full-drive white in units of the location's white (a perfect white diffuser
    #: reads green = 1 under every environment; the wall at drive [1, 1, 1] reads green =
    #: ``wall_gain``): how far above content white the camera's exposure puts the wall's peak.
    wall_gain: float = 1.0

    @property
    def SL(self) -> np.ndarray:
        """(3, 3) [SL]: camera RGB of each LED channel at drive 1 (paper, eq. 1)."""
        return camera_rgb(self, self.leds.T).T

    @property
    def SRL_unscaled(self) -> np.ndarray:
        """(n, 3, 3) [SRL]_j / beta: patch j under a uniform sphere of each LED channel."""
        lit = self.reflectances[:, None, :] * self.leds.T[None, :, :]  # (n, LED, W)
        return np.swapaxes(camera_rgb(self, lit), 1, 2)  # (n, camera, LED)


def camera_rgb(stage: SpectralStage, spectrum: ArrayLike) -> np.ndarray:
    """(..., 3) camera RGB of (..., W) spectral radiance, ``sum_lambda S_c(lambda) E(lambda)``.

    Examples
    --------
    A perfect white diffuser under an environment reads green = 1 (the simulator's exposure):

    >>> stage = paper_stage()
    >>> round(float(camera_rgb(stage, environment_spectrum(stage, "direct_sun"))[1]), 12)
    1.0
    """
    return np.asarray(spectrum, dtype=np.float64) @ stage.camera


def _resolve_leds(leds: Leds) -> tuple[np.ndarray, str]:
    if leds is None:
        leds = DEFAULT_LEDS
    array = np.asarray(leds, dtype=np.float64) if not hasattr(leds, "values") else None
    if array is not None and array.shape == (3, 2):
        pairs = ", ".join(f"{p:g}/{f:g} nm" for p, f in array)
        return gaussian_leds(array), f"Gaussian LEDs (peak/FWHM) {pairs}"
    import colour

    if isinstance(leds, colour.MultiSpectralDistributions):  # with 3 channels
        array = np.asarray(leds.copy().align(spectral_shape()).values, dtype=np.float64)
    if array is None or array.shape != (len(wavelengths()), 3) or not np.all(np.isfinite(array)):
        raise InputError(
            "expected three (peak, FWHM) pairs or (W, 3) measured spectra on 380-780 nm / 5 nm, "
            f"got {getattr(array, 'shape', type(leds).__name__)}",
            key="leds",
        )
    if np.any(array < 0) or np.any(array.max(axis=0) <= 0):
        raise InputError("LED spectra must be >= 0 and not all zero", key="leds")
    return array, "measured LED spectra"


def spectral_stage(
    *,
    camera: str = DEFAULT_CAMERA,
    leds: Leds = None,
    chart: str = DEFAULT_CHART,
    panel: PanelGeometry | None = None,
    beta: float | None = None,
    panel_albedo: float | None = DEFAULT_PANEL_ALBEDO,
    name: str = "simulated-stage",
    wall_gain: float = 1.0,
) -> SpectralStage:
    """Build a :class:`SpectralStage` from colour-science datasets.

    Parameters
    ----------
    camera
        A name of :func:`ocio_vp.spectra.camera_names`: colour's
        ``MSDS_CAMERA_SENSITIVITIES`` or the measured cameras shipped with ocio_vp.
    leds
        Three ``(peak nm, FWHM nm)`` pairs for Gaussian primaries (default
        :data:`~ocio_vp.simulator.data.DEFAULT_LEDS`), or measured spectra: a (W, 3) array on
        the simulator's grid or a colour ``MultiSpectralDistributions``.
    chart
        ``'ColorChecker N Ohta'`` or ``'BabelColor Average'`` (24 patches, white = 18).
    panel, beta
        The calibration panel's geometry (beta from the closed-form form factor; default
        :data:`DEFAULT_PANEL`), or beta alone (then the file carries ``beta``).
    panel_albedo
        Grey reflectance of the in-frustum panels (black level), ``None`` for none.
    """
    from ocio_vp.calibration.geometry import panel_beta
    from ocio_vp.formats.measurements import check_safe_name

    check_safe_name(name, key="name")
    if beta is None:
        panel = DEFAULT_PANEL if panel is None else panel
        beta = panel_beta(panel)
    elif not 0.0 < beta <= 1.0:
        raise InputError(f"beta is a form factor in (0, 1], got {beta!r}", key="beta")
    elif panel is not None and abs(panel_beta(panel) - beta) > 1e-9 * beta:
        raise InputError(
            f"beta {beta!r} disagrees with the panel geometry's {panel_beta(panel):.6g}; "
            "give one of them",
            key="beta",
        )
    if panel_albedo is not None and not 0.0 <= panel_albedo < 1.0:
        raise InputError(f"panel albedo must be in [0, 1), got {panel_albedo!r}", key="albedo")
    sensitivities = camera_sensitivities(camera)
    raw_leds, description = _resolve_leds(leds)
    reflectances = chart_reflectances(chart)
    # White-balance the wall: drive [1, 1, 1] looks like D65 (green = 1) to the camera.
    unscaled = sensitivities.T @ raw_leds
    _check_camera_tells_leds_apart(unscaled)
    d65 = ENVIRONMENTS["d65"].spectrum(raw_leds, sensitivities) @ sensitivities
    gains = np.linalg.solve(unscaled, d65 / d65[1])
    if np.any(gains <= 0):
        raise InputError(
            f"these LEDs cannot mix to D65 for this camera (gains {gains.round(4)})", key="leds"
        )
    if not (np.isfinite(wall_gain) and 0.0 < wall_gain <= 1e4):
        raise InputError(f"expected 0 < gain <= 10000, got {wall_gain!r}", key="wall_gain")
    return SpectralStage(
        name=name,
        camera=sensitivities,
        leds=raw_leds * gains * wall_gain,
        wall_gain=float(wall_gain),
        reflectances=reflectances,
        panel=panel,
        beta=float(beta),
        panel_albedo=None if panel_albedo is None else float(panel_albedo),
        camera_name=camera,
        chart_name=chart,
        led_description=description,
    )


def white_reflectance(stage: SpectralStage) -> float:
    """The chart white patch's reflectance as the camera's green channel sees it, ``sum S_g
    R_white / sum S_g`` to 4 digits (not the paper's nominal 0.9), for w_avg from the white
    patch."""
    green = stage.camera[:, 1]
    return round(float(green @ stage.reflectances[stage.white_patch] / green.sum()), 4)


def paper_stage(wall_gain: float = SAMPLE_WALL_GAIN) -> SpectralStage:
    """The default simulated stage (see the module docstring), named ``paper-stage``, its wall's
    peak two stops above content white, as a stage engineer sets it up (docs/headroom.md)."""
    return spectral_stage(name="paper-stage", wall_gain=wall_gain)


def _check_camera_tells_leds_apart(SL: np.ndarray) -> None:
    """Refuse LEDs whose [SL] (eq. 1) the solve would refuse: singular or as badly conditioned
    as :data:`~ocio_vp.calibration.equations.MAX_CONDITION_SL`."""
    from ocio_vp.calibration.equations import MAX_CONDITION_SL, condition_number

    if not condition_number(SL) < MAX_CONDITION_SL:
        raise InputError(
            "the camera cannot tell these LEDs apart ([SL] is singular: two of them look alike "
            "to it, or one is dark to it); choose LEDs of different colours",
            key="leds",
        )


def environment_spectrum(stage: SpectralStage, environment: EnvironmentLight) -> np.ndarray:
    """(W,) an environment's spectrum (see :data:`EnvironmentLight`), scaled so a perfect
    white diffuser reads green = 1."""
    if isinstance(environment, str):
        if environment not in ENVIRONMENTS:
            raise InputError(
                unknown_name("environment", environment, ENVIRONMENTS), key="environment"
            )
        spectrum = ENVIRONMENTS[environment].spectrum(stage.leds, stage.camera)
    elif hasattr(environment, "align"):
        from ocio_vp.simulator.data import align

        spectrum = align(environment)
    else:
        spectrum = np.asarray(environment, dtype=np.float64)
    if spectrum.shape != (len(wavelengths()),) or not np.all(np.isfinite(spectrum)):
        raise InputError(
            f"an environment spectrum needs {len(wavelengths())} finite values on 380-780 nm / "
            f"5 nm, got shape {spectrum.shape}",
            key="environment",
        )
    green = camera_rgb(stage, spectrum)[1]
    if np.any(spectrum < 0) or not green > 0:
        raise InputError("an environment spectrum must be >= 0 and visible", key="environment")
    return spectrum / green


def named_lights(
    environments: str | Sequence[str] | Mapping[str, _Light] | None,
    default: Sequence[str] = PAPER_ENVIRONMENTS,
) -> list[tuple[str, _Light | str]]:
    """(name, light) pairs of a name, names or name -> light mapping (None: ``default``)."""
    if environments is None:
        environments = default
    if isinstance(environments, str):
        environments = (environments,)
    if isinstance(environments, Mapping):
        return list(environments.items())
    return [(name, name) for name in environments]


def black_level_reading(
    stage: SpectralStage, M: np.ndarray, w_avg: np.ndarray
) -> np.ndarray | None:
    if stage.panel_albedo is None:
        return None
    drive = np.clip(M @ w_avg, 0.0, None)
    return stage.panel_albedo * camera_rgb(stage, stage.leds @ drive)


def simulate_measurements(
    environments: Environments = None, *, stage: SpectralStage | None = None, **options: Any
) -> Measurements:
    """Simulate a complete measurements file (version 1) for a stage and environments.

    Parameters
    ----------
    environments
        Names from :data:`ENVIRONMENTS` (default: the paper's seven), or a mapping of safe
        name -> environment (name, ``SpectralDistribution`` or (W,) array).
    stage
        A :class:`SpectralStage`; otherwise ``options`` are passed to :func:`spectral_stage`.

    Returns
    -------
    Measurements
        [SL] (eq. 1), [SRL]_j *as photographed* (beta x the uniform-sphere value), and per
        environment the target chart p_j, the true diffuse integral w_avg and, when the stage
        has a panel albedo, the black level b_camera seen with M = [SL]^-1 lighting the stage.

    Examples
    --------
    The stage's own LEDs mixed to a white need no post-correction (Q = I):

    >>> from ocio_vp.pipeline import solve_environment
    >>> m = simulate_measurements(["rgb_led_white"])
    >>> s = solve_environment(m, m.environments[0], method="least-squares")
    >>> bool(np.allclose(s.Q, np.eye(3), atol=1e-9))
    True
    """
    from ocio_vp.formats.measurements import check_safe_name

    if stage is None:
        stage = spectral_stage(**options)
    elif options:
        raise TypeError(f"give either stage= or stage options, not both: {sorted(options)}")
    SL = stage.SL
    M = np.linalg.inv(SL)
    envs = []
    for name, environment in named_lights(environments):
        check_safe_name(name, key="environment")
        spectrum = environment_spectrum(stage, environment)
        target = camera_rgb(stage, stage.reflectances * spectrum)
        w_avg = camera_rgb(stage, spectrum)
        envs.append(
            Environment(
                name=name,
                target_chart=target,
                w_avg=w_avg,
                black_level=black_level_reading(stage, M, w_avg),
            )
        )
    return Measurements(
        stage=Stage(
            name=stage.name,
            panel=stage.panel,
            beta=None if stage.panel is not None else stage.beta,
            white_patch=stage.white_patch,
            white_reflectance=white_reflectance(stage),
        ),
        SL=SL,
        SRL=stage.beta * stage.SRL_unscaled,
        environments=tuple(envs),
        source=None,  # in memory; solution.json names the file once it is saved
    )


def paper_stage_measurements(environments: Environments = PAPER_ENVIRONMENTS) -> Measurements:
    """:func:`simulate_measurements` of :func:`paper_stage` (default: the paper's seven)."""
    return simulate_measurements(environments, stage=paper_stage())
