"""The simulated camera take: blended frames, flicker, drops and the wall's decoding, against
closed forms and colour-science."""

from __future__ import annotations

import numpy as np

from ocio_vp.patterns.design import PatternOptions, calibration_sequence
from ocio_vp.patterns.frames import write_sequence_folder
from ocio_vp.patterns.sequence import load_sequence
from ocio_vp.simulator.take import (
    PanelResponse,
    TakeOptions,
    frame_drives,
    take_frame_count,
    take_signal,
    true_frame_times,
)

SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])
QUIET = dict(flicker=0.0, noise=0.0, read_noise=0.0, flare=0.0, readout=0.0)


def test_a_frame_straddling_a_change_mixes_the_two_lights():
    """Player at 24 fps, camera at 25 fps, shutter 1 frame: each camera frame integrates
    1/25 s of the wall; across red -> green it holds both, weighted by time."""
    sequence = calibration_sequence(PatternOptions(steps=5))
    options = TakeOptions(fps=25.0, shutter=1.0, preroll=0.0, **QUIET)
    numbers, signal = take_signal(sequence, SL, options)
    change = sequence.patch("green").first  # red ends, green starts (player frame number)
    t_change = (change - 1) / 24.0
    for i in range(len(numbers)):
        a, b = i / 25.0, (i + 1) / 25.0
        if a < t_change < b:
            w = (b - t_change) * 25.0  # fraction of the exposure showing green
            expected = (1 - w) * SL[:, 0] + w * SL[:, 1]
            np.testing.assert_allclose(signal[i], expected, rtol=1e-12)
            break
    else:
        raise AssertionError("no frame straddles the change")


def test_frame_times_and_drops():
    sequence = calibration_sequence(PatternOptions(steps=5))
    options = TakeOptions(fps=25.0, preroll=1.0, shutter=0.5, readout=0.25, dropped=(10,))
    times = true_frame_times(sequence, options)
    assert take_frame_count(sequence, options) == len(times)
    # frame 0's exposure is centred 0.375 camera frames after it opened, 1 s before the player
    assert np.isclose(times[0], 1 + (-1.0 + 0.375 / 25) * 24)
    steps = np.diff(times)
    assert np.allclose(steps[:9], 24 / 25) and np.isclose(steps[9], 2 * 24 / 25)


def test_flicker_is_multiplicative_and_periodic():
    sequence = calibration_sequence(PatternOptions(steps=5))
    quiet = dict(QUIET, flicker=0.05, flicker_hz=2.0)
    numbers, signal = take_signal(sequence, SL, TakeOptions(**quiet))
    white = sequence.patch("white")
    inside = numbers > 0  # all frames: ratio to the unflickered value
    _, still = take_signal(sequence, SL, TakeOptions(**QUIET))
    ratio = signal[inside, 1] / np.where(still[inside, 1] > 0, still[inside, 1], np.nan)
    ratio = ratio[np.isfinite(ratio)]
    assert np.nanmax(ratio) <= 1.05 + 1e-9 and np.nanmin(ratio) >= 0.95 - 1e-9
    assert white.kind == "white"


def test_the_simulated_wall_decodes_pq_frames_like_colour_science(tmp_path):
    options = PatternOptions(
        size=(8, 8), steps=9, file_format="tiff", encoding="pq", peak_nits=1000.0
    )
    sequence = load_sequence(write_sequence_folder(calibration_sequence(options), tmp_path / "p"))
    drives = frame_drives(sequence)
    for patch in sequence.of_kind("ramp", "primary", "white"):
        np.testing.assert_allclose(
            drives(np.array([patch.first]))[0], patch.drive, rtol=1e-9, atol=1e-15
        )


def test_panel_response_is_darker_near_black_and_exact_at_full_drive():
    r = PanelResponse()
    d = np.array([[0.01, 0.01, 0.01], [1.0, 1.0, 1.0]])
    out = r(d)
    np.testing.assert_allclose(out[0], 0.01 * (1 - np.array(r.darkening) * np.exp(-0.5)))
    np.testing.assert_allclose(out[1], 1.0, atol=1e-20)
