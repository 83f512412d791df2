"""Leave-one-out validation (ocio_vp.correction.validation) against a plain numpy loop."""

from __future__ import annotations

import numpy as np

from ocio_vp.correction.registry import QProblem
from ocio_vp.correction.validation import cross_validated_error
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.pipeline import solve_environment


class TestCrossValidation:
    def test_least_squares_loo_matches_a_plain_numpy_loop(self, measurements_dict) -> None:
        m = measurements_from_dict(measurements_dict)
        s = solve_environment(m, m.environments[0], method="least-squares")
        problem = QProblem(
            SL=m.SL, SRL=m.SRL, beta=s.beta, M=s.M, w_avg=s.w_avg,
            target=m.environments[0].target_chart,
        )  # fmt: skip
        X, P = problem.predicted, problem.target
        held = np.empty_like(P)
        for j in range(24):
            rows = np.arange(24) != j
            QT = np.linalg.lstsq(X[rows], P[rows], rcond=None)[0]
            held[j] = X[j] @ QT
        expected = np.mean(np.abs(held - P) / P[18], axis=0)
        np.testing.assert_allclose(cross_validated_error(problem, "least-squares"), expected)
        np.testing.assert_allclose(s.diagnostics.cross_validated_error, expected)
