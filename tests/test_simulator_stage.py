"""ocio_vp/simulator/stage.py: the spectral stage."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.simulator.stage import spectral_stage

SAME = ((530, 30), (530, 30), (530, 30))


def test_leds_the_camera_cannot_tell_apart_are_refused_naming_the_leds():
    # Three identical LEDs: colour-science's own data gives an [SL] of rank 1 for the default
    # camera, which used to end in "numerical failure (Singular matrix)" without a field.
    shape = colour.SpectralShape(380, 780, 5)
    camera = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"].copy().align(shape).values
    led = colour.sd_gaussian(530, 30, shape, method="FWHM").values
    assert np.linalg.matrix_rank(camera.T @ np.stack([led] * 3, axis=1)) == 1
    with pytest.raises(InputError) as caught:
        spectral_stage(leds=SAME)
    assert caught.value.key == "leds"
    assert "cannot tell these LEDs apart" in caught.value.problem
