"""The paper's solves: M, Q (eq. 5), N (eq. 8) and the black-level offset (Section 3.4)."""

from __future__ import annotations

import colour
import numpy as np
import pytest
from conftest import make_measurements_dict

from ocio_vp.calibration.equations import (
    black_level_offset,
    condition_number,
    predict_displayed_chart,
    predict_lit_chart,
    solve_M,
    solve_N,
)
from ocio_vp.correction.registry import QProblem, solve_post_correction
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.pipeline import solve_environment

RNG = np.random.default_rng(1234)
SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])


def _solve(data: dict, **kwargs):
    measurements = measurements_from_dict(data, source="test.yaml")
    env = measurements.environments[0]
    return measurements, env, solve_environment(measurements, env, method="least-squares", **kwargs)


class TestSolveM:
    def test_inverse_of_SL(self) -> None:
        np.testing.assert_allclose(SL @ solve_M(SL), np.eye(3), atol=1e-15)

    def test_refuses_singular(self) -> None:
        singular = SL.copy()
        singular[:, 2] = singular[:, 1]  # blue primary looks exactly like green
        with pytest.raises(InputError, match="badly conditioned"):
            solve_M(singular, source="stage.yaml")

    def test_refuses_above_threshold_accepts_below(self) -> None:
        near = np.diag([1.0, 1.0, 1e-9])  # cond 1e9
        solve_M(near)  # within the documented 1e10 limit
        with pytest.raises(InputError, match="primaries"):
            solve_M(near, max_condition=1e8)


class TestPostCorrection:
    def test_equals_colour_science_cheung_2004(self) -> None:
        # Independent implementation: colour.characterisation's Cheung 2004, 3 terms, solves
        # argmin ||X C^T - P|| (rows are patches), which is eq. 5 with Q = C.
        measurements, env, _ = _solve(make_measurements_dict(seed=3))
        problem = QProblem(
            SL=measurements.SL,
            SRL=measurements.SRL,
            beta=0.2394564704607735,
            M=solve_M(measurements.SL),
            w_avg=env.target_chart[18] / 0.9,
            target=env.target_chart,
        )
        Q = solve_post_correction(problem, method="least-squares").Q
        reference = colour.characterisation.matrix_colour_correction(
            problem.predicted, env.target_chart, method="Cheung 2004", terms=3
        )
        np.testing.assert_allclose(Q, reference, rtol=1e-9, atol=1e-12)

    def test_exact_linear_data_is_recovered(self) -> None:
        # When p_j = Q_true x_j exactly, least squares must return Q_true.
        measurements, env, _ = _solve(make_measurements_dict(seed=4))
        M = solve_M(measurements.SL)
        w_avg = np.array([0.7, 0.8, 0.6])
        x = predict_lit_chart(measurements.SRL, 0.24, M, w_avg)
        Q_true = np.array([[1.1, -0.08, 0.01], [0.03, 0.95, 0.02], [-0.02, -0.1, 1.15]])
        problem = QProblem(measurements.SL, measurements.SRL, 0.24, M, w_avg, x @ Q_true.T)
        np.testing.assert_allclose(solve_post_correction(problem).Q, Q_true, rtol=1e-12)

    def test_unknown_method_lists_valid_ones(self) -> None:
        measurements, env, _ = _solve(make_measurements_dict())
        problem = QProblem(
            measurements.SL, measurements.SRL, 0.24, np.eye(3), np.ones(3), env.target_chart
        )
        with pytest.raises(InputError, match="least-squares"):
            solve_post_correction(problem, method="least-sqares")


class TestRoundTrips:
    def test_in_frustum_chart_comes_back_exact(self) -> None:
        # Shown through N, seen by the camera ([SL]), post-corrected by Q: the target again
        # (paper eq. 6, Q [SL] N = I). Content positive and small enough for no clipping.
        measurements, env, s = _solve(make_measurements_dict(seed=5, black_level=False))
        # In-gamut content: what positive drives look like after Q (nothing for the wall to clip).
        content = RNG.uniform(0.05, 0.9, size=(50, 3)) @ (s.Q @ s.SL).T
        drive = content @ s.N.T
        assert np.all(drive > 0)
        back = (drive @ s.SL.T) @ s.Q.T
        np.testing.assert_allclose(back, content, rtol=1e-9)
        np.testing.assert_allclose(s.Q @ s.SL @ s.N, np.eye(3), atol=1e-12)

    def test_out_of_frustum_is_identity_to_the_camera(self) -> None:
        measurements, env, s = _solve(make_measurements_dict())
        np.testing.assert_allclose(s.SL @ s.M, np.eye(3), atol=1e-15)

    def test_black_level_exact_offset_cancels_bounce(self) -> None:
        # Drive N c + offset, camera sees [SL] drive + b, then Q: must equal c.
        measurements, env, s = _solve(make_measurements_dict(seed=6))
        # In-gamut content whose drive stays positive after the (negative) offset.
        drive = RNG.uniform(0.2, 0.9, size=(50, 3))
        content = (drive - s.black_level_offset) @ (s.Q @ s.SL).T
        seen = predict_displayed_chart(
            content, SL=s.SL, matrix=s.N, offset=s.black_level_offset, black_level=env.black_level
        )
        np.testing.assert_allclose(seen @ s.Q.T, content, rtol=1e-9)
        assert s.black_level_method == "exact"

    def test_paper_black_level_is_exact_only_for_diagonal_SL(self) -> None:
        b = np.array([0.02, 0.03, 0.01])
        diagonal = np.diag([0.8, 0.9, 0.7])
        M = solve_M(diagonal)
        np.testing.assert_allclose(
            black_level_offset(b, M=M, SL=diagonal, method="paper"),
            black_level_offset(b, M=M, method="exact"),
            rtol=1e-14,
        )
        M = solve_M(SL)
        paper = black_level_offset(b, M=M, SL=SL, method="paper")
        exact = black_level_offset(b, M=M, method="exact")
        assert np.abs(paper - exact).max() > 1e-3  # a real approximation for a mixing [SL]

    def test_paper_black_level_selectable(self) -> None:
        _, _, s = _solve(make_measurements_dict(seed=7), black_level="paper")
        assert s.black_level_method == "paper"
        w_camera = s.SL.sum(axis=1)
        np.testing.assert_allclose(
            s.black_level_offset,
            -(np.asarray(s.diagnostics.charts.target)[18] * 0.04 / w_camera),
            rtol=1e-12,
        )


class TestSolveN:
    def test_rank_one_Q_is_not_inverted(self) -> None:
        rank_one = np.outer([1.0, 0.8, 0.1], [0.3, 0.5, 0.2])
        N, reason = solve_N(np.eye(3), rank_one)
        assert N is None
        assert "rank 1" in reason

    def test_condition_threshold(self) -> None:
        Q = np.diag([1.0, 1.0, 1e-4])  # cond 1e4
        assert solve_N(np.eye(3), Q)[0] is None
        assert solve_N(np.eye(3), Q, max_condition=1e5)[0] is not None

    def test_N_equals_M_times_Q_inverse(self) -> None:
        Q = np.array([[1.1, -0.08, 0.01], [0.03, 0.95, 0.02], [-0.02, -0.1, 1.15]])
        M = solve_M(SL)
        N, reason = solve_N(M, Q)
        assert reason is None
        np.testing.assert_allclose(N, M @ np.linalg.inv(Q), rtol=1e-12)

    def test_unsolvable_N_falls_back_to_M_with_warning(self) -> None:
        data = make_measurements_dict(seed=8)
        # A monochromatic target: every patch the same colour up to brightness -> rank-1 Q.
        target = np.asarray(data["environments"][0]["target_chart"])
        data["environments"][0]["target_chart"] = (
            np.outer(target[:, 1], [1.0, 0.7, 0.05]) + 1e-9
        ).tolist()
        _, _, s = _solve(data)
        assert s.N is None
        assert s.diagnostics.N_solved is False
        assert any("N not solved" in w for w in s.diagnostics.warnings)
        np.testing.assert_array_equal(s.in_frustum_matrix, s.M)


def test_condition_number_of_singular_is_inf() -> None:
    assert condition_number(np.zeros((3, 3))) == float("inf")
    assert condition_number(np.eye(3)) == pytest.approx(1.0)


class TestByHand:
    def test_eq3_one_patch(self) -> None:
        # drive M w_avg = [1, 2, 3]; [SRL] drive = [1 + 4, 2, 9]; divided by beta = 0.25.
        SRL = np.array([[[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]]])
        M = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 0.0, 1.0]])
        lit = predict_lit_chart(SRL, 0.25, M, np.array([1.0, 1.0, 2.0]))
        np.testing.assert_array_equal(lit, [[20.0, 8.0, 36.0]])

    def test_displayed_chart_clips_the_drive_the_wall_cannot_emit(self) -> None:
        # drive N c = [0.2 - 0.5, 0.5, 0.1]: the wall shows 0 red; with max_drive 0.4, green 0.4.
        SL = np.diag([2.0, 3.0, 4.0])
        N = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        content = np.array([[0.2, 0.5, 0.1]])
        b = np.array([0.01, 0.02, 0.03])
        shown = predict_displayed_chart(content, SL=SL, matrix=N, black_level=b)
        np.testing.assert_allclose(shown, [[0.01, 1.52, 0.43]], rtol=1e-15)
        capped = predict_displayed_chart(content, SL=SL, matrix=N, max_drive=0.4)
        np.testing.assert_allclose(capped, [[0.0, 1.2, 0.4]], rtol=1e-15)
        offset = np.array([0.0, 0.0, -0.2])  # an offset pushing blue below zero is clipped too
        with_offset = predict_displayed_chart(content, SL=SL, matrix=N, offset=offset)
        np.testing.assert_allclose(with_offset, [[0.0, 1.5, 0.0]], rtol=1e-15)
