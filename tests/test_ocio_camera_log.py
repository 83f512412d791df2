"""Every camera log curve as OCIO runs it, against colour-science's published curves."""

from __future__ import annotations

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest

from ocio_vp.ocio.camera_log import CAMERA_LOG_CURVES, LOG_FOR_GAMUT, camera_log_for, log_transform

LINEAR = np.concatenate([np.linspace(-0.02, 1.0, 1000), np.geomspace(1.0, 100.0, 200)])


def _run(transform, values: np.ndarray) -> np.ndarray:
    rgb = np.ascontiguousarray(np.repeat(values[:, None], 3, axis=1), dtype=np.float32)
    OCIO.Config.CreateRaw().getProcessor(transform).getDefaultCPUProcessor().applyRGB(rgb)
    return rgb[:, 0].astype(np.float64)


@pytest.mark.parametrize("name", sorted(CAMERA_LOG_CURVES))
def test_curve_matches_colour_science(name):
    curve = CAMERA_LOG_CURVES[name]
    with np.errstate(invalid="ignore"):  # colour evaluates both branches of np.where
        encoded = colour.log_encoding(LINEAR, function=name)
    assert np.all(np.isfinite(encoded))
    np.testing.assert_allclose(_run(log_transform(curve), LINEAR), encoded, atol=5e-6)
    decoded = _run(log_transform(curve, OCIO.TRANSFORM_DIR_INVERSE), encoded)
    np.testing.assert_allclose(decoded, LINEAR, rtol=2e-5, atol=5e-6)


def test_every_gamut_names_a_colour_science_space_and_curve():
    for gamut, name in LOG_FOR_GAMUT.items():
        assert gamut in colour.RGB_COLOURSPACES
        assert name in colour.LOG_DECODINGS and camera_log_for(gamut).name == name
    assert camera_log_for(None) is None and camera_log_for("ITU-R BT.709") is None
