"""The ``joint`` Q-solve method, checked on the spectral simulator and against closed forms.

Independent references: the spectral simulator (:mod:`ocio_vp.simulator.stage`) says what the stage
really lights and shows; colour-science computes CIE xy, Lab and CIEDE2000; numpy's lstsq gives
the minimum-norm matrix change in closed form; the paper's eq. 7 (Q [SL] N = I) is the
in-frustum identity.
"""

from __future__ import annotations

import dataclasses
import re
import sys
from pathlib import Path

import colour
import numpy as np
import pytest

from ocio_vp.pipeline import solve_environment

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs"))
from joint_table import comparison_table

from ocio_vp.calibration.geometry import stage_beta
from ocio_vp.correction.joint import (
    DEFAULT_MAX_CONDITION,
    joint_matrix,
    make_q_joint,
    q_joint,
)
from ocio_vp.correction.linear import fit_least_squares
from ocio_vp.correction.registry import Q_SOLVE_METHODS, QProblem
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.simulator.data import ENVIRONMENTS, PAPER_ENVIRONMENTS
from ocio_vp.simulator.predict import predict_solution, predict_stage
from ocio_vp.simulator.stage import paper_stage, simulate_measurements

BROADBAND = [n for n in PAPER_ENVIRONMENTS if ENVIRONMENTS[n].broadband]


@pytest.fixture(scope="module")
def stage():
    return paper_stage()


@pytest.fixture(scope="module")
def measurements(stage):
    return simulate_measurements(PAPER_ENVIRONMENTS, stage=stage)


def problem_for(measurements, name):
    env = measurements.environment(name)
    return QProblem(
        SL=measurements.SL,
        SRL=measurements.SRL,
        beta=stage_beta(measurements),
        M=np.linalg.inv(measurements.SL),
        w_avg=env.w_avg,
        target=env.target_chart,
    )


def chromaticity_delta_e(light, baseline, camera_to_xyz):
    """ΔE2000 of two lights' chromaticities: both at Y = 1, Lab white = the baseline's xy."""
    xy_base = colour.XYZ_to_xy(camera_to_xyz @ baseline)
    xyz = colour.xyY_to_XYZ([*colour.XYZ_to_xy(camera_to_xyz @ light), 1.0])
    return float(colour.delta_E([100.0, 0.0, 0.0], colour.XYZ_to_Lab(xyz, xy_base), "CIE 2000"))


def test_registered():
    assert Q_SOLVE_METHODS["joint"].fit is q_joint


@pytest.mark.parametrize("name", BROADBAND)
def test_lowers_lit_chart_delta_e_within_limits(stage, measurements, name):
    problem = problem_for(measurements, name)
    fit = q_joint(problem)
    assert fit.M is not None and fit.notes["joint_applied"]
    xyz = camera_to_xyz_matrix(stage.camera)  # the same sample camera as the default matrix
    # What the stage really produces (spectral simulation), least squares vs joint.
    Q_ls = fit_least_squares(problem.predicted, problem.target, np.ones(24))
    seq = predict_stage(stage, name, M=problem.M, Q=Q_ls)
    joint = predict_stage(stage, name, M=fit.M, Q=fit.Q)
    de_seq = chart_errors(seq.lit_corrected, seq.target, camera_to_xyz=xyz).delta_E_2000.mean()
    de_joint = chart_errors(joint.lit_corrected, joint.target, camera_to_xyz=xyz).delta_E_2000
    assert de_joint.mean() < de_seq
    # Every limit, recomputed here: white point, drive range, cond(Q), luminance kept.
    drive = fit.M @ problem.w_avg
    baseline = problem.SL @ (problem.M @ problem.w_avg)
    assert chromaticity_delta_e(problem.SL @ drive, baseline, xyz) <= 2.0 + 1e-6
    assert drive.min() >= -1e-9 and drive.max() <= (problem.M @ problem.w_avg).max() * (1 + 1e-6)
    assert np.linalg.cond(fit.Q) <= DEFAULT_MAX_CONDITION
    assert (xyz @ problem.SL @ drive)[1] == pytest.approx((xyz @ baseline)[1], rel=1e-9)
    assert not joint.lit_drive_clipped
    notes = fit.notes
    assert notes["lit_chart_error_reduction"] > 0 and isinstance(notes["active_limits"], list)


def test_in_frustum_chart_comes_back_equal_to_target():
    # No panel bounce, so the in-frustum chart must return exactly after Q (paper eq. 7).
    stage = dataclasses.replace(paper_stage(), panel_albedo=None)
    m = simulate_measurements(["direct_sun"], stage=stage)
    solution = solve_environment(m, m.environments[0], method="joint")
    assert solution.diagnostics.method_notes["joint_applied"]
    assert not np.allclose(solution.M, np.linalg.inv(m.SL))  # the lighting matrix moved
    np.testing.assert_allclose(solution.Q @ m.SL @ solution.N, np.eye(3), atol=1e-12)
    truth = predict_solution(stage, "direct_sun", solution)
    ok = ~truth.displayed_drive_clipped  # the wall cannot emit negative drive
    assert ok.sum() >= 18
    np.testing.assert_allclose(
        truth.displayed_corrected[ok], truth.target[ok], rtol=1e-9, atol=1e-12
    )


def test_joint_matrix_is_the_minimum_norm_change():
    rng = np.random.default_rng(1)
    M, w, d = rng.normal(size=(3, 3)), rng.uniform(0.2, 1, 3), rng.uniform(0.2, 1, 3)
    # vec(dM) solves kron(I, w^T) vec(dM) = d - M w; lstsq gives the minimum-norm solution.
    delta, *_ = np.linalg.lstsq(np.kron(np.eye(3), w[None, :]), d - M @ w, rcond=None)
    np.testing.assert_allclose(joint_matrix(M, w, d), M + delta.reshape(3, 3), atol=1e-12)


def test_zero_white_point_budget_keeps_the_sequential_solution(measurements):
    problem = problem_for(measurements, "incandescent")
    fit = make_q_joint(max_delta_e=0.0)(problem)
    assert fit.M is None and not fit.notes["joint_applied"]
    Q_ls = fit_least_squares(problem.predicted, problem.target, np.ones(24))
    np.testing.assert_allclose(fit.Q, Q_ls, atol=1e-12)


def test_looser_white_point_gains_more(measurements):
    problem = problem_for(measurements, "warm_white_led")
    tight = make_q_joint(max_delta_e=1.0)(problem).notes
    loose = make_q_joint(max_delta_e=4.0, max_drive=1.2 * (problem.M @ problem.w_avg).max())(
        problem
    ).notes
    assert 0 < tight["lit_chart_error_reduction"] < loose["lit_chart_error_reduction"]
    assert tight["white_point_delta_e"] <= 1.0 + 1e-6


def test_sodium_cannot_meet_the_limits(measurements):
    # Low-pressure sodium: Q is rank 1, so no Q meets cond(Q) <= 100: sequential returned.
    problem = problem_for(measurements, "sodium_vapour")
    fit = q_joint(problem)
    assert fit.M is None and fit.notes["limits_met"] is False
    assert "no solution within the limits" in fit.notes["reason"]


def _numbers(text):
    return [float(x) for x in re.findall(r"[-+]?\d+\.\d+|[-+]?\d+(?=\b)", text)]


def test_docs_table_is_generated_by_comparison_table():
    # docs/joint.md's tables must be what the code produces now (not typed by hand).
    doc = (Path(__file__).resolve().parent.parent / "docs" / "joint.md").read_text()
    fresh = comparison_table()
    table_lines = [x for x in fresh.splitlines() if x.startswith("| ") and "---" not in x]
    for line in table_lines:
        name = line.split("|")[1].strip()
        (doc_line,) = [x for x in doc.splitlines() if x.split("|")[1:2] == [f" {name} "]]
        np.testing.assert_allclose(_numbers(doc_line), _numbers(line), atol=0.011, rtol=1e-3)


def test_dark_baseline_light_is_refused_politely(measurements):
    problem = problem_for(measurements, "direct_sun")
    fit = q_joint(dataclasses.replace(problem, w_avg=-problem.w_avg))
    assert fit.M is None and not fit.notes["joint_applied"]
    assert "no luminance" in fit.notes["reason"]
