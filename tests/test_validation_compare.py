"""validation.compare's expected camera RGB against its closed form: the wall applies the
solve's soft clip (written out here from docs/headroom.md), clips to [0, 1], [SL] films it,
plus the bounce the black-level offset cancels."""

from __future__ import annotations

import numpy as np
from conftest import make_measurements_dict

from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.pipeline import solve_measurements
from ocio_vp.validation.compare import expected_camera
from ocio_vp.wall.softclip import with_soft_clip


def _solution():
    data = make_measurements_dict(seed=3, environments=1)
    (solution,) = solve_measurements(measurements_from_dict(data), method="least-squares")
    return solution


def test_expected_camera_follows_the_soft_clip_of_the_solve():
    solution = _solution()
    light = np.array([[0.2, 0.5, 0.55], [0.65, 0.9, 0.3], [1.4, -0.1, 0.95]])
    SL = np.asarray(solution.SL)
    bounce = -(SL @ solution.in_frustum_offset)
    plain = expected_camera(solution, light)
    np.testing.assert_allclose(plain, np.clip(light, 0, 1) @ SL.T + bounce, rtol=1e-12)
    knee = 0.6
    clipped = with_soft_clip(solution, knee)
    span = 1 - knee
    f = np.where(light > knee, 1 - span * np.exp(-(light - knee) / span), light)
    want = np.clip(f, 0, 1) @ SL.T + bounce
    np.testing.assert_allclose(expected_camera(clipped, light), want, rtol=1e-12)
    # below the knee nothing changes; above it the wall shows less than the hard clip's light
    np.testing.assert_array_equal(expected_camera(clipped, light[:1]), plain[:1])
    assert not np.allclose(expected_camera(clipped, light[1:]), plain[1:])
