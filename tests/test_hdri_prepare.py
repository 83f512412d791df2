"""prepare-hdri: over-range sources spread under the peak, checked against closed forms.

Closed forms (spherical geometry, independent of ocio_vp.hdri.diffuse):
- solid angle of a lat-long row between polar angles t0, t1: (2 pi / W) (cos t0 - cos t1);
- a spherical cap of radius r has solid angle 2 pi (1 - cos r), and the mean of w over it is
  its axis times (1 + cos r) / 2: so an energy E spread uniformly over it lowers the diffuse
  integral (1/pi) integral L cos+ dw of a normal facing it by E (1 - cos r) / (2 pi);
- the smallest cap that holds an excess X over a uniform background b under a peak P has
  2 pi (1 - cos r) (P - b) = X.
Files are checked with OpenImageIO's own ``oiiotool --stats`` as a second reader.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from exr_helpers import write_exr

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.hdri.prepare import fit_under_peak, label_sources, minimum_cap_radius_deg

oiio = pytest.importorskip("OpenImageIO")

H, W = 256, 512


def row_solid_angles(height, width):
    edges = np.cos(np.arange(height + 1) * np.pi / height)
    return (edges[:-1] - edges[1:]) * 2 * np.pi / width


def energy(image):
    return np.einsum("h,hwc->c", row_solid_angles(*image.shape[:2]), image.astype(np.float64))


def directions(height, width):
    theta = (np.arange(height) + 0.5) * np.pi / height
    phi = ((np.arange(width) + 0.5) / width - 0.5) * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return np.stack([np.sin(t) * np.sin(p), np.cos(t), np.sin(t) * np.cos(p)], axis=-1)


def diffuse(image, normal):
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    weight = np.maximum(directions(*image.shape[:2]) @ n, 0.0)
    weight *= row_solid_angles(*image.shape[:2])[:, None]
    return np.einsum("hw,hwc->c", weight, image.astype(np.float64)) / np.pi


def sky_with_sun(axis, *, sun=300.0, sun_radius_deg=1.0, colour=(1.0, 0.9, 0.8), bg=0.2):
    img = np.full((H, W, 3), bg)
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    inside = np.degrees(np.arccos(np.clip(directions(H, W) @ axis, -1, 1))) < sun_radius_deg
    img[inside] = sun * np.asarray(colour)
    return img, inside


SUN = (0.3, 0.7, 0.5)


class TestFitUnderPeak:
    def test_peak_energy_and_colour(self):
        img, inside = sky_with_sun(SUN)
        out = fit_under_peak(img, peak=1.0)
        assert out.image.max() <= 1.0
        np.testing.assert_allclose(energy(out.image), energy(img), rtol=1e-9)
        added = out.image - img
        added[inside] = 0.0  # the source itself is scaled down, keep only receivers
        gained = added.max(axis=2) > 0
        assert gained.sum() > 100
        # Receivers gain energy in the source's own colour (1 : 0.9 : 0.8), not per channel.
        ratio = added[gained] / added[gained][:, :1]
        np.testing.assert_allclose(ratio, np.broadcast_to([1.0, 0.9, 0.8], ratio.shape), rtol=1e-9)

    def test_radius_is_the_smallest_cap(self):
        img, inside = sky_with_sun(SUN)
        excess = energy(img)[0] - energy(np.where(inside[..., None], 1.0 * img / 300, img))[0]
        out = fit_under_peak(img, peak=1.0)
        (source,) = out.sources
        expected = minimum_cap_radius_deg(excess, 1.0 - 0.2)
        # Pixels are 0.7 deg wide here: the filled disc matches the closed form within one.
        assert source.centre_radius_deg == pytest.approx(expected, abs=0.8)
        axis = np.asarray(SUN) / np.linalg.norm(SUN)
        changed = np.any(out.image != img, axis=2)
        angles = np.degrees(np.arccos(np.clip(directions(H, W)[changed] @ axis, -1, 1)))
        # Every changed pixel lies in that disc (measured from the true sun axis: the source's
        # pixel-sampled centre may differ by a fraction of a pixel).
        assert angles.max() <= expected + 0.8

    def test_w_avg_shrink_matches_closed_form(self):
        # A normal facing the sun loses E (1 - cos r) / (2 pi) (mean of w over a cap), others
        # that see the whole cap lose that times cos(angle to the sun), unlit ones nothing.
        img, _ = sky_with_sun(SUN)
        out = fit_under_peak(img, peak=1.0)
        (source,) = out.sources
        axis = np.asarray(SUN) / np.linalg.norm(SUN)
        r = np.radians(source.centre_radius_deg)
        e_sun = energy(img)[0] - 0.2 * np.pi * 4  # the sun's energy above the background
        for normal in (axis, (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
            n = np.asarray(normal) / np.linalg.norm(normal)
            drop = e_sun * (1 - np.cos(r)) / (2 * np.pi) * float(n @ axis)
            change = diffuse(img, n)[0] - diffuse(out.image, n)[0]
            assert change == pytest.approx(drop, rel=0.1)
        # A normal facing away from the sun's hemisphere sees no change at all.
        away = -axis
        np.testing.assert_allclose(diffuse(out.image, away), diffuse(img, away), rtol=1e-12)

    def test_small_sun_keeps_w_avg_to_0_1_percent(self):
        # One pixel at 300: E ~ 0.045, so the shrink above is E (1 - cos r) / (2 pi) ~ 7e-5
        # of a w_avg ~ 0.31 (the 8K sun of peak 3000 is in benchmarks/bench_prepare_hdri.py).
        img = np.full((H, W, 3), 0.3)
        img[70, 300] = 300.0
        out = fit_under_peak(img, peak=1.0)
        assert out.image.max() <= 1.0
        for n in (SUN, (0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 0, -1), (0, -1, 0)):
            np.testing.assert_allclose(diffuse(out.image, n), diffuse(img, n), rtol=1e-3)

    def test_displayable_map_is_unchanged(self):
        img = np.random.default_rng(0).uniform(0, 1, (H, W, 3))
        out = fit_under_peak(img, peak=1.0)
        assert out.sources == ()
        np.testing.assert_array_equal(out.image, img)

    def test_source_across_the_seam_is_one_source(self):
        img = np.full((H, W, 3), 0.1)
        img[120:124, -2:] = 50.0
        img[120:124, :2] = 50.0
        out = fit_under_peak(img, peak=1.0)
        assert len(out.sources) == 1
        np.testing.assert_allclose(energy(out.image), energy(img), rtol=1e-9)
        gained = out.image[..., 0] > 0.1 + 1e-12
        # Symmetric about the seam: as much lands left of it as right of it.
        left = gained[:, : W // 2].sum()
        right = gained[:, W // 2 :].sum()
        assert abs(left - right) <= 0.1 * (left + right)

    def test_source_at_the_pole(self):
        img = np.full((H, W, 3), 0.1)
        img[0:2] = 100.0
        out = fit_under_peak(img, peak=1.0)
        assert out.image.max() <= 1.0
        np.testing.assert_allclose(energy(out.image), energy(img), rtol=1e-9)

    def test_each_source_spreads_around_itself(self):
        img = np.full((H, W, 3), 0.1)
        img[60:63, 100:103] = 200.0
        img[190:192, 400:402] = 50.0
        out = fit_under_peak(img, peak=1.0)
        assert len(out.sources) == 2
        for rows, cols in ((slice(0, 128), slice(0, 256)), (slice(128, H), slice(256, W))):
            np.testing.assert_allclose(
                _box_energy(out.image, rows, cols), _box_energy(img, rows, cols), rtol=1e-9
            )

    def test_labels_join_across_seam_only_when_touching(self):
        over = np.zeros((8, 16), bool)
        over[3, 0] = over[4, 15] = True  # diagonal neighbours across the seam
        over[0, 7] = True
        labels, count = label_sources(over)
        assert count == 2 and labels[3, 0] == labels[4, 15] != labels[0, 7]

    @pytest.mark.parametrize(
        ("image", "peak", "message"),
        [
            (np.full((H, W, 3), 2.0), 1.0, "cannot fit"),
            (np.full((H, W, 3), 0.5), 0.0, "peak"),
            (np.full((H, W, 3), 0.5), float("nan"), "peak"),
            (np.full((H, H, 3), 0.5), 1.0, "2:1"),
            (np.full((H, W, 3), np.nan), 1.0, "NaN"),
        ],
    )
    def test_bad_input(self, image, peak, message):
        with pytest.raises(InputError, match=message):
            fit_under_peak(image, peak=peak)


def _box_energy(image, rows, cols):
    omega = row_solid_angles(*image.shape[:2])[rows]
    return np.einsum("h,hwc->c", omega, image[rows, cols].astype(np.float64))


def oiiotool_max(path):
    if shutil.which("oiiotool") is None:
        pytest.skip("oiiotool is not on PATH")
    text = subprocess.run(
        ["oiiotool", "--stats", str(path)], capture_output=True, text=True, check=True
    ).stdout
    line = next(x for x in text.splitlines() if "Stats Max" in x)
    return [float(v) for v in line.split(":")[1].split()[:-1]]


class TestCommand:
    def test_exr_round_trip(self, tmp_path, capsys):
        img, _ = sky_with_sun(SUN)
        rgba = np.concatenate([img, np.full((H, W, 1), 0.25)], axis=2)
        src, dst = tmp_path / "in.exr", tmp_path / "out.exr"
        write_exr(src, rgba, oiio.HALF, ("R", "G", "B", "A"), compression="piz", Owner="stage")
        assert main(["prepare-hdri", str(src), "--peak", "0.7", "--out", str(dst)]) == 0
        assert "1 over-range source" in capsys.readouterr().out
        # 0.7 is not a half: the file must still hold nothing above it (second reader: oiiotool).
        maxima = oiiotool_max(dst)
        assert max(maxima[:3]) <= 0.7 and maxima[3] == 0.25
        buf = oiio.ImageBuf(str(dst))
        spec = buf.spec()
        assert list(spec.channelnames) == ["R", "G", "B", "A"]
        assert spec.format == oiio.HALF
        assert spec.get_string_attribute("compression") == "piz"
        assert spec.get_string_attribute("Owner") == "stage"
        assert "peak=" in spec.get_string_attribute("ocio_vp:prepare_hdri")
        pixels = buf.get_pixels(oiio.FLOAT)
        np.testing.assert_array_equal(pixels[..., 3], 0.25)
        half_in = np.asarray(img, np.float16).astype(np.float64)  # what the file held
        np.testing.assert_allclose(energy(pixels[..., :3]), energy(half_in), rtol=1e-3)
        assert not list(tmp_path.glob(".*tmp*"))

    @pytest.mark.parametrize(
        ("make", "peak", "message"),
        [
            (None, "1.0", "no such file"),
            ("text", "1.0", "not an image"),
            ("exr", "0", "peak"),
            ("exr", "-1", "peak"),
            ("exr", "0.1", "cannot fit"),
            ("square", "1.0", "2:1"),
        ],
    )
    def test_bad_input_exit_2(self, tmp_path, capsys, make, peak, message):
        src, dst = tmp_path / "in.exr", tmp_path / "out.exr"
        if make == "text":
            src.write_text("not an image\n")
        elif make == "exr":
            write_exr(src, np.full((H, W, 3), 0.5), oiio.FLOAT, ("R", "G", "B"))
        elif make == "square":
            write_exr(src, np.full((H, H, 3), 0.5), oiio.FLOAT, ("R", "G", "B"))
        assert main(["prepare-hdri", str(src), "--peak", peak, "--out", str(dst)]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and message in err and "Traceback" not in err
        assert not dst.exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == ([] if make is None else ["in.exr"])


def test_integer_input_is_written_as_half(tmp_path):
    # An 8-bit TIFF (OIIO reads it as 0..1): the prepared map is written as half float.
    img = np.full((H, W, 3), 0.2)
    img[100:104, 200:204] = 1.0
    src, dst = tmp_path / "in.tif", tmp_path / "out.exr"
    write_exr(src, img, oiio.UINT8, ("R", "G", "B"))
    assert main(["prepare-hdri", str(src), "--peak", "0.5", "--out", str(dst)]) == 0
    spec = oiio.ImageInput.open(str(dst)).spec()
    assert spec.format == oiio.HALF
    assert max(oiiotool_max(dst)) <= 0.5
    pixels = oiio.ImageBuf(str(dst)).get_pixels(oiio.FLOAT)
    np.testing.assert_allclose(energy(pixels), energy(np.round(img * 255) / 255), rtol=1e-3)
