"""Camera raw plates: the simulator's DNG mosaic read back by LibRaw as camera-native RGB.

The lit chart is rendered once by the simulator (the paper stage's [SRL] for red, 1 % noise plus
1e-4 read noise, 5 % vignetting) and written twice: as the half-float EXR plate ``measure``
reads today and as a 14-bit RGGB DNG (pidng). Sampled with the same corners, the DNG gives
the EXR's patch values within 0.5 %: the truth is the EXR plate (the issue's criterion).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.plates.raw import raw_mosaic, read_raw
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
    assert "raw.to_camera" in lines[0]  # what to add
    assert not out.exists()


def _gamut_capture(folder, name, raw=None, camera="ARRI Wide Gamut 4"):
    """Lit charts: green from the DNG, red and blue from the EXR, in ``camera``."""
    stage = {"name": "s", "beta": 0.2}
    if camera:
        stage["camera_colorspace"] = camera
    capture = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": stage,
        "lit_chart": {
            c: {"plate": "lit_red.dng" if c == "green" else "lit_red.exr",
                "corners": CHART_CORNERS.tolist()}
            for c in ("red", "green", "blue")
        },
    }  # fmt: skip
    if raw is not None:
        capture["raw"] = raw
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(capture))
    return path


def _measured(path, out):
    """[SRL] (24, 3, 3) of the lit charts a capture file measured, and its samples.json."""
    assert main(["measure", str(path), "--out", str(out), "--no-write-back"]) == 0
    samples = json.loads((out.parent / f"{out.stem}.overlays" / "samples.json").read_text())
    lit = yaml.safe_load(out.read_text())["lit_chart"]
    return np.stack([np.array(lit[c]) for c in ("red", "green", "blue")], axis=2), samples


def test_a_given_matrix_brings_the_raw_plate_into_the_camera_gamut(lit_chart, tmp_path):
    """raw.to_camera as a matrix: the DNG's patches, as sensor RGB, times that matrix (the
    EXR plates are untouched), and samples.json says which conversion and demosaic were used."""
    folder, _ = lit_chart
    # Cross-talk only: a red-lit chart's near-black channels stay positive (the measurements
    # file refuses negative chart values, which a matrix with negative terms can give).
    M = [[0.9, 0.08, 0.02], [0.05, 0.9, 0.05], [0.01, 0.09, 0.9]]
    SRL, samples = _measured(
        _gamut_capture(folder, "matrix", {"to_camera": M}), tmp_path / "matrix.yaml"
    )
    sensor = sample_chart(str(folder / "lit_red.dng"), CHART_CORNERS, clip_level=1.0).means
    np.testing.assert_allclose(SRL[:, :, 1], sensor @ np.array(M).T, rtol=1e-6, atol=1e-9)
    exr = sample_chart(str(folder / "lit_red.exr"), CHART_CORNERS).means
    np.testing.assert_allclose(SRL[:, :, 0], exr, rtol=1e-6)
    green = next(p for p in samples["plates"] if p["key"] == "lit_chart.green")
    assert green["demosaic"] == "superpixel"
    assert green["to_camera"]["from"] == "the capture file's raw.to_camera"
    assert green["to_camera"]["matrix"] == M
    red = next(p for p in samples["plates"] if p["key"] == "lit_chart.red")
    assert "to_camera" not in red and "demosaic" not in red


def test_the_dng_colour_matrix_brings_the_raw_plate_into_the_camera_gamut(lit_chart, tmp_path):
    """raw.to_camera: dng. The simulated DNG's ColorMatrix1 is the identity under D65, so its
    sensor RGB is read as XYZ and the conversion is colour-science's XYZ -> ARRI Wide Gamut 4
    (white D65: no adaptation)."""
    import colour

    folder, _ = lit_chart
    # Pale colours (all channels within 30 % of each other): inside the gamut once converted.
    values = 0.3 * np.random.default_rng(3).uniform(0.7, 1.0, (24, 3))
    write_plate(tmp_path / "lit_red.exr", render_chart(values, noise=0.01, seed=2))
    write_dng(tmp_path / "lit_red.dng", render_chart(values, noise=0.01, seed=2))
    path = _gamut_capture(tmp_path, "dng", {"to_camera": "dng", "demosaic": "linear"})
    SRL, samples = _measured(path, tmp_path / "dng_out.yaml")
    box = (0, 0, 600, 400)
    sensor = sample_chart(read_raw(tmp_path / "lit_red.dng", box, "linear"), CHART_CORNERS).means
    awg4 = colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"].matrix_XYZ_to_RGB
    np.testing.assert_allclose(SRL[:, :, 1], sensor @ awg4.T, rtol=1e-5, atol=1e-9)
    green = next(p for p in samples["plates"] if p["key"] == "lit_chart.green")
    assert green["demosaic"] == "linear" and "ColorMatrix (D65)" in green["to_camera"]["from"]


@pytest.mark.parametrize(
    ("raw", "camera", "plate", "key", "expected"),
    [
        ({"to_camera": "dng"}, None, "lit_red.dng", "raw.to_camera",
         "needs stage.camera_colorspace"),
        ({"to_camera": [[1, 0, 0], [0, 1, 0], [1, 0, 0]]}, "ARRI Wide Gamut 4", "a.dng",
         "raw.to_camera", "singular"),
        ({"to_camera": "dng"}, "ARRI Wide Gamut 4", "a.nef", "lit_chart.red: raw.to_camera",
         "not a DNG"),
        ({"demosaic": "magic"}, None, "a.dng", "raw.demosaic", "expected one of superpixel"),
    ],
)  # fmt: skip
def test_bad_raw_options_are_refused_by_key(raw, camera, plate, key, expected):
    from ocio_vp.plates.capture import capture_from_dict

    stage = {"name": "s", "beta": 0.2} | ({"camera_colorspace": camera} if camera else {})
    document = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": stage,
        "raw": raw,
        "lit_chart": {c: {"plate": plate} for c in ("red", "green", "blue")},
    }
    with pytest.raises(InputError, match=expected) as caught:
        capture_from_dict(document, source="c.yaml")
    assert str(caught.value).startswith(f"c.yaml: {key}: "), str(caught.value)


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


class _Reported:
    """A LibRaw file whose header or sensor is reported otherwise than the file holds."""

    def __init__(self, raw, **reported) -> None:
        self._raw, self._reported = raw, reported

    def __getattr__(self, name):
        return self._reported.get(name, getattr(self._raw, name))

    def __enter__(self):
        self._raw.__enter__()
        return self

    def __exit__(self, *exc):
        return self._raw.__exit__(*exc)


def _reporting(monkeypatch, **reported) -> None:
    import ocio_vp.plates.raw as raw_module

    opened = raw_module._open
    monkeypatch.setattr(raw_module, "_open", lambda path: _Reported(opened(path), **reported))


@pytest.mark.parametrize("method", ["superpixel", "linear"])
def test_a_decoded_size_unlike_the_header_is_refused_naming_the_file(tmp_path, monkeypatch, method):
    import rawpy

    path = tmp_path / f"short_{method}.dng"  # a new file each: the decoding caches miss
    write_dng(path, np.full((40, 60, 3), 0.2, dtype=np.float32))
    assert open_plate(path).height == 40
    with rawpy.imread(str(path)) as raw:
        sizes = raw.sizes._replace(height=38)
    _reporting(monkeypatch, sizes=sizes)
    expected = rf"short_{method}\.dng.*decoded 60x40 pixels where the file's header states 60x38"
    with pytest.raises(InputError, match=expected):
        read_raw(path, (0, 0, 60, 38), method)


@pytest.mark.parametrize("method", ["superpixel", "linear"])
def test_a_raw_file_without_a_colour_filter_is_refused_by_either_demosaic(
    tmp_path, monkeypatch, method
):
    path = tmp_path / f"stacked_{method}.dng"
    write_dng(path, np.full((40, 60, 3), 0.2, dtype=np.float32))
    _reporting(monkeypatch, raw_type=1, num_colors=4)
    with pytest.raises(InputError, match="not a colour-filter-array raw file"):
        read_raw(path, (0, 0, 60, 40), method)
