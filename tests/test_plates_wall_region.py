"""Finding the wall: the largest rectangle of pixels that change over the take."""

from __future__ import annotations

import numpy as np

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


def test_an_inf_block_is_bright_for_the_wall_finder_and_zero_for_the_chart_detector(monkeypatch):
    # read_region refuses a plate file with NaN/Inf samples; the block average's own rule is
    # tested on the pixels it would be given: one block overflowed to +Inf (a half-float
    # highlight), the rest 0.5.
    from ocio_vp.plates import reader

    pixels = np.full((8, 8, 3), 0.5, dtype=np.float32)
    pixels[4:8, 0:4] = np.inf
    monkeypatch.setattr(reader, "read_region", lambda info, box: pixels[box[1] : box[3]])
    info = reader.PlateInfo("p.exr", "openexr", 8, 8, 16, True, "linear")
    wall = reader.block_means(info, 4, zero_non_finite=False)
    chart = reader.block_means(info, 4)
    assert np.isposinf(wall[1, 0]).all() and (wall[[0, 0, 1], [0, 1, 1]] == 0.5).all()
    assert (chart[1, 0] == 0).all() and (chart[[0, 0, 1], [0, 1, 1]] == 0.5).all()
