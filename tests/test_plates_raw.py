"""Camera raw plates: the simulator's DNG mosaic read back by LibRaw as camera-native RGB.

The lit chart is rendered once by the simulator (the paper stage's [SRL] for red, 1 % noise plus
1e-4 read noise, 5 % vignetting) and written twice: as the half-float EXR plate ``measure``
reads today and as a 14-bit RGGB DNG (pidng). Sampled with the same corners, the DNG gives
the EXR's patch values within 0.5 %: the truth is the EXR plate (the issue's criterion).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.plates.raw import DEMOSAIC_METHODS, raw_mosaic, read_raw
from ocio_vp.plates.reader import open_plate
from ocio_vp.plates.sampling import sample_chart
from ocio_vp.simulator.plates import CHART_CORNERS, render_chart, write_plate
from ocio_vp.simulator.raw import BLACK, WHITE, mosaic, write_dng


@pytest.fixture(scope="module")
def lit_chart(tmp_path_factory):
    from ocio_vp.simulator.stage import paper_stage

    stage = paper_stage()
    values = stage.beta * stage.SRL_unscaled[:, :, 0]
    image = render_chart(values, noise=0.01, read_noise=1e-4, vignetting=0.05, seed=5)
    folder = tmp_path_factory.mktemp("raw")
    write_plate(folder / "lit_red.exr", image)
    write_dng(folder / "lit_red.dng", image)
    return folder, image


def test_the_mosaic_reads_back_with_the_file_s_levels(lit_chart):
    folder, image = lit_chart
    raw = raw_mosaic(folder / "lit_red.dng")
    assert raw.black == (BLACK,) * 4 and raw.white == WHITE and raw.bayer
    np.testing.assert_array_equal(raw.mosaic, mosaic(image))
    pixels = read_raw(folder / "lit_red.dng", (100, 80, 140, 120))
    # superpixel: each 2x2 block's R (top-left) and B (bottom-right) on all four pixels
    step = 1 / (WHITE - BLACK)
    np.testing.assert_allclose(pixels[0::2, 0::2, 0], image[80:120:2, 100:140:2, 0], atol=step)
    np.testing.assert_allclose(pixels[1::2, 1::2, 2], image[81:120:2, 101:140:2, 2], atol=step)
    green = (image[80:120:2, 101:140:2, 1] + image[81:120:2, 100:140:2, 1]) / 2
    np.testing.assert_allclose(pixels[0::2, 0::2, 1], green, atol=step)
    info = open_plate(folder / "lit_red.dng")
    assert (info.width, info.height, info.is_float) == (600, 400, False)
    assert "superpixel" in info.file_format


def _means(path, method="superpixel"):
    if method == "superpixel":
        return sample_chart(str(path), CHART_CORNERS, clip_level=1.0).means
    box = (0, 0, 600, 400)
    return sample_chart(read_raw(path, box, method), CHART_CORNERS, clip_level=1.0).means


def test_dng_lit_chart_matches_the_exr_within_half_a_percent(lit_chart):
    folder, _ = lit_chart
    exr = sample_chart(str(folder / "lit_red.exr"), CHART_CORNERS).means
    dng = _means(folder / "lit_red.dng")
    error = np.abs(dng - exr) / np.maximum(np.abs(exr), 0.05 * np.abs(exr).max())
    assert np.max(error) < 0.005, np.max(error)  # observed: 0.43 % (red), 0.19 % (green, blue)


@pytest.mark.parametrize("method", ["linear", "ahd"])
def test_demosaic_methods_agree_on_chart_patches(lit_chart, method):
    """LibRaw's interpolating methods against superpixel on the same DNG: patches averaged
    inside the inset barely see demosaicing (observed: within 0.05 % of white)."""
    folder, _ = lit_chart
    superpixel = _means(folder / "lit_red.dng")
    other = _means(folder / "lit_red.dng", method)
    assert method in DEMOSAIC_METHODS
    assert np.max(np.abs(other - superpixel)) < 0.002 * np.abs(superpixel).max()


def test_clipping_is_judged_at_the_raw_white_level(tmp_path):
    image = np.full((40, 60, 3), 0.2, dtype=np.float32)
    image[10:30, 20:40] = 1.3  # above the sensor's clip: stored at the white level
    write_dng(tmp_path / "hot.dng", image)
    pixels = read_raw(tmp_path / "hot.dng", (0, 0, 60, 40))
    assert pixels.max() == pytest.approx(1.0, abs=1e-6)
    corners = [[2, 10], [58, 10], [58, 30], [2, 30]]  # three patches, the middle one clipped
    samples = sample_chart(str(tmp_path / "hot.dng"), corners, 1, 3, clip_level=1.0)
    assert samples.clipped.tolist() == [False, True, False]


def test_a_file_libraw_cannot_read_is_refused_on_one_line(tmp_path, capsys):
    (tmp_path / "bad.nef").write_bytes(b"II*\x00 not really a raw file" * 10)
    with pytest.raises(InputError, match="LibRaw cannot read this raw file"):
        open_plate(tmp_path / "bad.nef")
    with pytest.raises(InputError, match="raw plate is linear"):
        open_plate(tmp_path / "bad.nef", encoding="sRGB")
    capture = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": {"name": "s", "beta": 0.2},
        "lit_chart": {
            c: {"plate": "bad.nef", "corners": CHART_CORNERS.tolist()}
            for c in ("red", "green", "blue")
        },
    }
    (tmp_path / "capture.yaml").write_text(yaml.safe_dump(capture))
    out = tmp_path / "out.yaml"
    assert main(["measure", str(tmp_path / "capture.yaml"), "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "bad.nef" in lines[0] and "LibRaw" in lines[0]
    assert not out.exists()


def test_raw_plates_with_a_named_camera_gamut_are_refused(lit_chart, capsys):
    """stage.camera_colorspace puts the measurements in an encoding gamut; a raw plate is
    sensor RGB and the file says nothing to bring it there: one line naming the plate's key."""
    folder, _ = lit_chart
    capture = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": {"name": "s", "beta": 0.2, "camera_colorspace": "ARRI Wide Gamut 4"},
        "lit_chart": {
            c: {"plate": "lit_red.dng" if c == "green" else "lit_red.exr",
                "corners": CHART_CORNERS.tolist()}
            for c in ("red", "green", "blue")
        },
    }  # fmt: skip
    (folder / "gamut.yaml").write_text(yaml.safe_dump(capture))
    out = folder / "gamut_out.yaml"
    assert main(["measure", str(folder / "gamut.yaml"), "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "lit_chart.green" in lines[0] and "sensor RGB" in lines[0]
    assert not out.exists()


def test_detection_reads_a_raw_plate_as_measured(lit_chart):
    """`corners: detect` on the DNG finds what it finds on the EXR (the detector sees the same
    picture: the raw plate as ocio-vp measures it, not as OpenImageIO would develop it)."""
    from ocio_vp.plates.detection import detect_chart_corners

    folder, _ = lit_chart
    exr = detect_chart_corners(open_plate(folder / "lit_red.exr"))
    dng = detect_chart_corners(open_plate(folder / "lit_red.dng"))
    # superpixel moves a patch's edges by up to a pixel: its centre by a fraction of one
    assert np.max(np.abs(exr - CHART_CORNERS)) < 0.5
    assert np.max(np.abs(dng - CHART_CORNERS)) < 1.0
