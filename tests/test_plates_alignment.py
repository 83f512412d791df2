"""Placing a take in the sequence's time, judged against the simulator's exact frame times.

Each case films the default calibration sequence with a camera at another rate than the
player (faster and slower), a random shutter (0.2-1 frame) and rolling-shutter readout
(0-0.5 frame), 3% flicker at a random beat, 2% noise, a random start (up to 0.5 s late or 2 s
early) and one dropped frame. The error is the mapped camera time of every change between
measured patches minus the true one (the exposure centred on it).
"""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.patterns.design import PatternOptions, calibration_sequence
from ocio_vp.plates.alignment import GUARD, align_take, brightness, kept_frames
from ocio_vp.simulator.take import TakeOptions, take_signal, true_frame_times

SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])
#: (player fps, camera fps): a camera faster and slower than the player, NTSC against film.
RATES = [(24.0, 25.0), (25.0, 24.0), (24.0, 23.976), (24.0, 30.0), (30.0, 24.0)]


def _changes(sequence):
    kinds = ("black", "primary", "white", "ramp")
    return np.array(
        sorted({t for p in sequence.patches if p.kind in kinds for t in (p.first, p.last + 1)}),
        dtype=np.float64,
    )


def _errors(sequence, options, alignment, numbers):
    truth = true_frame_times(sequence, options)
    T = _changes(sequence)
    true_camera = np.interp(T, truth, numbers.astype(np.float64))
    return alignment.to_camera(T) - true_camera


def _random_take(fs, fc, seed, **extra):
    rng = np.random.default_rng(1000 + seed)
    sequence = calibration_sequence(PatternOptions(fps=fs))
    count = int((sequence.duration + 2) * fc)
    options = TakeOptions(
        fps=fc,
        seed=seed,
        preroll=float(rng.uniform(-0.5, 2.0)),
        flicker=0.03,
        flicker_hz=float(rng.uniform(0.5, 12.0)),
        shutter=float(rng.uniform(0.2, 1.0)),
        readout=float(rng.uniform(0.0, 0.5)),
        dropped=(int(rng.integers(50, count - 50)),),
        noise=0.02,
        **extra,
    )
    return sequence, options


@pytest.mark.parametrize(("fs", "fc"), RATES)
@pytest.mark.parametrize("seed", range(4))
def test_unsynchronised_takes_are_placed_within_a_frame(fs, fc, seed):
    sequence, options = _random_take(fs, fc, seed)
    numbers, signal = take_signal(sequence, SL, options)
    alignment = align_take(signal, numbers, sequence)
    errors = _errors(sequence, options, alignment, numbers)
    # Blended frames lie within (shutter + readout) / 2 <= 0.75 frame of a change, the frames
    # kept GUARD = 2 frames away: an error below 1.25 frames never keeps a blended frame.
    assert np.max(np.abs(errors)) < 1.2
    assert np.median(np.abs(errors)) < 0.35
    # the global line may straddle the dropped frame: the anchors, not the line, place patches
    assert abs(alignment.rate - fc / fs) < 5e-3 * fc / fs


@pytest.mark.parametrize(("fs", "fc"), RATES)
def test_without_a_drop_every_change_is_within_half_a_frame(fs, fc):
    sequence = calibration_sequence(PatternOptions(fps=fs))
    options = TakeOptions(fps=fc, flicker=0.03, noise=0.02, seed=7)
    numbers, signal = take_signal(sequence, SL, options)
    alignment = align_take(signal, numbers, sequence)
    assert np.max(np.abs(_errors(sequence, options, alignment, numbers))) < 0.5
    assert alignment.steps == () and alignment.marks_found == (0, 1, 2, 3, 4)


def test_a_dropped_frame_is_found_where_it_happened():
    sequence = calibration_sequence(PatternOptions())
    ramp = sequence.patch("ramp_green_10")
    dropped_at = ramp.first + 5  # player frame, in the middle of a patch
    # the camera frame exposed at that time
    options = TakeOptions(preroll=1.0, seed=3)
    index = int(((dropped_at - 1) / 24.0 + options.preroll) * options.fps)
    options = TakeOptions(preroll=1.0, seed=3, dropped=(index,))
    numbers, signal = take_signal(sequence, SL, options)
    alignment = align_take(signal, numbers, sequence)
    assert len(alignment.steps) == 1
    where, frames = alignment.steps[0]
    assert frames == -1 and abs(where - dropped_at) <= 2 * sequence.hold
    assert np.max(np.abs(_errors(sequence, options, alignment, numbers))) < 1.0


@pytest.mark.parametrize("preroll", [-0.9, 0.0, 3.0])
def test_early_and_late_starts(preroll):
    """0.9 s late (the lead-in absorbs it), in time, 3 s early."""
    sequence = calibration_sequence(PatternOptions())
    options = TakeOptions(preroll=preroll, seed=2)
    numbers, signal = take_signal(sequence, SL, options)
    alignment = align_take(signal, numbers, sequence)
    assert np.max(np.abs(_errors(sequence, options, alignment, numbers))) < 0.5
    for patch in sequence.of_kind("black", "primary", "white", "ramp"):
        kept = kept_frames(alignment, patch, numbers)
        truth = true_frame_times(sequence, options)[kept]
        # every kept frame's exposure lies inside the patch (centre at least 0.75 frame in)
        margin = 0.75 * sequence.fps / options.fps
        assert np.all(truth > patch.first + margin) and np.all(truth < patch.last + 1 - margin)
        assert len(kept) >= int(patch.frames * options.fps / sequence.fps - 2 * GUARD - 1)


def test_a_camera_started_after_the_first_mark_is_placed_by_the_others():
    sequence = calibration_sequence(PatternOptions())
    options = TakeOptions(preroll=-2.2, seed=4)  # misses lead-in and sync_0
    numbers, signal = take_signal(sequence, SL, options)
    alignment = align_take(signal, numbers, sequence)
    assert alignment.marks_found == (1, 2, 3, 4)
    assert np.max(np.abs(_errors(sequence, options, alignment, numbers)[10:])) < 0.5


def test_no_sequence_in_noise_or_in_another_sequence():
    sequence = calibration_sequence(PatternOptions())
    rng = np.random.default_rng(0)
    noise = 0.5 + 0.01 * rng.standard_normal((900, 3))
    with pytest.raises(InputError, match="not found in the take"):
        align_take(noise, np.arange(900.0), sequence, source="take")
    # A take of a sequence with two sync marks of other flash counts than these
    other = calibration_sequence(PatternOptions(fps=24.0))
    numbers, signal = take_signal(other, SL, TakeOptions())
    with pytest.raises(InputError, match="not found"):
        align_take(signal[:150], numbers[:150], sequence)  # only one mark in view


def test_brightness_is_near_one_for_white_and_zero_for_black():
    signal = np.array(
        [[0.001, 0.001, 0.001]] * 10 + [[0.9, 1.0, 0.8]] * 2 + [[0.5, 0.05, 0.01]] * 5
    )
    b = brightness(signal)
    assert np.all(b[:10] < 0.01) and np.all(b[10:12] > 0.99) and np.all(b[12:] < 0.02)
