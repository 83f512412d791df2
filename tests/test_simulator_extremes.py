"""Emitters and optimal colours (ocio_vp.simulator.extremes) against closed forms and colour."""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from ocio_vp.metrics import chart_errors
from ocio_vp.simulator.extremes import (
    EMITTER_LEVELS,
    EMITTER_PEAKS,
    OPTIMAL_EDGES,
    emitter_errors,
    emitter_spectra,
    emitters_in_scene,
    luminance,
    optimal_reflectances,
)
from ocio_vp.simulator.stage import camera_rgb, environment_spectrum, paper_stage
from ocio_vp.simulator.truth import camera_matrix
from ocio_vp.spectra import spectral_shape, wavelengths


class TestEmitterSpectra:
    def test_a_gaussian_of_the_stated_width(self) -> None:
        # exp(-4 ln 2 (l - p)^2 / F^2): 1 at the peak, 1/2 at p +- F/2, 1/16 at p +- F.
        (s,) = emitter_spectra([550.0], fwhm=20.0)
        grid = wavelengths()
        assert s[grid == 550.0] == pytest.approx(1.0)
        assert s[grid == 540.0] == pytest.approx(0.5) and s[grid == 560.0] == pytest.approx(0.5)
        assert s[grid == 570.0] == pytest.approx(1 / 16)

    def test_its_area_is_the_closed_form(self) -> None:
        # The integral of a unit-peak Gaussian is F sqrt(pi / (4 ln 2)); sampled every 5 nm
        # with sigma = 8.5 nm the sum equals it to ~exp(-2 pi^2 sigma^2 / 25) (Poisson).
        (s,) = emitter_spectra([550.0], fwhm=20.0)
        assert 5.0 * s.sum() == pytest.approx(20.0 * math.sqrt(math.pi / (4 * math.log(2))))

    def test_the_default_set(self) -> None:
        assert EMITTER_PEAKS[0] == 420 and EMITTER_PEAKS[-1] == 680 and len(EMITTER_PEAKS) == 27
        assert EMITTER_LEVELS == (0.25, 1.0, 4.0)


class TestEmittersInScene:
    @pytest.mark.parametrize("environment", ["direct_sun", "sodium_vapour", "incandescent"])
    def test_luminance_is_the_level_times_the_white_by_colour_science(self, environment) -> None:
        # CIE 1931 Y by colour-science's own integration of each spectrum (not the camera):
        # emitter / scene white = the level, for every emitter.
        stage = paper_stage()
        white = environment_spectrum(stage, environment)
        emitters = emitters_in_scene(stage, environment)
        cmfs = (
            colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(spectral_shape())
        )

        def y(values):
            sd = colour.SpectralDistribution(values, wavelengths())
            return colour.sd_to_XYZ(sd, cmfs, method="Integration")[1]

        levels = np.repeat(EMITTER_LEVELS, len(EMITTER_PEAKS))
        ratios = np.array([y(e) for e in emitters[::7]]) / y(white)
        np.testing.assert_allclose(ratios, levels[::7], rtol=1e-9)
        np.testing.assert_allclose(luminance(emitters) / luminance(white), levels, rtol=1e-12)

    def test_levels_scale_one_spectrum(self) -> None:
        e = emitters_in_scene(paper_stage(), "d65").reshape(3, len(EMITTER_PEAKS), -1)
        np.testing.assert_allclose(e[2], 16.0 * e[0], rtol=1e-12, atol=1e-300)


class TestEmitterErrors:
    def test_the_identity_does_no_damage(self) -> None:
        stage = paper_stage()
        errors, corrected = emitter_errors(
            stage, "direct_sun", lambda x: x, camera_to_xyz=camera_matrix(stage)
        )
        assert errors.shape == (len(EMITTER_PEAKS) * len(EMITTER_LEVELS),)
        assert np.max(errors) < 1e-9
        np.testing.assert_allclose(
            corrected, camera_rgb(stage, emitters_in_scene(stage, "direct_sun"))
        )

    def test_a_matrix_is_judged_as_chart_errors_judges_it(self) -> None:
        # The same ΔE2000 as ocio_vp.metrics.chart_errors with the scene's white appended.
        stage = paper_stage()
        Q = np.array([[1.2, -0.1, -0.1], [-0.05, 1.1, -0.05], [0.0, -0.2, 1.2]])
        matrix = camera_matrix(stage)
        errors, _ = emitter_errors(stage, "d50", lambda x: x @ Q.T, camera_to_xyz=matrix)
        x = camera_rgb(stage, emitters_in_scene(stage, "d50"))[:27]  # 0.25x: ICtCp stays finite
        white = camera_rgb(stage, environment_spectrum(stage, "d50"))
        reference = chart_errors(
            np.vstack([x @ Q.T, white]), np.vstack([x, white]), camera_to_xyz=matrix, white_patch=27
        )
        np.testing.assert_allclose(errors[:27], reference.delta_E_2000[:-1], rtol=1e-9)


class TestOptimalReflectances:
    def test_construction(self) -> None:
        r = optimal_reflectances()
        edges, inner = len(OPTIMAL_EDGES), len(OPTIMAL_EDGES) - 2
        passes = edges * (edges - 1) // 2 - 1  # every pair of edges but the whole range
        assert r.shape == (passes + inner * (inner - 1) // 2, len(wavelengths()))
        assert set(np.unique(r)) == {0.0, 1.0}
        # band-pass: one contiguous run of ones; band-stop: one contiguous run of zeros
        runs = np.abs(np.diff(r, axis=1)).sum(axis=1)
        assert np.all(runs[:passes] <= 2) and np.all(runs[passes:] == 2)
        assert np.all(r[passes:, 0] == 1.0) and np.all(r[passes:, -1] == 1.0)

    def test_a_band_and_its_complement_make_white(self) -> None:
        # Band-stops are complements of the inner band-passes, so by linearity a band-pass and its
        # band-stop photograph as a perfect white diffuser.
        r = optimal_reflectances((380.0, 500.0, 600.0, 780.0))
        grid = wavelengths()
        band = r[next(i for i in range(len(r)) if r[i, 0] == 0 and r[i, -1] == 0)]
        np.testing.assert_array_equal(band, ((grid >= 500) & (grid < 600)).astype(float))
        stage = paper_stage()
        light = environment_spectrum(stage, "d65")
        stop = r[-1]
        np.testing.assert_allclose(
            camera_rgb(stage, band * light) + camera_rgb(stage, stop * light),
            camera_rgb(stage, light),
            rtol=1e-12,
        )
