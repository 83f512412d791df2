"""The calibration sequence: layout, ramp spacing and code values (checked against
colour-science's transfer functions and OpenImageIO reading the frames back)."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.patterns.design import (
    PatternOptions,
    calibration_sequence,
    flash_frames,
    quantise,
    ramp_drives,
    ramp_levels,
)
from ocio_vp.wall.linearity import CHANNELS


class TestLayout:
    def test_every_kind_is_there_in_order(self):
        s = calibration_sequence(PatternOptions(steps=5, hold=10))
        kinds = [p.kind for p in s.patches]
        assert kinds[:7] == ["lead", "sync", "black", "primary", "primary", "primary", "white"]
        assert kinds.count("ramp") == 15 and kinds.count("sync") == 5 and kinds[-1] == "lead"
        # contiguous frames from first_frame, each plain patch held `hold` frames
        assert s.patches[0].first == 1
        for a, b in zip(s.patches, s.patches[1:], strict=False):
            assert b.first == a.last + 1
        assert all(p.frames == 10 for p in s.patches if p.kind in ("black", "primary", "ramp"))

    def test_sync_marks_are_told_apart_by_their_flash_count(self):
        s = calibration_sequence(PatternOptions(fps=30))
        f = flash_frames(30)
        assert f == 5
        for g, mark in enumerate(s.of_kind("sync")):
            assert len(mark.flashes) == g + 2
            assert mark.flashes[0][0] - mark.first == 2 * f  # black before the first flash
            assert mark.last - mark.flashes[-1][1] == 2 * f  # and after the last
            for a, b in mark.flashes:
                assert b - a + 1 == f
            for (_, b), (c, _) in zip(mark.flashes, mark.flashes[1:], strict=False):
                assert c - b - 1 == f

    def test_drive_at_frames(self):
        s = calibration_sequence(PatternOptions(steps=5))
        red, mark = s.patch("red"), s.patch("sync_0")
        frames = np.array(
            [red.first, red.last, mark.first, mark.flashes[0][0], 0, s.last_frame + 5]
        )
        drive = s.drive_at(frames)
        np.testing.assert_array_equal(drive[:2], [[1, 0, 0], [1, 0, 0]])
        np.testing.assert_array_equal(drive[2:], [[0, 0, 0], [1, 1, 1], [0, 0, 0], [0, 0, 0]])

    def test_options_are_checked(self):
        with pytest.raises(InputError, match="--peak-nits"):
            PatternOptions(peak_nits=1000.0)
        with pytest.raises(InputError, match="--peak-nits"):
            PatternOptions(encoding="pq")
        with pytest.raises(InputError, match="--hold"):
            PatternOptions(hold=1)
        with pytest.raises(InputError, match="distinct"):
            ramp_drives(PatternOptions(file_format="dpx", steps=1000, encoding="pq", peak_nits=1e3))


class TestRampSpacing:
    """Steps evenly spaced in the wall's signal, the top exactly 1.0: colour-science's EOTFs."""

    @pytest.mark.parametrize("steps", [5, 17, 33])
    def test_pq_steps_follow_st2084(self, steps):
        import colour

        options = PatternOptions(encoding="pq", peak_nits=1000.0, steps=steps, file_format="exr")
        drive = ramp_drives(options)
        top = colour.models.eotf_inverse_ST2084(1000.0)
        expected = colour.models.eotf_ST2084(np.linspace(0, top, steps)) / 1000.0
        # EXR holds half floats: each drive is the half nearest the exact one
        np.testing.assert_allclose(drive, expected.astype(np.float16), rtol=0, atol=0)
        assert drive[-1] == 1.0 and drive[0] == 0.0

    def test_linear_wall_ramps_are_spaced_in_gamma_2_4(self):
        drive = ramp_drives(PatternOptions(steps=5))
        expected = (np.arange(5) / 4) ** 2.4
        np.testing.assert_allclose(drive, expected, rtol=1e-3)
        assert np.all(np.diff(drive) > 0)

    def test_srgb_tiff_code_values(self):
        import colour

        options = PatternOptions(encoding="srgb", file_format="tiff", steps=9)
        drive, signal = ramp_levels(options)
        codes = signal * 65535
        np.testing.assert_array_equal(codes, np.round(codes))
        np.testing.assert_allclose(drive, colour.models.eotf_sRGB(signal), atol=1e-12)
        np.testing.assert_array_equal(codes, np.round(np.linspace(0, 65535, 9)))

    def test_pq_dpx_drive_is_normalised_at_the_top_code(self):
        import colour

        options = PatternOptions(encoding="pq", peak_nits=1000.0, file_format="dpx", steps=17)
        drive, signal = ramp_levels(options)
        codes = signal * 1023
        top = np.round(colour.models.eotf_inverse_ST2084(1000.0) * 1023)
        assert codes[-1] == top and drive[-1] == 1.0
        nits = colour.models.eotf_ST2084(codes / 1023)
        np.testing.assert_allclose(drive, nits / nits[-1], rtol=1e-9)
        # 10-bit PQ: drive 1.0 is peak_nits within half a code value (well under 1%)
        assert abs(nits[-1] / 1000 - 1) < 0.006


def test_quantise_rounds_to_code_values():
    options = PatternOptions(file_format="tiff", encoding="gamma2.4")
    drive, signal = quantise(np.array([0.5, 1.0, 2.0]), options)
    np.testing.assert_array_equal(signal * 65535, [round(0.5 ** (1 / 2.4) * 65535), 65535, 65535])
    np.testing.assert_allclose(drive[0], (signal[0]) ** 2.4, rtol=1e-12)


def test_primaries_and_white_are_full_drive_in_every_format():
    for fmt, enc, peak in [
        ("exr", "linear", None),
        ("tiff", "pq", 4000.0),
        ("dpx", "gamma2.4", None),
    ]:
        s = calibration_sequence(
            PatternOptions(file_format=fmt, encoding=enc, peak_nits=peak, steps=5)
        )
        for k, c in enumerate(CHANNELS):
            assert s.patch(c).drive == tuple(float(i == k) for i in range(3))
        assert s.patch("white").drive == (1.0, 1.0, 1.0)
        ramps = [p for p in s.of_kind("ramp") if p.channel == "blue"]
        assert [p.step for p in ramps] == list(range(5)) and ramps[-1].drive == (0.0, 0.0, 1.0)
