"""The wall encodings (checked against colour-science) and the LUT spaced in the wall's signal:
its shaper through OCIO, and what ``lut.max_error`` measures."""

from __future__ import annotations

import json

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.formats.linearity import ChannelBlack, ChannelNoise, Linearity, LinearityChannel
from ocio_vp.ocio.config import OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.ocio.wall import encoding_transforms, log_shaper_transform
from ocio_vp.wall.encoding import (
    LINEAR_HEADROOM,
    WallEncoding,
    decode,
    encode,
    lut_accuracy,
    lut_drive,
    lut_table,
    shaper,
)
from ocio_vp.wall.linearity import response_model

DRIVE = np.r_[0.0, np.geomspace(1e-7, 1.0, 5001)]


def cpu(transforms, optimization=OCIO.OPTIMIZATION_LOSSLESS):
    processor = OCIO.Config.CreateRaw().getProcessor(OCIO.GroupTransform(transforms))
    return processor.getOptimizedCPUProcessor(OCIO.BIT_DEPTH_F32, OCIO.BIT_DEPTH_F32, optimization)


def run(transforms, values: np.ndarray) -> np.ndarray:
    pixels = np.ascontiguousarray(np.repeat(values[:, None], 3, axis=1), dtype=np.float32)
    cpu(transforms).applyRGB(pixels)
    return pixels[:, 0].astype(np.float64)


class TestSrgb:
    def test_encode_is_iec_61966_2_1_as_colour_science_has_it(self):
        np.testing.assert_allclose(
            encode(DRIVE, "srgb"), colour.models.eotf_inverse_sRGB(DRIVE), rtol=1e-12, atol=1e-15
        )
        signal = np.linspace(0, 1, 5001)
        np.testing.assert_allclose(
            decode(signal, "srgb"), colour.models.eotf_sRGB(signal), rtol=1e-12, atol=1e-15
        )

    def test_ocio_moncurve_is_the_iec_curve_within_1e_5(self):
        # OCIO's ExponentWithLinearTransform (gamma 2.4, offset 0.055) derives its break point
        # and slope (12.923) from continuity; IEC rounds them (0.0031308, 12.92).
        got = run(encoding_transforms("srgb"), DRIVE)
        expected = colour.models.eotf_inverse_sRGB(DRIVE)
        assert np.max(np.abs(got - expected)) < 1e-5
        assert np.max(np.abs(got - expected)) > 1e-6  # the two really differ, slightly
        # in light, as the wall decodes it: 0.025% of the level at most
        light = colour.models.eotf_sRGB(got)[1:] / DRIVE[1:] - 1
        assert np.max(np.abs(light[DRIVE[1:] > 1e-5])) < 3e-4
        assert run(encoding_transforms("srgb"), np.array([-0.5, -1e-3])).tolist() == [0.0, 0.0]

    def test_solve_with_srgb_encodes_the_wall_colorspaces(self, tmp_path, capsys):
        path = tmp_path / "m.json"
        path.write_text(json.dumps(make_measurements_dict(environments=1)))
        assert (
            main(["solve", str(path), "--out", str(tmp_path / "o"), "--wall-encoding", "srgb"]) == 0
        )
        folder = tmp_path / "o" / "env_0"
        solution = json.loads((folder / "solution.json").read_text())
        assert solution["linearity"]["wall_encoding"] == {"name": "srgb"}
        config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
        assert config.getColorSpace(OUT_OF_FRUSTUM).getEncoding() == "sdr-video"
        rgb = np.random.default_rng(0).uniform(0, 1, size=(200, 3)).astype(np.float32)
        drive = rgb.astype(np.float64) @ np.array(solution["M"]).T
        config.getProcessor(REFERENCE, OUT_OF_FRUSTUM).getDefaultCPUProcessor().applyRGB(rgb)
        # drive below 0 is black, above 1 (the signal's top) is clipped
        expected = colour.models.eotf_inverse_sRGB(np.clip(drive, 0, 1))
        np.testing.assert_allclose(rgb, expected, atol=2e-5)


class TestShaper:
    def test_the_log_shaper_in_ocio_matches_the_numpy_model(self):
        drive = np.r_[0.0, np.geomspace(1e-6, LINEAR_HEADROOM, 2001)]
        np.testing.assert_allclose(
            run([log_shaper_transform()], drive), shaper(drive, "linear"), atol=2e-7
        )
        assert shaper(np.array([0.0, LINEAR_HEADROOM]), "linear").tolist() == [0.0, 1.0]

    @pytest.mark.parametrize("encoding", ["gamma2.4", "srgb", "pq"])
    def test_encodings_shape_with_their_own_signal(self, encoding):
        np.testing.assert_array_equal(shaper(DRIVE, encoding), encode(DRIVE, encoding))
        np.testing.assert_allclose(
            decode(encode(DRIVE, encoding), encoding), DRIVE, rtol=1e-9, atol=1e-15
        )


def _channel(drive: np.ndarray, response: np.ndarray, corrected: bool) -> LinearityChannel:
    return LinearityChannel(
        drive=drive,
        response=response,
        measured_response=response,
        max_deviation=float(np.max(np.abs(response - drive))),
        shadow_deviation=None,
        corrected=corrected,
        black=ChannelBlack(source="zero step", camera=np.zeros(3), level=0.0),
        noise=ChannelNoise(floor=0.0, relative=0.0, source="given", detection_limit=0.0),
        below_floor=[],
        merged=[],
        at_top=[],
        projection_residual=0.0,
        top_step_vs_primary=0.0,
    )


def shadow_block(size: int = 33) -> Linearity:
    """A linearity block whose red is 30% dark near black (``d (1 - 0.3 exp(-d / 0.01))``)."""
    d = np.r_[0.0, np.geomspace(1e-4, 1.0, size - 1)]
    r = d * (1 - 0.3 * np.exp(-d / 0.01))
    r /= r[-1]
    linear = _channel(np.array([0.0, 1.0]), np.array([0.0, 1.0]), False)
    channels = {"red": _channel(d, r, True), "green": linear, "blue": linear}
    return Linearity(measured=True, model="isotonic-pchip-inverse-1d-lut", channels=channels)


class TestLutAccuracy:
    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_max_error_is_the_relative_error_above_0_2_percent_of_peak(self, encoding):
        # Recomputed here, independently, through OCIO's own run of the sidecar's transforms.
        from ocio_vp.ocio.wall import lut_transform

        block = shadow_block()
        lut = lut_table(block, encoding)
        max_error, bands_measured = lut_accuracy(block, lut)
        assert max_error < 0.005  # the documented target
        x = np.geomspace(0.002, 1.0, 20001)
        front = [] if encoding == "linear" else encoding_transforms(encoding)
        signal = run([*front, lut_transform(lut)], x)
        drive = signal if encoding == "linear" else decode(signal, encoding)
        red = block.channels["red"]
        error = np.abs(response_model(red.drive, red.response)(np.clip(drive, 0, 1)) / x - 1)
        # (for sRGB OCIO's moncurve adds its own 0.025% below 0.3% of peak, see TestSrgb)
        tolerance = 3e-4 if encoding == "srgb" else 2e-5
        # two samplings of one error curve (20001 points here, lut_accuracy's own grid there):
        # their maxima agree in magnitude, not to the digit
        assert np.max(error) == pytest.approx(max_error, rel=0.5, abs=tolerance)
        bands = {(b["from"], b["to"]): b["max_error"] for b in bands_measured}
        assert max_error == max(bands[(0.002, 0.02)], bands[(0.02, 1.0)])

    def test_even_drive_spacing_was_far_worse_in_the_shadows(self):
        # The old sidecar sampled the inverse every 1/255 of drive for a linear wall: the same
        # measure over 0.2%-2% of peak, on the same response, for comparison.
        block = shadow_block()
        red = block.channels["red"]
        model = response_model(red.drive, red.response)
        from ocio_vp.wall.linearity import inverse_response

        knots = np.linspace(0, LINEAR_HEADROOM, 4081)
        table = inverse_response(red.drive, red.response, knots)
        x = np.geomspace(0.002, 0.02, 2001)
        even = np.abs(model(np.interp(x, knots, table)) / x - 1).max()
        spaced = np.abs(
            model(lut_drive(lut_table(block, "linear"), np.repeat(x[:, None], 3, 1))[:, 0]) / x - 1
        ).max()
        assert even > 0.01 and spaced < 1e-4


def test_panel_types_keep_their_own_encoding_and_take_the_stages_otherwise(
    panel_stage_and_measurements,
):
    import dataclasses

    from ocio_vp.pipeline import solve_environment
    from ocio_vp.wall.encoding import with_wall_encoding

    _, m = panel_stage_and_measurements
    wall, ceiling = m.panels
    m = dataclasses.replace(m, panels=(wall, dataclasses.replace(ceiling, encoding="gamma2.4")))
    solution = with_wall_encoding(solve_environment(m, m.environments[0]), "pq", peak_nits=1200)
    assert WallEncoding.of(solution.panels["ceiling"].linearity) == WallEncoding("gamma2.4")
    pq = WallEncoding("pq", 1200.0)
    assert WallEncoding.of(solution.panels["wall"].linearity) == pq
    assert WallEncoding.of(solution.linearity) == pq  # the top level is the wall's


@pytest.mark.parametrize("name, peak", [("gamma2.4", None), ("srgb", None), ("pq", 600.0)])
def test_a_wall_encoding_is_one_object_for_numpy_ocio_and_the_file(name, peak):
    """The same curve three ways: numpy (independently, colour-science's), OCIO, and the
    ``wall_encoding`` block it round-trips through."""
    wall = WallEncoding(name, peak)
    assert WallEncoding.from_dict(json.loads(json.dumps(wall.to_dict()))) == wall
    drive = np.geomspace(1e-4, 1.0, 201)
    reference = {
        "gamma2.4": lambda d: d ** (1 / 2.4),
        "srgb": colour.models.eotf_inverse_sRGB,
        "pq": lambda d: colour.models.eotf_inverse_ST2084(d * 600.0),
    }[name](drive)
    np.testing.assert_allclose(wall.encode(drive), reference, rtol=1e-9)
    np.testing.assert_allclose(wall.decode(wall.encode(drive)), drive, rtol=1e-9)
    np.testing.assert_allclose(run(wall.ocio_transforms(), drive), reference, atol=2e-5)
    # where the signal is 1.0: the clamp the config puts before the curve
    np.testing.assert_allclose(wall.encode(np.array([wall.signal_top])), [1.0], rtol=1e-9)


def test_the_linear_wall_is_the_default_and_has_no_curve():
    wall = WallEncoding.of(None)
    assert wall.linear and wall.ocio_transforms() == [] and wall.signal_top is None
    assert wall.ocio_encoding == "scene-linear" and wall.to_dict() == {"name": "linear"}
    with pytest.raises(ValueError, match="unknown wall encoding"):
        WallEncoding("hlg")
