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
