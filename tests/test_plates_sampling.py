"""Chart sampling on synthetic plates rendered from the spectral simulator's patch values."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.plates.sampling import (
    ROBUST_MEAN_METHODS,
    grid_homography,
    patch_labels,
    sample_chart,
    sample_region,
)
from ocio_vp.simulator.plates import (
    CHART_CORNERS,
    PATCH_GAP,
    homography,
    render_chart,
    render_regions,
    write_plate,
)

# Noise of the synthetic sensor: 1 % of the signal plus 1e-4 absolute; vignetting 0.6 % at the
# image corners (the chart's patches sit at most ~0.35 % down from the centre).
NOISE, READ_NOISE, VIGNETTING = 0.01, 1e-4, 0.006
TOLERANCE = 0.005  # the 0.5 %


@pytest.fixture(scope="module")
def truth() -> np.ndarray:
    """A lit chart from the spectral simulator (camera RGB of 24 patches lit by the red LED)."""
    from ocio_vp.simulator.stage import paper_stage

    stage = paper_stage()
    lit = stage.SRL_unscaled[:, :, 0] + stage.SRL_unscaled[:, :, 1] + stage.SRL_unscaled[:, :, 2]
    return lit / lit.max() * 0.6  # exposed so the brightest patch sits at 0.6


def _plate(truth: np.ndarray, **options) -> np.ndarray:
    defaults = dict(noise=NOISE, read_noise=READ_NOISE, vignetting=VIGNETTING, highlight=7)
    return render_chart(truth, **{**defaults, **options})


def _check_values(means: np.ndarray, truth: np.ndarray) -> None:
    white = truth.max(axis=0)
    # Every value within 0.5 % of the chart's white in that channel ...
    assert np.max(np.abs(means - truth) / white) < TOLERANCE
    # ... and every value above 5 % of white within 0.5 % of itself.
    bright = truth > 0.05 * white
    assert np.max(np.abs(means - truth)[bright] / truth[bright]) < TOLERANCE


class TestSampleChart:
    @pytest.mark.parametrize("dtype", ["half", "float", "uint16"])
    def test_within_half_percent_and_highlight_flagged(self, tmp_path, truth, dtype):
        suffix = "tif" if dtype == "uint16" else "exr"
        path = write_plate(tmp_path / f"chart.{suffix}", _plate(truth), dtype=dtype)
        samples = sample_chart(path, CHART_CORNERS, 4, 6)
        _check_values(samples.means, truth)
        # Only the patch with the specular glint is flagged (clipped and too many outliers).
        assert np.flatnonzero(samples.flagged).tolist() == [7]
        assert samples.high_spread[7]
        if dtype == "uint16":  # the glint is above 1.0: clipped at the TIFF's maximum code
            assert samples.clipped[7]
        # spreads are the pixel standard deviation: ~1 % of the value away from the glint
        ok = np.arange(24) != 7
        bright = truth[ok] > 0.1
        ratio = samples.spreads[ok][bright] / truth[ok][bright]
        assert np.all((ratio > 0.008) & (ratio < 0.014))

    def test_independent_homography(self):
        # grid_homography (8x8 DLT) against the tests' SVD null-space fit.
        np.testing.assert_allclose(
            grid_homography(CHART_CORNERS, 4, 6), homography(CHART_CORNERS, 4, 6), atol=1e-9
        )

    def test_labels_cover_the_inset_quad(self):
        # Pixel count of each patch ~ area of its inset quadrilateral (shoelace formula).
        inset = 0.25
        box = (100, 60, 500, 340)
        labels = patch_labels(CHART_CORNERS, 4, 6, inset=inset, box=box)
        H = homography(CHART_CORNERS, 4, 6)
        for j in range(24):
            r, c = divmod(j, 6)
            uv = np.array(
                [
                    [c + inset, r + inset],
                    [c + 1 - inset, r + inset],
                    [c + 1 - inset, r + 1 - inset],
                    [c + inset, r + 1 - inset],
                ]
            )
            p = np.c_[uv, np.ones(4)] @ H.T
            q = p[:, :2] / p[:, 2:]
            area = 0.5 * abs(
                np.dot(q[:, 0], np.roll(q[:, 1], -1)) - np.dot(q[:, 1], np.roll(q[:, 0], -1))
            )
            perimeter = np.sum(np.linalg.norm(q - np.roll(q, -1, axis=0), axis=1))
            assert abs(np.count_nonzero(labels == j) - area) < 0.5 * perimeter

    def test_sampled_pixels_stay_inside_patches(self, truth):
        # With a large inset no sampled pixel touches the black gaps (PATCH_GAP < inset).
        image = render_chart(truth)
        labels = patch_labels(CHART_CORNERS, 4, 6, inset=PATCH_GAP + 0.02, box=(0, 0, 600, 400))
        for j in range(24):
            assert np.all(image[labels == j] == image[labels == j][0])

    @pytest.mark.parametrize("method", sorted(ROBUST_MEAN_METHODS))
    def test_methods_without_glint(self, truth, method):
        samples = sample_chart(_plate(truth, highlight=None), CHART_CORNERS, 4, 6, method=method)
        _check_values(samples.means, truth)
        assert not samples.flagged.any()

    def test_plain_mean_is_biased_by_the_glint(self, truth):
        # The reason for a robust mean: the glint drags the plain mean far off.
        mean = sample_chart(_plate(truth), CHART_CORNERS, 4, 6, method="mean").means[7]
        robust = sample_chart(_plate(truth), CHART_CORNERS, 4, 6).means[7]
        assert np.all(mean > truth[7] * 1.2)
        np.testing.assert_allclose(robust, truth[7], rtol=TOLERANCE)

    def test_frames_are_averaged(self, truth):
        frames = [_plate(truth, highlight=None, seed=s) for s in range(4)]
        one = sample_chart(frames[0], CHART_CORNERS, 4, 6)
        four = sample_chart(frames, CHART_CORNERS, 4, 6)
        assert four.frames == 4
        # pixel noise of the average of 4 frames is half of one frame's (sqrt(4)).
        bright = truth > 0.1
        ratio = four.spreads[bright] / one.spreads[bright]
        assert 0.4 < np.median(ratio) < 0.6
        _check_values(four.means, truth)

    def test_flat_field_removes_strong_vignetting(self, tmp_path, truth):
        # 30 % fall-off at the corners: patches are off by up to ~15 % without correction.
        # The flat: a uniform white target, same lens, averaged over 4 frames.
        plate = _plate(truth, vignetting=0.3)
        flats = [
            render_regions(
                {"all": ((0, 0, 600, 400), [0.5, 0.5, 0.5])}, vignetting=0.3, noise=0.003, seed=s
            )
            for s in range(4)
        ]
        paths = [write_plate(tmp_path / f"flat.{i}.exr", f) for i, f in enumerate(flats)]
        raw = sample_chart(plate, CHART_CORNERS, 4, 6)
        assert np.max(np.abs(raw.means / truth - 1)) > 0.05
        corrected = sample_chart(plate, CHART_CORNERS, 4, 6, flat_field=paths)
        _check_values(corrected.means, truth)
        assert np.flatnonzero(corrected.flagged).tolist() == [7]
        with pytest.raises(InputError, match="differs from the plate"):
            sample_chart(plate[:, :590], CHART_CORNERS, 4, 6, flat_field=paths)

    def test_example_exact(self):
        # A noise-free 2 x 2 chart gives its exact patch values with any method.
        values = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6], [0.7, 0.8, 0.9], [0.05, 0.5, 0.25]])
        corners = np.array([[10.0, 10.0], [190.0, 20.0], [180.0, 150.0], [20.0, 140.0]])
        image = render_chart(values, corners=corners, rows=2, columns=2, size=(200, 160))
        for method in ROBUST_MEAN_METHODS:
            samples = sample_chart(image, corners, 2, 2, method=method, clip_level=1.0)
            np.testing.assert_allclose(samples.means, values, rtol=1e-6)
            np.testing.assert_allclose(samples.spreads, 0, atol=1e-7)


class TestErrors:
    def test_corners_outside(self, truth, tmp_path):
        path = write_plate(tmp_path / "c.exr", render_chart(truth))
        corners = CHART_CORNERS + np.array([[0, 0], [200, 0], [200, 0], [0, 0]])
        with pytest.raises(InputError, match="outside the image") as info:
            sample_chart(path, corners, 4, 6)
        assert str(path) in str(info.value)

    def test_not_convex(self, truth):
        with pytest.raises(InputError, match="convex"):
            sample_chart(render_chart(truth), CHART_CORNERS[[0, 2, 1, 3]], 4, 6)

    def test_too_small(self, truth):
        corners = np.array([[10.0, 10], [22, 10], [22, 18], [10, 18]])
        with pytest.raises(InputError, match="too small"):
            sample_chart(render_chart(truth), corners, 4, 6)

    @pytest.mark.parametrize("dtype", ["half", "uint16"])
    def test_fully_clipped(self, truth, tmp_path, dtype):
        # Overexposed 100x: every patch at the sensor's flat top (1.0, the TIFF's max code).
        image = np.minimum(render_chart(truth * 100, noise=NOISE), 1.0)
        path = write_plate(
            tmp_path / f"clip.{'tif' if dtype == 'uint16' else 'exr'}", image, dtype=dtype
        )
        with pytest.raises(InputError, match="clipped") as info:
            sample_chart(path, CHART_CORNERS, 4, 6)
        assert str(path) in str(info.value)


class TestSampleRegion:
    def test_region_mean(self):
        rng = np.random.default_rng(3)
        image = np.full((50, 80, 3), 0.3) * (1 + 0.01 * rng.standard_normal((50, 80, 3)))
        image[10:20, 10:30] = [0.2, 0.4, 0.6]
        s = sample_region(image.astype(np.float32), (10, 10, 30, 20), clip_level=1.0)
        np.testing.assert_allclose(s.means[0], [0.2, 0.4, 0.6], rtol=1e-6)
        assert s.counts[0] == 200
        with pytest.raises(InputError, match="outside"):
            sample_region(image, (70, 10, 90, 20))
