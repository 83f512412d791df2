"""Guards shared by every Q method (ocio_vp.correction.guards): the issue's four bad inputs.

Each must be an InputError naming the key (exit 2, one line through the CLI) for every method,
never a rank-deficient or absurd Q; and N_reason names the real cause.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ocio_vp.correction.guards import check_problem, singular_q_cause
from ocio_vp.correction.registry import Q_SOLVE_METHODS, QProblem
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import save_measurements
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.stage import simulate_measurements

METHODS = sorted(Q_SOLVE_METHODS)


@pytest.fixture(scope="module")
def measurements():
    return simulate_measurements(["direct_sun", "sodium_vapour"])


def _with_target(m, target, **changes):
    env = dataclasses.replace(m.environments[0], target_chart=target, **changes)
    return dataclasses.replace(m, environments=(env, *m.environments[1:])), env


@pytest.mark.parametrize("method", METHODS)
def test_two_usable_patches(measurements, method: str) -> None:
    m = dataclasses.replace(measurements, SRL=measurements.SRL[:2])
    m, env = _with_target(m, measurements.environments[0].target_chart[:2])
    m = dataclasses.replace(m, stage=dataclasses.replace(m.stage, white_patch=1))
    with pytest.raises(InputError, match="only 2 chart patches") as error:
        solve_environment(m, env, method=method)
    assert error.value.key == "environments[0].target_chart"


@pytest.mark.parametrize("method", METHODS)
def test_black_target_with_w_avg_given(measurements, method: str) -> None:
    m, env = _with_target(measurements, np.zeros((24, 3)))
    assert env.w_avg is not None
    with pytest.raises(InputError, match="black on every fitted patch") as error:
        solve_environment(m, env, method=method)
    assert error.value.key == "environments[0].target_chart"


@pytest.mark.parametrize("method", METHODS)
def test_lit_chart_with_a_dark_camera_channel(measurements, method: str) -> None:
    SRL = measurements.SRL.copy()
    SRL[:, 1, :] = 0.0  # the camera's green channel reads 0 under every LED
    m = dataclasses.replace(measurements, SRL=SRL)
    with pytest.raises(InputError, match="green channel") as error:
        solve_environment(m, m.environments[0], method=method)
    assert error.value.key == "lit_chart"


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("where", ["target", "lit"])
def test_a_value_no_camera_produces(measurements, method: str, where: str) -> None:
    if where == "target":
        target = measurements.environments[0].target_chart.copy()
        target[4, 2] = 1e300
        m, env = _with_target(measurements, target)
        key = "environments[0].target_chart"
    else:
        SRL = measurements.SRL.copy()
        SRL[4, 2, 0] = 1e300
        m = dataclasses.replace(measurements, SRL=SRL)
        env, key = m.environments[0], "lit_chart"
    with pytest.raises(InputError, match="not a camera value") as error:
        solve_environment(m, env, method=method)
    assert error.value.key == key and "patch 5" in str(error.value)


def test_cli_refuses_in_one_line_with_exit_2(measurements, tmp_path, capsys) -> None:
    from ocio_vp.cli import main

    m, _ = _with_target(measurements, np.zeros((24, 3)))
    path = tmp_path / "m.yaml"
    save_measurements(m, path)
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "environments[0].target_chart" in err[0]
    assert not (tmp_path / "out").exists()


def test_patches_of_one_colour_span_one_direction(measurements) -> None:
    SRL = np.repeat(measurements.SRL[18:19], 24, axis=0) * np.linspace(0.1, 1, 24)[:, None, None]
    problem = QProblem(
        SL=measurements.SL, SRL=SRL, beta=0.24, M=np.linalg.inv(measurements.SL),
        w_avg=np.ones(3), target=np.random.default_rng(0).uniform(0.1, 1, (24, 3)),
    )  # fmt: skip
    with pytest.raises(InputError, match="span only 1 colour direction"):
        check_problem(problem)


def test_n_reason_names_the_real_cause(measurements) -> None:
    sodium = solve_environment(measurements, measurements.environment("sodium_vapour"))
    assert "rank 1" in sodium.diagnostics.N_reason
    assert "sodium" in sodium.diagnostics.N_reason
    # A singular Q that is not the light's fault is not blamed on sodium vapour.
    problem = QProblem(
        SL=measurements.SL, SRL=measurements.SRL, beta=0.24, M=np.linalg.inv(measurements.SL),
        w_avg=np.ones(3), target=measurements.environments[0].target_chart,
    )  # fmt: skip
    text = singular_q_cause(problem, "least-squares")
    assert "sodium" not in text and "least-squares" in text
