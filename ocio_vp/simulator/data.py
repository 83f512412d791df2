"""Spectral datasets for the stage simulator, all from colour-science's offline data.

Kept apart from the simulator's algorithms (:mod:`ocio_vp.simulator.stage`), as colour-science
keeps datasets apart from algorithms, and resampled onto one wavelength grid,
:data:`SPECTRAL_SHAPE` (380-780 nm in 5 nm steps, the grid of the cameras' sensitivities). The
paper's seven environments (Fig. 5) and a few extra light sources are :data:`ENVIRONMENTS`;
docs/simulator.md (*Environments*) names the spectrum chosen for each.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.spectra import (
    DEFAULT_CAMERA,
    DEFAULT_CHART,
    SPECTRAL_SHAPE,
    align,
    camera_sensitivities,
    checker_reflectances,
    spectral_shape,
    wavelengths,
)

__all__ = [
    "DEFAULT_CAMERA",
    "DEFAULT_CHART",
    "DEFAULT_LEDS",
    "ENVIRONMENTS",
    "PAPER_ENVIRONMENTS",
    "SPECTRAL_SHAPE",
    "EnvironmentSpec",
    "align",
    "camera_sensitivities",
    "camera_white_drive",
    "chart_reflectances",
    "describe_drive",
    "gaussian_leds",
    "light_spectrum",
    "wavelengths",
]

#: Paper-like narrow-band RGB LEDs: (peak nm, FWHM nm) for red, green, blue. Red AlInGaP and
#: blue InGaN LEDs are ~20 nm wide; green InGaN is broader (~35 nm).
DEFAULT_LEDS = ((630.0, 20.0), (525.0, 35.0), (460.0, 22.0))


def chart_reflectances(name: str = DEFAULT_CHART) -> np.ndarray:
    """(24, W) reflectances of a chart in ``colour.SDS_COLOURCHECKERS``, in reading order."""
    if name not in ("ColorChecker N Ohta", "BabelColor Average"):
        raise InputError(
            f"unknown chart {name!r}; expected 'ColorChecker N Ohta' or 'BabelColor Average'",
            key="chart",
        )
    return checker_reflectances(name)


def gaussian_leds(primaries=DEFAULT_LEDS) -> np.ndarray:
    """(W, 3) Gaussian LED emission spectra, unit peak, from three (peak nm, FWHM nm) pairs."""
    import colour

    pairs = [tuple(float(v) for v in p) for p in primaries]
    if len(pairs) != 3 or any(len(p) != 2 for p in pairs):
        raise InputError(f"expected three (peak, FWHM) pairs, got {primaries!r}", key="leds")
    for peak, fwhm in pairs:
        if not (300.0 <= peak <= 830.0 and 1.0 <= fwhm <= 300.0):
            raise InputError(
                f"LED peak {peak:g} nm / FWHM {fwhm:g} nm out of range "
                "(peak 300-830 nm, FWHM 1-300 nm)",
                key="leds",
            )
    return np.stack(
        [
            align(colour.sd_gaussian(peak, fwhm, spectral_shape(), method="FWHM"))
            for peak, fwhm in pairs
        ],
        axis=1,
    )


# Environments: each resolves to an (unnormalised) spectrum on the grid. The simulator scales
# it (see ocio_vp.simulator.stage.environment_spectrum); ``leds``/``camera`` are the stage's own.


@dataclass(frozen=True)
class EnvironmentSpec:
    """A named environment illuminant for the simulator.

    ``spectrum(leds, camera)`` returns the (W,) relative spectral distribution; only the
    stage's own RGB-LED white needs the stage. ``broadband`` marks the continuous spectra for
    which the paper's findings (Q helps, error < 4% of white) are expected to hold.
    """

    name: str
    description: str
    spectrum: Callable[[np.ndarray, np.ndarray], np.ndarray]
    broadband: bool


def light_spectrum(key: str) -> np.ndarray:
    """(W,) colour-science's ``SDS_ILLUMINANTS[key]`` or ``SDS_LIGHT_SOURCES[key]`` on the grid
    (no key is in both)."""
    import colour

    for collection in (colour.SDS_ILLUMINANTS, colour.SDS_LIGHT_SOURCES):
        if key in collection:
            return align(collection[key])
    raise KeyError(key)  # a typo in a table of the package, not a user error


def camera_white_drive(leds: np.ndarray, camera: np.ndarray) -> np.ndarray:
    """(3,) the drive that makes the camera see R = G = B = 1 from the stage's own LEDs:
    ``[SL]^-1 [1, 1, 1]`` (eq. 1's [SL]); a negative entry means they cannot mix it.

    >>> from ocio_vp.simulator.stage import paper_stage
    >>> stage = paper_stage()
    >>> bool(np.all(camera_white_drive(stage.leds, stage.camera) > 0))
    True
    """
    return np.linalg.solve(camera.T @ leds, np.ones(3))


def describe_drive(drive: np.ndarray) -> str:
    """``'drive R 3.45, G -0.794, B 1.38'``: a drive for people, three significant digits."""
    return "drive " + ", ".join(f"{n} {d:.3g}" for n, d in zip("RGB", drive, strict=True))


def _rgb_led_white(leds: np.ndarray, camera: np.ndarray) -> np.ndarray:
    drive = camera_white_drive(leds, camera)
    if np.any(drive < 0):
        # Sigma's Foveon sensor with 620/535/455 nm LEDs: green would need negative light.
        negative = ", ".join(n for n, d in zip("RGB", drive, strict=True) if d < 0)
        raise InputError(
            f"rgb_led_white: this camera sees no mix of the stage's LEDs as neutral: it needs "
            f"negative drive in {negative} ({describe_drive(drive)}); leave this environment out",
            key="environment",
        )
    return leds @ drive


def _spectrum(key: str | None) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The stage's own white (``None``), else :func:`light_spectrum` of ``key``."""
    return _rgb_led_white if key is None else lambda leds, camera: light_spectrum(key)


#: The paper's seven environments (Fig. 5), in the paper's order.
PAPER_ENVIRONMENTS = (
    "warm_white_led",
    "incandescent",
    "indoor_daylight",
    "rgb_led_white",
    "sodium_vapour",
    "outdoor_shade",
    "direct_sun",
)

#: (safe name, description, colour-science key or None for the stage's own white, broadband).
_ENVIRONMENT_TABLE = (
    (
        "warm_white_led",
        "warm white phosphor LED (colour: SDS_LIGHT_SOURCES['Luxeon WW 2880'])",
        "Luxeon WW 2880",
        True,
    ),
    ("incandescent", "incandescent tungsten, CIE illuminant A (2856 K)", "A", True),
    ("indoor_daylight", "indoor daylight through window glass, CIE ID65", "ID65", True),
    ("rgb_led_white", "the stage's own R, G, B LEDs mixed to a camera-neutral white", None, False),
    (
        "sodium_vapour",
        "low-pressure sodium vapour (colour: SDS_LIGHT_SOURCES['LPS'])",
        "LPS",
        False,
    ),
    ("outdoor_shade", "outdoors in shade, CIE D75", "D75", True),
    ("direct_sun", "outdoors in direct sun, CIE D55", "D55", True),
    (
        "high_pressure_sodium",
        "high-pressure sodium (colour: SDS_LIGHT_SOURCES['HPS'])",
        "HPS",
        False,
    ),
    ("d65", "CIE D65 daylight", "D65", True),
    ("d50", "CIE D50 daylight", "D50", True),
)
#: Every named environment the simulator knows, by safe name.
ENVIRONMENTS: dict[str, EnvironmentSpec] = {
    name: EnvironmentSpec(name, description, _spectrum(key), broadband)
    for name, description, key, broadband in _ENVIRONMENT_TABLE
}
