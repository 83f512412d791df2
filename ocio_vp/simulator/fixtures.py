"""Simulated practical fixtures, built from colour-science's spectra.

Each kind (:data:`FIXTURE_KINDS`, listed in docs/fixtures.md) has the stage's own red, green and
blue LED spectra plus white, amber, cyan, lime or fluorescent channels. Every channel is scaled
so that at drive 1 its luminance (CIE 1931 Y) equals the stage's green LED's; a fixture's chart
at its reference drive 1 is the chart lit uniformly by that spectrum, in the units of the
wall's ``[SRL]_j / beta``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ocio_vp.errors import InputError
from ocio_vp.formats.fixtures import Fixture
from ocio_vp.formats.measurements import Measurements
from ocio_vp.simulator.data import DEFAULT_LEDS, gaussian_leds, light_spectrum
from ocio_vp.simulator.extremes import luminance
from ocio_vp.simulator.stage import SpectralStage, camera_rgb
from ocio_vp.spectra import unknown_name

__all__ = [
    "FIXTURE_KINDS",
    "fixture_spectra",
    "simulated_fixture",
    "with_simulated_fixtures",
]

_RGB = (("red", DEFAULT_LEDS[0]), ("green", DEFAULT_LEDS[1]), ("blue", DEFAULT_LEDS[2]))

#: kind -> channels as (name, (peak nm, FWHM nm) for a Gaussian LED, or a colour dataset key).
FIXTURE_KINDS: dict[str, tuple[tuple[str, object], ...]] = {
    "rgbw": (*_RGB, ("white", "LED-B1")),
    "rgbww": (*_RGB, ("warm_white", "LED-B1"), ("cool_white", "LED-B5")),
    "rgbacl": (*_RGB, ("amber", (592.0, 18.0)), ("cyan", (497.0, 28.0)), ("lime", (555.0, 100.0))),
    "rgbw-fluorescent": (*_RGB, ("white", "FL2")),
}


def _spectrum(source: object) -> np.ndarray:
    if isinstance(source, tuple):
        return gaussian_leds((source, source, source))[:, 0]
    return light_spectrum(str(source))


def fixture_spectra(stage: SpectralStage, kind: str) -> tuple[tuple[str, ...], np.ndarray]:
    """(channel names, (W, k) radiance per unit drive) of a fixture kind on ``stage``."""
    if kind not in FIXTURE_KINDS:
        raise InputError(unknown_name("fixture kind", kind, FIXTURE_KINDS), key="fixture")
    names = tuple(name for name, _ in FIXTURE_KINDS[kind])
    spectra = np.column_stack([_spectrum(source) for _, source in FIXTURE_KINDS[kind]])
    green = float(luminance(stage.leds[:, 1]))
    return names, spectra * (green / luminance(spectra.T))


def simulated_fixture(stage: SpectralStage, kind: str, name: str | None = None) -> Fixture:
    """The fixture as a measurements file records it: its chart lit by each channel at drive 1.

    Examples
    --------
    >>> from ocio_vp.simulator.stage import paper_stage
    >>> f = simulated_fixture(paper_stage(), "rgbw")
    >>> f.channels, f.lit_chart.shape
    (('red', 'green', 'blue', 'white'), (4, 24, 3))
    """
    channels, spectra = fixture_spectra(stage, kind)
    lit = stage.reflectances[None, :, :] * spectra.T[:, None, :]  # (k, n, W)
    return Fixture(
        name=name or kind.replace("-", "_"),
        channels=channels,
        reference_drive=1.0,
        lit_chart=camera_rgb(stage, lit),
        direct=camera_rgb(stage, spectra.T),
    )


def with_simulated_fixtures(
    measurements: Measurements, stage: SpectralStage, kinds: Sequence[str]
) -> Measurements:
    """``measurements`` with one simulated fixture per kind (named after the kind)."""
    fixtures = tuple(simulated_fixture(stage, kind) for kind in kinds)
    return dataclasses.replace(measurements, fixtures=fixtures)
