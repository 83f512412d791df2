"""The camera range footage spans (ocio_vp/model/footage_range.py) and host agreement on it.

Independent checks: colour-science's own Lab and ΔE2000 for the metric; the sets' documented
exposures, levels and noise recomputed here."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.model.footage_range import (
    EMITTER_LEVELS,
    HDR,
    READ_NOISE,
    SETS,
    agreement,
    calibration_footage_range,
    footage_range,
    wall_emitters,
)

CAMERA_TO_XYZ = np.array([[0.49, 0.31, 0.2], [0.18, 0.81, 0.01], [0.0, 0.01, 0.99]])
WHITE = np.array([0.9, 1.0, 0.8])


@pytest.fixture
def footage():
    rng = np.random.default_rng(1)
    lit = rng.uniform(0.03, 0.9, (50, 3)) * WHITE
    emitters = np.array([[2.0, 0.3, 0.01], [0.1, 1.5, 0.2], [0.05, 0.2, 6.0]])
    return footage_range(
        lit=lit, lit_white=WHITE, white=WHITE, emitters=emitters, camera_to_xyz=CAMERA_TO_XYZ
    )


def test_the_sets_span_what_footage_spans(footage):
    sets = footage.sets
    assert tuple(sets) == SETS
    assert np.any(sets["near_black"] < 0)  # noise around black
    assert np.all(np.abs(sets["near_black"]) < 0.02 + 6 * READ_NOISE)
    # Noiseless, at most HDR times the lit white; exp2(log2(HDR)) may round an ulp above HDR.
    assert sets["highlights"].max() <= HDR * WHITE.max() * (1 + 4 * np.finfo(float).eps)
    assert sets["highlights"].max() > 0.5 * HDR * WHITE.max()
    emitters = sets["emitters"].reshape(len(EMITTER_LEVELS), -1, 3)
    for level, block in zip(EMITTER_LEVELS, emitters, strict=True):
        np.testing.assert_allclose(block, emitters[1] * level)
    again = footage_range(
        lit=sets["reflectances"][:0], lit_white=WHITE, white=WHITE, emitters=np.zeros((0, 3)),
        camera_to_xyz=CAMERA_TO_XYZ,
    )  # fmt: skip
    assert len(again.sets["reflectances"]) == 0


def test_same_seed_same_sets(footage):
    rng = np.random.default_rng(1)
    lit = rng.uniform(0.03, 0.9, (50, 3)) * WHITE
    emitters = np.array([[2.0, 0.3, 0.01], [0.1, 1.5, 0.2], [0.05, 0.2, 6.0]])
    other = footage_range(
        lit=lit, lit_white=WHITE, white=WHITE, emitters=emitters, camera_to_xyz=CAMERA_TO_XYZ
    )
    for name in SETS:
        np.testing.assert_array_equal(other.sets[name], footage.sets[name])


def test_agreement_is_colour_sciences_delta_e(footage):
    """A host that scales every pixel by 1 % against the exact one: the p99 and worst ΔE2000
    are colour-science's, through the camera matrix with the white at Y = 1."""
    import colour

    exact = lambda x: x  # noqa: E731
    host = lambda x: x * np.array([1.01, 1.0, 0.99])  # noqa: E731
    measured = agreement(footage, exact, host)
    x = footage.sets["reflectances"]
    scale = 1.0 / (WHITE @ CAMERA_TO_XYZ[1])
    white_xy = colour.XYZ_to_xy(WHITE @ CAMERA_TO_XYZ.T * scale)
    lab_a = colour.XYZ_to_Lab(host(x) @ CAMERA_TO_XYZ.T * scale, white_xy)
    lab_b = colour.XYZ_to_Lab(x @ CAMERA_TO_XYZ.T * scale, white_xy)
    de = colour.delta_E(lab_a, lab_b, method="CIE 2000")
    assert measured.p99["reflectances"] == pytest.approx(np.percentile(de, 99), rel=1e-12)
    assert measured.worst["reflectances"] == pytest.approx(de.max(), rel=1e-12)
    assert agreement(footage, exact, exact).overall == (0.0, 0.0)
    assert not measured.within(0.0, 0.0) and measured.within(1e3, 1e3)


def test_wall_emitters_are_at_whites_luminance():
    SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])
    emitters = wall_emitters(SL, WHITE, CAMERA_TO_XYZ)
    assert emitters.shape == (6, 3)
    np.testing.assert_allclose(emitters @ CAMERA_TO_XYZ[1], WHITE @ CAMERA_TO_XYZ[1])
    # each is a primary or a pair of them, scaled
    columns = [SL[:, 0], SL[:, 1], SL[:, 2], SL[:, 0] + SL[:, 1]]
    for emitter, column in zip(emitters, columns, strict=False):
        np.testing.assert_allclose(np.cross(emitter, column), 0.0, atol=1e-12)
    chart = np.random.default_rng(2).uniform(0.05, 0.9, (24, 3))
    calibration = calibration_footage_range(
        lit_chart=chart, white_patch=18, target_white=WHITE, SL=SL, camera_to_xyz=CAMERA_TO_XYZ
    )
    assert len(calibration.sets["emitters"]) == 6 * len(EMITTER_LEVELS)
