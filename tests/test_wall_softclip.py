"""ocio_vp.wall.softclip: the soft clip's closed form checked against its defining properties
(identity below the knee, C1 at it, strictly rising, approaching full drive and within 1/1023 of
it from ``full_drive``), its exact inverse, and how solution.json records it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ocio_vp.formats.solution import load_solution, solution_to_json
from ocio_vp.wall.encoding import WallEncoding, with_wall_encoding
from ocio_vp.wall.softclip import (
    FULL_TOLERANCE,
    INVERSE_CAP,
    check_knee,
    forward,
    full_drive,
    inverse,
    soft_clip_knee,
    with_soft_clip,
)

KNEES = (0.05, 0.5, 0.7, 0.8, 0.95)
SAMPLE = "sample_configs/paper_stage/warm_white_led/solution.json"


@pytest.mark.parametrize("knee", KNEES)
def test_identity_below_the_knee_negative_drive_included(knee):
    d = np.concatenate([np.linspace(-4.0, knee, 1001), [-1e-30, 0.0, knee]])
    np.testing.assert_array_equal(forward(d, knee), d)


@pytest.mark.parametrize("knee", KNEES)
def test_c1_at_the_knee_and_the_slope_everywhere(knee):
    """Value and slope match at the knee (one-sided differences of the closed form), and above
    it the slope is exp(-(d - k) / (1 - k)): positive, so the curve rises strictly."""
    h = 1e-8
    left = (forward(knee, knee) - forward(knee - h, knee)) / h
    right = (forward(knee + h, knee) - forward(knee, knee)) / h
    assert float(forward(knee + 1e-12, knee)) == pytest.approx(knee, abs=1e-11)
    assert float(left) == pytest.approx(1.0, abs=1e-6)
    assert float(right) == pytest.approx(1.0, abs=1e-6)
    d = np.linspace(knee + 1e-3, knee + 20 * (1 - knee), 2001)
    slope = (forward(d + 1e-6, knee) - forward(d - 1e-6, knee)) / 2e-6
    want = np.exp(-(d - knee) / (1 - knee))
    np.testing.assert_allclose(slope, want, rtol=1e-4, atol=1e-9)


@pytest.mark.parametrize("knee", KNEES)
def test_strictly_rising_below_full_drive(knee):
    """In float64 until 1 - f is below the spacing of doubles near 1 (20 knee widths on)."""
    d = np.linspace(-1.0, knee + 20 * (1 - knee), 200001)
    y = forward(d, knee)
    assert np.all(np.diff(y) > 0)
    assert np.all(y < 1.0)
    big = forward(np.array([1e3, 1e6, 1e300]), knee)
    assert np.all(big <= 1.0) and np.all(np.isfinite(big))


@pytest.mark.parametrize("knee", KNEES)
def test_within_a_10_bit_code_of_full_drive_from_full_drive(knee):
    """1 - f(full_drive) = 1/1023 exactly (the closed form solved for it), never later than
    drive ln 1023 = 6.93, below 16x content white's drive on the sample stage (red, 2.33)."""
    top = full_drive(knee)
    assert 1.0 - float(forward(top, knee)) == pytest.approx(FULL_TOLERANCE, rel=1e-9)
    assert 1.0 - float(forward(top * 0.999, knee)) > FULL_TOLERANCE
    assert top <= math.log(1023.0) + 1e-12
    assert 16 * 2.33 > top


@pytest.mark.parametrize("knee", KNEES)
def test_inverse_undoes_the_clip_on_its_domain(knee):
    d = np.linspace(-2.0, knee + (1 - knee) * 8, 5001)
    np.testing.assert_allclose(inverse(forward(d, knee), knee), d, rtol=0, atol=1e-9)
    assert np.isinf(inverse(1.0, knee))
    cap = float(inverse(INVERSE_CAP, knee))
    assert cap == pytest.approx(knee + (1 - knee) * math.log(4096 * (1 - knee)), rel=1e-12)


@pytest.mark.parametrize("knee", [0.0, 1.0, -0.5, 2.0, math.nan, math.inf])
def test_knee_outside_0_1_is_refused(knee):
    with pytest.raises(ValueError, match="knee in \\(0, 1\\)"):
        check_knee(knee)


def test_solution_json_records_it_and_old_files_read_as_off(tmp_path):
    solution = load_solution(SAMPLE)
    assert soft_clip_knee(solution.linearity) is None  # written before the option existed
    assert with_soft_clip(solution, None) is solution
    clipped = with_soft_clip(solution, 0.75)
    block = clipped.linearity.soft_clip
    assert block.knee == 0.75 and block.full_drive == pytest.approx(full_drive(0.75))
    assert clipped.linearity.model == "linear (assumed)"
    path = tmp_path / "solution.json"
    path.write_text(solution_to_json(clipped), encoding="utf-8")
    assert json.loads(path.read_text())["linearity"]["soft_clip"]["knee"] == 0.75
    assert soft_clip_knee(load_solution(path).linearity) == 0.75
    # the other settings of the wall's transfer are kept beside it
    encoded = with_wall_encoding(solution, "pq")
    assert WallEncoding.of(with_soft_clip(encoded, 0.5).linearity) == WallEncoding("pq")
