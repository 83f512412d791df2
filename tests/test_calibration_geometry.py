"""beta (the calibration panel's diffuse form factor) and w_avg."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.calibration.geometry import (
    form_factor_numerical,
    form_factor_parallel_rectangle,
    w_avg_from_white_patch,
)
from ocio_vp.errors import InputError


class TestFormFactorParallelRectangle:
    def test_reference_values(self) -> None:
        # DESIGN.md "Facts already measured": 1 m square at 1 m -> 0.23946; the paper's
        # beta ~ 0.311 is a 1.2 m square at 1 m (+-0.6 on a 90-degree cube face) -> 0.31128.
        assert form_factor_parallel_rectangle(1.0, 1.0, 1.0) == pytest.approx(0.23946, abs=5e-6)
        assert form_factor_parallel_rectangle(1.2, 1.2, 1.0) == pytest.approx(0.31128, abs=5e-6)

    @pytest.mark.parametrize(
        ("width", "height", "distance", "ox", "oy"),
        [
            (1.0, 1.0, 1.0, 0.0, 0.0),
            (2.0, 0.5, 1.5, 0.0, 0.0),
            (1.0, 1.0, 1.0, 0.3, -0.2),  # centre off the normal but still covering it
            (0.5, 0.8, 1.2, 1.5, 0.7),  # entirely to one side
        ],
    )
    def test_matches_numerical_integration(self, width, height, distance, ox, oy) -> None:
        # Independent check: midpoint rule of cos*cos/(pi r^2) over the panel.
        closed = form_factor_parallel_rectangle(width, height, distance, ox, oy)
        numeric = form_factor_numerical(width, height, distance, ox, oy, samples=1500)
        assert closed == pytest.approx(numeric, rel=1e-6)

    def test_infinite_plane_limit_is_one(self) -> None:
        # A plane filling the whole hemisphere delivers all of the diffuse irradiance.
        assert form_factor_parallel_rectangle(1e6, 1e6, 1.0) == pytest.approx(1.0, abs=1e-5)

    def test_mirror_symmetry_of_offsets(self) -> None:
        a = form_factor_parallel_rectangle(1.0, 0.5, 1.0, 0.4, 0.1)
        b = form_factor_parallel_rectangle(1.0, 0.5, 1.0, -0.4, -0.1)
        assert a == pytest.approx(b, rel=1e-14)

    def test_rejects_non_positive_sizes(self) -> None:
        with pytest.raises(InputError, match="must be > 0"):
            form_factor_parallel_rectangle(0.0, 1.0, 1.0)


class TestWAvgFromWhitePatch:
    def test_divides_white_by_reflectance(self) -> None:
        chart = np.zeros((24, 3))
        chart[18] = [0.45, 0.9, 0.18]
        np.testing.assert_allclose(w_avg_from_white_patch(chart), [0.5, 1.0, 0.2], rtol=1e-15)

    def test_leading_dimensions(self) -> None:
        charts = np.ones((2, 5, 24, 3))
        assert w_avg_from_white_patch(charts, 3, 0.5).shape == (2, 5, 3)
