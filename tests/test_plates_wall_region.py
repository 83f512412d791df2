"""Finding the wall: the largest rectangle of pixels that change over the take."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.plates.wall_region import largest_rectangle, wall_mask


def test_largest_rectangle_against_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(20):
        mask = rng.random((7, 9)) < 0.75
        x0, y0, x1, y1 = largest_rectangle(mask)
        assert mask[y0:y1, x0:x1].all()
        best = max(
            ((b - a) * (d - c))
            for a in range(7)
            for b in range(a + 1, 8)
            for c in range(9)
            for d in range(c + 1, 10)
            if mask[a:b, c:d].all()
        )
        assert (x1 - x0) * (y1 - y0) == best


def test_the_mask_is_the_part_that_changes():
    rng = np.random.default_rng(0)
    stack = 0.05 + 0.001 * rng.standard_normal((8, 30, 40, 3))
    levels = np.linspace(0, 1, 8)[:, None, None, None]
    stack[:, 5:20, 10:35] += levels  # the wall
    stack[:, 25:28, 2:5] += 0.2 * levels  # a small practical light in the set, dimmer
    mask = wall_mask(stack)
    assert mask[5:20, 10:35].all() and mask.sum() == 15 * 25


def test_a_non_finite_block_counts_as_zero(monkeypatch):
    # read_region refuses a plate file with NaN/Inf samples; the block average's own rule is
    # tested on the pixels it would be given: one block overflowed to +Inf, one NaN, the rest 0.5.
    from ocio_vp.plates import reader

    pixels = np.full((8, 8, 3), 0.5, dtype=np.float32)
    pixels[4:8, 0:4] = np.inf
    pixels[0:4, 4:8] = np.nan
    monkeypatch.setattr(reader, "read_region", lambda info, box: pixels[box[1] : box[3]])
    info = reader.PlateInfo("p.exr", "openexr", 8, 8, 16, True, "linear")
    means = reader.block_means(info, 4)
    assert (means[1, 0] == 0).all() and (means[0, 1] == 0).all()
    assert (means[0, 0] == 0.5).all() and (means[1, 1] == 0.5).all()


@pytest.mark.filterwarnings("ignore:invalid value encountered in power:RuntimeWarning")
def test_the_wall_is_found_where_decoding_gives_nan(tmp_path):
    # A float take with a stated pure-power encoding: the set's noise below black decodes to
    # NaN (colour-science's Gamma 2.4 of a negative value), which must not hide the wall.
    from exr_helpers import write_exr

    from ocio_vp.plates.reader import open_plate
    from ocio_vp.plates.wall_region import find_wall

    rng = np.random.default_rng(1)
    paths = []
    for k in range(8):
        frame = 0.01 * rng.standard_normal((48, 64, 3))
        frame[10:40, 12:56] += 0.9 * (k % 2)
        paths.append(tmp_path / f"f.{k:04d}.exr")
        write_exr(paths[-1], frame)
    info = open_plate(paths[0], encoding="Gamma 2.4")
    x0, y0, x1, y1 = find_wall(paths, info)
    assert 12 <= x0 < x1 <= 56 and 10 <= y0 < y1 <= 40 and (x1 - x0) * (y1 - y0) > 600


def test_a_movie_frame_decoded_to_nan_does_not_hide_the_wall():
    # A movie's reduced frames come through ``frames``: Gamma 2.4 decodes below-black
    # legal-range codes to NaN (reduced_frame -> decode_log); one NaN cell made the spread's
    # percentile NaN and the take was refused as unchanging.
    from ocio_vp.plates.movie import decode_log
    from ocio_vp.plates.reader import PlateInfo
    from ocio_vp.plates.wall_region import find_wall

    encoded = np.full((8, 48, 64, 3), 0.05)  # R'G'B' after the legal range's scaling
    encoded[1::2, 10:40, 12:56] = 0.8
    encoded[:, 0, 0] = (14 - 64) / 876  # 10-bit code 14, below black
    with np.errstate(invalid="ignore"):
        stack = [decode_log(frame, "Gamma 2.4") for frame in encoded]
    assert np.isnan(stack[0][0, 0]).all()
    info = PlateInfo("take.mov", "movie", 64, 48, 10, False, "Gamma 2.4")
    x0, y0, x1, y1 = find_wall([], info, frames=(8, lambda k, factor: stack[k]))
    assert 12 <= x0 < x1 <= 56 and 10 <= y0 < y1 <= 40 and (x1 - x0) * (y1 - y0) > 600
