"""ocio_vp/simulator/data.py: the environments' spectra on a stage's own LEDs."""

from __future__ import annotations

import re

import colour
import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.simulator.stage import simulate_measurements, spectral_stage

SIGMA = "Sigma SDMerill (NPL)"
SHIFTED = ((620, 20), (535, 35), (455, 22))


def _independent_white_drive() -> np.ndarray:
    # From colour-science's own camera data, Gaussians and D65, not the simulator's: the LEDs
    # scaled so drive [1, 1, 1] looks like D65 (green 1) to the camera, then [SL]^-1 [1, 1, 1].
    shape = colour.SpectralShape(380, 780, 5)
    camera = colour.MSDS_CAMERA_SENSITIVITIES[SIGMA].copy().align(shape).values
    leds = np.stack(
        [colour.sd_gaussian(p, w, shape, method="FWHM").values for p, w in SHIFTED], axis=1
    )
    d65 = camera.T @ colour.SDS_ILLUMINANTS["D65"].copy().align(shape).values
    SL = camera.T @ leds * np.linalg.solve(camera.T @ leds, d65 / d65[1])
    return np.linalg.solve(SL, np.ones(3))


def test_rgb_led_white_refusal_names_the_environment_and_the_negative_drive():
    # Foveon-like overlapping sensitivities: no positive mix of these LEDs looks neutral to it.
    expected = _independent_white_drive()
    assert expected[1] < 0 < min(expected[0], expected[2])
    stage = spectral_stage(camera=SIGMA, leds=SHIFTED)
    with pytest.raises(InputError) as caught:
        simulate_measurements(["rgb_led_white"], stage=stage)
    message = str(caught.value)
    assert "rgb_led_white" in message and "negative drive in G " in message
    printed = [float(v) for v in re.findall(r"[RGB] (-?[\d.]+)", message.split("(drive")[1])]
    np.testing.assert_allclose(printed, expected, rtol=0.02)
