"""Synthesized target charts, checked against colour-science and closed forms.

Independent references: colour-science's CCT/Duv (Ohno 2013) and its CIE daylight and Planckian
spectra, its ``sd_to_XYZ`` and ``RGB_to_RGB``; closed forms for the exact colour match and the
white scaling; the spectral simulator (a different code path) for the rendered chart.
"""

from __future__ import annotations

import colour
import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.simulator import (
    camera_rgb,
    environment_spectrum,
    paper_stage,
    simulate_measurements,
    white_reflectance,
)
from ocio_vp.spectra import align, spectral_shape, wavelengths
from ocio_vp.synthesis import (
    NATURAL_DUV,
    camera_from_colourspace,
    camera_from_csv,
    camera_from_dataset,
    cct_duv,
    chart_spectra,
    estimate_illuminant,
    given_illuminant,
    match_colour,
    rgb_to_camera,
    scaled_to_white,
    synthesize_target,
)
from ocio_vp.synthesis.evaluate import study_environment

NIKON = "Nikon 5100 (NPL)"


@pytest.fixture(scope="module")
def stage():
    return paper_stage()


@pytest.fixture(scope="module")
def nikon():
    return camera_from_dataset(NIKON)


def _shape_error(a, b):
    """Largest relative difference of two spectra after scaling b onto a (least squares)."""
    b = b * (a @ b) / (b @ b)
    return float(np.max(np.abs(a - b)) / np.max(a))


class TestCctDuv:
    def test_planckian_radiators_sit_on_the_locus(self):
        for cct in (2000.0, 2856.0, 4000.0, 6500.0):
            xyz = colour.sd_to_XYZ(colour.sd_blackbody(cct, spectral_shape()))
            found, duv = cct_duv(xyz)
            assert found == pytest.approx(cct, rel=2e-3)
            assert abs(duv) < 2e-4

    def test_daylight_sits_above_the_locus(self):
        # CIE D65 is ~0.0032 Duv above the Planckian locus (Ohno 2014, Table 1).
        cct, duv = cct_duv(
            colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
        )
        assert cct == pytest.approx(6504, abs=5)
        assert duv == pytest.approx(0.0032, abs=1e-4)

    def test_black_is_refused(self):
        with pytest.raises(InputError):
            cct_duv([0.0, 0.0, 0.0])


class TestMatchColour:
    def test_matches_the_colour_exactly(self, nikon):
        spectrum = match_colour(np.ones(len(wavelengths())), nikon.observer, [0.7, 1.0, 0.4])
        np.testing.assert_allclose(nikon.render(spectrum), [0.7, 1.0, 0.4], rtol=1e-10)

    def test_a_base_of_that_colour_comes_back_unchanged(self, nikon):
        base = align(colour.SDS_ILLUMINANTS["D65"])
        spectrum = match_colour(base, nikon.observer, nikon.render(base))
        np.testing.assert_allclose(spectrum, base, rtol=1e-8, atol=1e-10 * base.max())


class TestEstimateIlluminant:
    def test_daylight_is_recovered_as_cie_daylight(self, stage, nikon):
        truth = environment_spectrum(stage, "direct_sun")  # CIE D55
        estimate = estimate_illuminant(camera_rgb(stage, truth), nikon)
        assert estimate.label == "CIE daylight" and estimate.natural and not estimate.warnings
        assert _shape_error(truth, estimate.spectrum) < 0.01

    def test_tungsten_is_recovered_as_planckian(self, stage, nikon):
        truth = environment_spectrum(stage, "incandescent")  # CIE A, 2856 K Planckian
        estimate = estimate_illuminant(camera_rgb(stage, truth), nikon)
        assert estimate.label == "Planckian" and estimate.natural
        assert _shape_error(truth, estimate.spectrum) < 0.01
        assert estimate.cct == pytest.approx(2856, rel=0.02)

    def test_an_off_locus_light_is_warned_about_with_the_reason(self, stage, nikon):
        w = camera_rgb(stage, environment_spectrum(stage, "warm_white_led"))
        estimate = estimate_illuminant(w, nikon)
        assert not estimate.natural and abs(estimate.duv) > NATURAL_DUV
        assert estimate.label == "smooth (Jakob 2019)"
        assert "Duv from the Planckian locus" in estimate.warnings[0]
        np.testing.assert_allclose(nikon.render(estimate.spectrum), w, rtol=1e-9)

    def test_sodium_is_refused_rather_than_guessed(self, stage, nikon):
        w = camera_rgb(stage, environment_spectrum(stage, "sodium_vapour"))
        with pytest.raises(InputError, match="illuminant-spectrum"):
            estimate_illuminant(w, nikon)

    def test_unknown_method(self, nikon):
        with pytest.raises(InputError, match="unknown illuminant method"):
            estimate_illuminant([1.0, 1.0, 1.0], nikon, method="guess")

    def test_a_given_spectrum_keeps_its_shape(self, stage, nikon):
        truth = environment_spectrum(stage, "sodium_vapour")
        w = camera_rgb(stage, truth) * 3.0
        estimate = given_illuminant(truth, w, nikon)
        np.testing.assert_allclose(estimate.spectrum, 3.0 * truth, rtol=1e-12)
        assert not estimate.warnings


class TestCameraModels:
    def test_colour_space_model_is_xyz_through_the_gamut_matrix(self):
        camera = camera_from_colourspace("ARRI Wide Gamut 4")
        sd = colour.SDS_ILLUMINANTS["A"].copy().align(spectral_shape())
        cmfs = (
            colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(spectral_shape())
        )
        xyz = colour.sd_to_XYZ(sd, cmfs=cmfs, method="Integration")  # colour's own integration
        expected = colour.XYZ_to_RGB(xyz, "ARRI Wide Gamut 4", chromatic_adaptation_transform=None)
        got = camera.render(align(sd))
        np.testing.assert_allclose(got / got[1], expected / expected[1], rtol=1e-9)

    def test_unknown_colour_space(self):
        with pytest.raises(InputError, match="unknown colour space"):
            camera_from_colourspace("ARRI Wide Gamut 5")

    def test_csv_sensitivities_equal_the_dataset(self, tmp_path, nikon):
        # The rawtoaces format: the dataset's own rows, written as wavelength,R,G,B.
        data = colour.MSDS_CAMERA_SENSITIVITIES[NIKON]
        path = tmp_path / "nikon.csv"
        rows = ["wavelength,R,G,B"] + [
            f"{w:g},{r!r},{g!r},{b!r}"
            for w, (r, g, b) in zip(data.wavelengths, data.values, strict=True)
        ]
        path.write_text("\n".join(rows) + "\n")
        np.testing.assert_allclose(camera_from_csv(path).observer, nikon.observer, atol=1e-15)

    def test_a_dead_channel_in_a_csv_is_refused(self, tmp_path):
        path = tmp_path / "dead.csv"
        path.write_text("400,1,1,0\n700,1,1,0\n")
        with pytest.raises(InputError, match="a channel is zero"):
            camera_from_csv(path)


class TestChart:
    def test_scaled_to_white_closed_form(self):
        chart = scaled_to_white(np.full((24, 81), 0.8), 18, 0.9, np.ones(81))
        assert chart.scale == pytest.approx(0.9 / 0.8)
        np.testing.assert_allclose(chart.reflectances, 0.9)

    def test_unknown_chart_lists_the_known_ones(self):
        with pytest.raises(InputError, match="ColorChecker N Ohta"):
            chart_spectra("ColorChecker Classic")


class TestSynthesizeTarget:
    def test_with_the_true_spectrum_it_is_the_simulated_chart(self, stage, nikon):
        spectrum = environment_spectrum(stage, "incandescent")
        real = simulate_measurements({"a": spectrum}, stage=stage).environments[0]
        synth = synthesize_target(
            real.w_avg,
            nikon,
            chart_spectra(),
            white_reflectance=white_reflectance(stage),
            spectrum=spectrum,
        )
        # white_reflectance is rounded to 4 digits in the file: the chart scale is 1 +- 1e-4.
        np.testing.assert_allclose(synth.target_chart, real.target_chart, rtol=2e-4)

    def test_daylight_from_w_avg_alone_is_within_a_hundredth_of_a_delta_e(self, stage, nikon):
        from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors

        real = simulate_measurements(["outdoor_shade"], stage=stage).environments[0]
        synth = synthesize_target(
            real.w_avg, nikon, chart_spectra(), white_reflectance=white_reflectance(stage)
        )
        errors = chart_errors(
            synth.target_chart,
            real.target_chart,
            camera_to_xyz=camera_to_xyz_matrix(nikon.observer),
        )
        assert errors.delta_E_2000.max() < 0.01

    def test_black_w_avg_is_refused(self, nikon):
        with pytest.raises(InputError, match="no light"):
            synthesize_target([0.0, 0.0, 0.0], nikon, chart_spectra())


class TestRgbToCamera:
    def test_matches_colour_rgb_to_rgb_with_cat02(self):
        rgb = np.array([0.8, 0.6, 0.3])
        expected = colour.RGB_to_RGB(
            rgb, "ACEScg", "ARRI Wide Gamut 4", chromatic_adaptation_transform="CAT02"
        )
        np.testing.assert_allclose(rgb_to_camera(rgb, "ACEScg", "ARRI Wide Gamut 4"), expected)

    def test_linear_rec709_alias(self):
        expected = colour.RGB_to_RGB(
            [1, 0, 0], "Linear Rec.709 (sRGB)", "ACES2065-1", chromatic_adaptation_transform="CAT02"
        )
        np.testing.assert_allclose(
            rgb_to_camera([1, 0, 0], "Linear Rec.709", "ACES2065-1"), expected
        )

    def test_without_a_camera_gamut_it_is_refused(self):
        with pytest.raises(InputError, match="camera_colorspace"):
            rgb_to_camera([1, 1, 1], "ACEScg", None)


def test_q_from_a_synthesized_daylight_chart_is_within_10_percent(stage, nikon):
    # The criterion on one natural illuminant (benchmarks/bench_target_chart.py does all):
    # held-out ΔE2000 on the 190 training reflectances, 0.5% noise, 3 seeds.
    reflectances, white = chart_spectra(), white_reflectance(stage)
    study = study_environment(
        stage,
        "direct_sun",
        lambda w: synthesize_target(w, nikon, reflectances, white_reflectance=white).target_chart,
        seeds=3,
    )
    assert study.q_synthesized < study.m_only and study.q_real < study.m_only
    assert study.ratio < 1.10
    assert study.per_seed.shape == (3, 3)
