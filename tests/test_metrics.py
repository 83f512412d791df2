"""Chart metrics against published reference values and colour-science's own data.

Sources: Sharma, Wu & Dalal (2005), "The CIEDE2000 color-difference formula", test pair 1
(ΔE00 = 2.0425); SMPTE ST 2084 (100 cd/m^2 encodes to 0.5080784, colour's docstring) and
ITU-R BT.2124 (ΔE ITP = 720 sqrt(ΔI^2 + ΔT^2 + ΔP^2), T = Ct / 2); CIE 1931 XYZ from
colour.sd_to_XYZ.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

from ocio_vp.calibration import diagnostics as diagnostics
from ocio_vp.metrics import (
    ITP_WHITE_NITS,
    camera_to_xyz_matrix,
    chart_errors,
    error_relative_to_white,
    training_rgb_xyz,
    white_scale,
)
from ocio_vp.simulator.stage import environment_spectrum, paper_stage

D65_XY = np.array([0.3127, 0.3290])


def _d65_chart(n: int = 24) -> np.ndarray:
    chart = np.tile(colour.xy_to_XYZ(D65_XY) * 0.2, (n, 1))
    chart[18] = colour.xy_to_XYZ(D65_XY)  # white: Y = 1
    return chart


def test_delta_E_2000_sharma_pair_1():
    target, predicted = _d65_chart(), _d65_chart()
    target[0] = colour.Lab_to_XYZ([50.0, 2.6772, -79.7751], D65_XY)
    predicted[0] = colour.Lab_to_XYZ([50.0, 0.0, -82.7485], D65_XY)
    errors = chart_errors(predicted, target, camera_to_xyz=np.eye(3))
    # Sharma, Wu & Dalal (2005), CIEDE2000 test data, pair 1: Delta E00 = 2.0425.
    assert errors.delta_E_2000[0] == pytest.approx(2.0425, abs=1e-4)
    np.testing.assert_allclose(errors.delta_E_2000[1:], 0.0, atol=1e-12)


def test_delta_E_ITP_neutral_luminance_step():
    # A D65 neutral is R = G = B in BT.2020, so Ct = Cp = 0 and I = PQ(Y nits).
    target = _d65_chart()
    predicted = target.copy()
    predicted[18] *= 1.1
    errors = chart_errors(predicted, target, camera_to_xyz=np.eye(3))
    i_100 = colour.models.eotf_inverse_ST2084(ITP_WHITE_NITS)
    # SMPTE ST 2084 inverse EOTF at 100 cd/m2 (closed form): 0.5080784.
    assert i_100 == pytest.approx(0.5080784, abs=1e-7)
    expected = 720.0 * abs(colour.models.eotf_inverse_ST2084(1.1 * ITP_WHITE_NITS) - i_100)
    assert errors.delta_E_ITP[18] == pytest.approx(expected, rel=1e-3)
    np.testing.assert_allclose(errors.delta_E_ITP[:18], 0.0, atol=1e-9)
    np.testing.assert_allclose(errors.relative_to_white, [0.1 / 24] * 3, rtol=1e-12)


def test_normalisation_is_scale_free():
    rng = np.random.default_rng(1)
    target = rng.uniform(0.05, 0.9, (24, 3))
    predicted = target * rng.uniform(0.97, 1.03, (24, 3))
    a = chart_errors(predicted, target, camera_to_xyz=np.eye(3))
    b = chart_errors(7 * predicted, 7 * target, camera_to_xyz=np.eye(3))
    np.testing.assert_allclose(a.delta_E_2000, b.delta_E_2000, rtol=1e-9)
    np.testing.assert_allclose(a.delta_E_ITP, b.delta_E_ITP, rtol=1e-9)


def test_camera_matrix_recovers_chart_xyz():
    # The fitted matrix maps the camera's view of the ColorChecker under D65 close to
    # colour.sd_to_XYZ of the same patches: mean ΔE2000 below 3 (a 3x3 camera fit).
    stage = paper_stage()
    matrix = camera_to_xyz_matrix(stage.camera)
    light = environment_spectrum(stage, "d65")
    rgb = (stage.reflectances * light) @ stage.camera
    shape = colour.SpectralShape(380, 780, 5)
    illuminant = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    xyz = np.array(
        [
            colour.sd_to_XYZ(sd.copy().align(shape), illuminant=illuminant) / 100
            for sd in colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"].values()
        ]
    )
    fitted = rgb @ matrix.T
    fitted *= xyz[18, 1] / fitted[18, 1]
    white = colour.XYZ_to_xy(xyz[18])
    delta = colour.delta_E(colour.XYZ_to_Lab(xyz, white), colour.XYZ_to_Lab(fitted, white))
    assert np.mean(delta) < 3.0


class TestErrorRelativeToWhite:
    def test_paper_metric_by_hand(self) -> None:
        target = np.array([[0.2, 0.4, 0.1], [0.8, 0.8, 0.4]])
        predicted = target + np.array([[0.08, 0.0, 0.04], [0.0, -0.08, 0.0]])
        # mean_j |d_j| / white: red (0.08 + 0) / 2 / 0.8, green 0.08 / 2 / 0.8, blue 0.04/2/0.4
        np.testing.assert_allclose(
            error_relative_to_white(predicted, target, white_patch=1), [0.05, 0.05, 0.05]
        )

    def test_weights_exclude_patches(self) -> None:
        rng = np.random.default_rng(1)
        target, predicted = rng.uniform(0.1, 1, (2, 24, 3))
        weights = np.ones(24)
        weights[[3, 7]] = 0
        keep = weights > 0
        full = error_relative_to_white(predicted, target, 18, weights)
        white = target[18]
        expected = np.mean(np.abs(predicted[keep] - target[keep]) / white, axis=0)
        np.testing.assert_allclose(full, expected)

    def test_dark_white_channel_is_floored_not_divided_by_zero(self) -> None:
        target = np.full((24, 3), 0.5)
        target[18] = [0.8, 0.4, 0.0]  # sodium-like: no blue in the white
        np.testing.assert_allclose(white_scale(target, 18), [0.8, 0.4, 0.008])
        assert np.all(np.isfinite(error_relative_to_white(target + 0.1, target, 18)))

    def test_black_white_falls_back_to_the_chart_mean(self) -> None:
        target = np.full((24, 3), 0.5)
        target[18] = 0.0
        np.testing.assert_allclose(white_scale(target, 18), [0.5 * 23 / 24] * 3)

    def test_residuals_are_signed_and_white_relative(self) -> None:
        target = np.full((24, 3), 0.5)
        predicted = target.copy()
        predicted[2] = [0.55, 0.45, 0.5]
        r = diagnostics.residuals_per_patch(predicted, target, 18)
        np.testing.assert_allclose(r[2], [0.1, -0.1, 0.0])
        assert not np.any(r[np.arange(24) != 2])


@pytest.mark.parametrize("illuminant", ["D65", "A"])
def test_training_rgb_xyz_matches_colour_align_path(illuminant):
    # The oracle: colour's own reader and interpolating align of every spectrum onto the grid
    # (what training_rgb_xyz did before it took the grid's values directly and cached them).
    shape = colour.SpectralShape(380, 780, 5)
    reflectances = np.asarray(
        colour.characterisation.read_training_data_rawtoaces_v1().copy().align(shape).values
    ).T
    light = colour.SDS_ILLUMINANTS[illuminant].copy().align(shape).values
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape).values
    camera = paper_stage().camera
    rgb, xyz = training_rgb_xyz(camera, illuminant=illuminant)
    np.testing.assert_allclose(rgb, (reflectances * light) @ camera, rtol=1e-12, atol=0)
    np.testing.assert_allclose(xyz, (reflectances * light) @ cmfs, rtol=1e-12, atol=0)
    again, _ = training_rgb_xyz(2 * camera, illuminant=illuminant)  # cached spectra, new camera
    np.testing.assert_allclose(again, 2 * rgb, rtol=1e-15)


def test_delta_E_2000_between_renderings_is_chart_errors():
    """Two renderings compared with the white as reference give chart_errors' ΔE2000 when the
    target chart's white patch is that white."""
    from ocio_vp.metrics import chart_errors, delta_E_2000

    rng = np.random.default_rng(4)
    target = rng.uniform(0.02, 0.9, (24, 3))
    predicted = target * rng.uniform(0.95, 1.05, (24, 3))
    matrix = np.array([[0.49, 0.31, 0.2], [0.18, 0.81, 0.01], [0.0, 0.01, 0.99]])
    expected = chart_errors(predicted, target, camera_to_xyz=matrix, white_patch=18)
    got = delta_E_2000(predicted, target, camera_to_xyz=matrix, white=target[18])
    np.testing.assert_allclose(got, expected.delta_E_2000, rtol=1e-12)


def test_delta_E_2000_is_colour_sciences():
    """The numpy ΔE2000 (and its Lab) against colour-science's, on random pairs including
    negative, near-black, above-white and very saturated values, and identical pairs."""
    import colour

    from ocio_vp.metrics import delta_E_2000

    rng = np.random.default_rng(5)
    a = np.vstack([rng.uniform(-0.05, 4.0, (3000, 3)), rng.uniform(0, 1e-3, (200, 3))])
    b = a * rng.uniform(0.5, 1.5, a.shape) + rng.normal(0, 0.01, a.shape)
    b[:50] = a[:50]
    matrix = np.array([[0.49, 0.31, 0.2], [0.18, 0.81, 0.01], [0.0, 0.01, 0.99]])
    white = np.array([0.9, 1.0, 0.8])
    scale = 1.0 / (white @ matrix[1])
    white_xy = colour.XYZ_to_xy(white @ matrix.T * scale)
    lab_a = colour.XYZ_to_Lab(a @ matrix.T * scale, white_xy)
    lab_b = colour.XYZ_to_Lab(b @ matrix.T * scale, white_xy)
    expected = colour.delta_E(lab_a, lab_b, method="CIE 2000")
    got = delta_E_2000(a, b, camera_to_xyz=matrix, white=white)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


def test_sample_camera_matrix_is_the_fit():
    # ocio_vp/data/sample_camera_to_xyz.json, written by python -m benchmarks.make_sample_matrix
    from ocio_vp.metrics import sample_camera_to_xyz
    from ocio_vp.spectra import camera_sensitivities

    fitted = camera_to_xyz_matrix(camera_sensitivities())
    np.testing.assert_allclose(sample_camera_to_xyz(), fitted, rtol=1e-9, atol=1e-12)
    assert not sample_camera_to_xyz().flags.writeable


#: Sharma, Wu & Dalal (2005), CIEDE2000 test data: (Lab 1, Lab 2, ΔE00), pairs 1, 2, 3, 7,
#: 17 and 25.
SHARMA_PAIRS = [
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, 3.1571, -77.2803), (50.0, 0.0, -82.7485), 2.8615),
    ((50.0, 2.8361, -74.0200), (50.0, 0.0, -82.7485), 3.4412),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
    ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
]


def test_camera_delta_E_2000_is_the_published_ciede2000_through_a_camera():
    """The one camera RGB -> ΔE2000 (colour-science's) gives Sharma's published values for
    colours a camera with a non-trivial matrix recorded, and the numpy copy agrees with it."""
    from ocio_vp.metrics import camera_delta_E_2000, delta_E_2000

    matrix = np.array([[0.49, 0.31, 0.2], [0.18, 0.81, 0.01], [0.0, 0.01, 0.99]])
    to_camera = np.linalg.inv(matrix)
    white = to_camera @ colour.xy_to_XYZ(D65_XY)  # camera RGB of the white, Y = 1
    first, second, expected = (
        np.array(v, dtype=np.float64) for v in zip(*SHARMA_PAIRS, strict=True)
    )
    a = colour.Lab_to_XYZ(first, D65_XY) @ to_camera.T
    b = colour.Lab_to_XYZ(second, D65_XY) @ to_camera.T
    got = camera_delta_E_2000(a, b, camera_to_xyz=matrix, white=white)
    np.testing.assert_allclose(got, expected, atol=1e-4)
    np.testing.assert_allclose(
        delta_E_2000(a, b, camera_to_xyz=matrix, white=white), got, rtol=1e-9, atol=1e-12
    )
    # the scale of the exposure does not matter: white and colours 4x brighter
    np.testing.assert_allclose(
        camera_delta_E_2000(4 * a, 4 * b, camera_to_xyz=matrix, white=4 * white), got, rtol=1e-12
    )


def test_camera_lab_with_the_white_as_a_row_is_colour_science_lab_of_that_rows_xyz():
    # Independent source: colour-science's XYZ_to_Lab on the rows' XYZ, the white's row scaled to
    # Y = 1 and its chromaticity the reference white (bit for bit: the skin selection's
    # thresholds depend on it).
    from ocio_vp.metrics import camera_lab, sample_camera_to_xyz

    matrix = sample_camera_to_xyz()
    rgb = np.random.default_rng(5).uniform(0.001, 2.0, (24, 3))
    xyz = rgb @ matrix.T
    xyz = xyz * (1.0 / xyz[7, 1])
    expected = colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(xyz[7]))
    lab = camera_lab(rgb, camera_to_xyz=matrix, white=7)
    np.testing.assert_array_equal(lab, expected)
    assert np.allclose(lab[7], [100.0, 0.0, 0.0], atol=1e-9)
