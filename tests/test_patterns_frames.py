"""Writing the pattern frames: read back with OpenImageIO and decoded with colour-science, every
frame holds what ``sequence.yaml`` says; one file per distinct picture, hard links for the rest."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.patterns.design import PatternOptions, calibration_sequence
from ocio_vp.patterns.frames import write_sequence_folder
from ocio_vp.patterns.sequence import expand_frame, load_sequence


def _read(path: Path, dtype: str) -> np.ndarray:
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, oiio.geterror()
    try:
        return np.asarray(inp.read_image(0, 0, 0, 3, dtype))
    finally:
        inp.close()


@pytest.mark.parametrize(
    ("fmt", "encoding", "peak", "dtype", "full"),
    [
        ("exr", "linear", None, "float", None),
        ("tiff", "pq", 1000.0, "uint16", 65535),
        ("dpx", "gamma2.4", None, "uint16", 1023),
    ],
)
def test_frames_hold_the_sequence(tmp_path, fmt, encoding, peak, dtype, full):
    import colour

    options = PatternOptions(
        size=(8, 6), hold=3, steps=6, file_format=fmt, encoding=encoding, peak_nits=peak
    )
    path = write_sequence_folder(calibration_sequence(options), tmp_path / "p")
    sequence = load_sequence(path)
    files = sorted((tmp_path / "p").glob("patterns.*"))
    assert len(files) == sequence.last_frame - sequence.first_frame + 1
    decoded_top = None
    for patch in sequence.patches:
        for frame in (patch.first, patch.last):
            image = _read(path.parent / expand_frame(sequence.frames, frame), dtype)
            assert image.shape == (6, 8, 3) and np.all(image == image[0, 0])
            value = image[0, 0].astype(np.float64)
            lit = patch.kind != "sync" or any(a <= frame <= b for a, b in patch.flashes)
            expected = np.array(patch.drive if lit else (0, 0, 0))
            if full is None:
                np.testing.assert_array_equal(value, expected)  # half floats, exactly
                continue
            if fmt == "dpx":  # OIIO widens 10-bit codes to 16 bits: c * 65535 / 1023
                value = np.round(value * 1023 / 65535)
            np.testing.assert_array_equal(
                value, np.round(np.array(patch.signal if lit else (0,) * 3) * full)
            )
            signal = value / full
            if encoding == "pq":
                light = colour.models.eotf_ST2084(signal)
            else:
                light = colour.models.gamma_function(signal, 2.4)
            if patch.kind == "white":
                decoded_top = light[0]
            if decoded_top is not None and patch.kind == "ramp":
                np.testing.assert_allclose(light / decoded_top, expected, rtol=1e-9, atol=1e-15)


def test_one_file_per_distinct_picture(tmp_path):
    options = PatternOptions(size=(4, 4), hold=4, steps=5)
    sequence = calibration_sequence(options)
    write_sequence_folder(sequence, tmp_path / "p")
    inodes = {os.stat(p).st_ino for p in (tmp_path / "p").glob("patterns.*.exr")}
    # black, white, 3 primaries, 4 non-zero steps per ramp (the top one is the primary's value
    # only in drive, not necessarily as a file: it is the same picture, so it is linked too)
    assert len(inodes) == 2 + 3 + 3 * 3


def test_sequence_file_round_trips(tmp_path):
    sequence = calibration_sequence(PatternOptions(size=(4, 4), steps=5, fps=23.976))
    path = write_sequence_folder(sequence, tmp_path / "p", frames=False)
    loaded = load_sequence(path)
    assert loaded.patches == sequence.patches
    assert loaded.fps == 23.976 and loaded.frames == "patterns.####.exr"
    assert path.read_text().startswith("# Written by ocio-vp")
