"""ocio_vp.calibration.panels and the solve of a stage of several panel types (pipeline).

Checked against the simulator's spectra (an independent computation of the light on the chart:
each type's LED spectra times its drive, through the camera), against numpy's least squares for
eq. 5, and against eq. 7 for every in-frustum type.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ocio_vp.correction.registry import Q_SOLVE_METHODS
from ocio_vp.formats.measurements import Measurements
from ocio_vp.formats.solution import solution_to_dict
from ocio_vp.pipeline import post_correction_problem, solve_environment
from ocio_vp.simulator.panels import scene_light
from ocio_vp.simulator.stage import camera_rgb


def spectral_lit_chart(stage, environment, M_wall, M_ceiling):
    """(n, 3) the chart lit by both panel types, from the spectra (each type's true LEDs
    times its drive clipped at 0), the independent counterpart of eq. 3 summed."""
    light = scene_light(stage.wall, environment)
    w = {k: camera_rgb(stage.wall, v) for k, v in light.items()}
    emitted = stage.wall.leds @ np.clip(M_wall @ w["wall"], 0, None)
    emitted = emitted + stage.ceiling.leds @ np.clip(M_ceiling @ w["ceiling"], 0, None)
    return camera_rgb(stage.wall, stage.wall.reflectances * emitted)


def test_the_summed_eq3_is_the_spectral_truth(panel_stage_and_measurements):
    stage, m = panel_stage_and_measurements
    for env in m.environments:
        problem = post_correction_problem(m, env)
        truth = spectral_lit_chart(
            stage, env.name, np.linalg.inv(stage.wall.SL), np.linalg.inv(stage.ceiling.SL)
        )
        assert np.allclose(problem.predicted, truth, rtol=1e-10, atol=0)
        # The first in-frustum type's eq. 3 is the problem's own; the ceiling's is extra light.
        assert np.array_equal(problem.M, np.linalg.inv(stage.wall.SL))
        assert np.allclose(problem.extra_light, truth - problem.predicted + problem.extra_light)


@pytest.mark.parametrize("method", list(Q_SOLVE_METHODS))
def test_every_method_fits_q_to_the_summed_light(panel_stage_and_measurements, method):
    stage, m = panel_stage_and_measurements
    env = m.environments[0]
    solution = solve_environment(m, env, method=method)
    assert np.all(np.isfinite(solution.Q))
    ceiling = solution.panels["ceiling"]
    assert np.allclose(ceiling.M @ stage.ceiling.SL, np.eye(3), atol=1e-12)
    assert ceiling.N is None and not ceiling.in_frustum
    truth = spectral_lit_chart(stage, env.name, solution.M, ceiling.M)
    # The chart after Q is the summed light corrected (the solve's own "lit_corrected").
    corrected = solution.diagnostics.charts.lit_corrected
    assert np.allclose(corrected, solution.correction.apply(truth), rtol=1e-9, atol=1e-12)
    if method == "least-squares":  # eq. 5 on the summed light, by numpy's own least squares
        QT, *_ = np.linalg.lstsq(truth, env.target_chart, rcond=None)
        assert np.allclose(solution.Q, QT.T, rtol=1e-9, atol=1e-12)


def test_the_ceiling_gets_m_and_no_n_in_solution_json(panel_stage_and_measurements):
    _, m = panel_stage_and_measurements
    block = solution_to_dict(solve_environment(m, m.environments[0]))
    assert set(block["panels"]) == {"wall", "ceiling"}
    assert (
        "N" not in block["panels"]["ceiling"]
        and "black_level_offset" not in block["panels"]["ceiling"]
    )
    wall = block["panels"]["wall"]
    # The top level stays the first in-frustum type's, for readers of single-wall solutions.
    for key in ("M", "N", "black_level_offset"):
        assert wall[key] == block[key]
    shares = block["diagnostics"]["panels"]["shares"]
    assert abs(sum(shares.values()) - 1) < 1e-12 and shares["ceiling"] > shares["wall"]  # overcast


def test_lit_white_with_the_walls_m_everywhere(panel_stage_and_measurements):
    stage, m = panel_stage_and_measurements
    env = m.environments[1]
    notes = solve_environment(m, env).diagnostics.panels
    M_wall = np.linalg.inv(stage.wall.SL)
    white = env.target_chart[18]
    for key, M_ceiling in (
        ("lit_white_error", np.linalg.inv(stage.ceiling.SL)),
        ("lit_white_error_primary_M", M_wall),
    ):
        lit = spectral_lit_chart(stage, env.name, M_wall, M_ceiling)[18]
        assert np.allclose(getattr(notes, key), np.abs(lit - white) / white, rtol=1e-9)
    assert max(notes.lit_white_error) < 0.01 < max(notes.lit_white_error_primary_M)


def with_floor(m: Measurements, gain: float = 1.0) -> Measurements:
    """The simulated stage with its second panel type in frustum (a floor) at ``gain``."""
    wall, other = m.panels
    floor = dataclasses.replace(other, name="floor", in_frustum=True, SL=other.SL * gain)
    floor = dataclasses.replace(floor, SRL=other.SRL * gain)
    envs = []
    for e in m.environments:
        w_avg = {"wall": e.panel_w_avg["wall"], "floor": e.panel_w_avg["ceiling"]}
        black = {"wall": e.panel_black_level["wall"], "floor": 0.5 * e.panel_black_level["wall"]}
        envs.append(dataclasses.replace(e, panel_w_avg=w_avg, panel_black_level=black))
    return dataclasses.replace(m, panels=(wall, floor), environments=tuple(envs))


def test_in_frustum_types_match_in_camera_by_construction(panel_stage_and_measurements):
    from ocio_vp.calibration.geometry import environment_panel_w_avg
    from ocio_vp.calibration.panels import InFrustumDrive, panel_lights, shown_in_camera

    _, m = panel_stage_and_measurements
    m = with_floor(m)
    env = m.environments[0]
    solution = solve_environment(m, env, method="least-squares")
    floor = solution.panels["floor"]
    # Eq. 7 with the floor's own [SL]: Q [SL]_floor N_floor = I, and its own offset -M b.
    assert np.allclose(solution.Q @ floor.SL @ floor.N, np.eye(3), atol=1e-12)
    black = env.panel_black_level["floor"]
    assert np.allclose(floor.black_level_offset, -floor.M @ black, atol=1e-15)
    # Every colour both types can emit comes out of Q the same, whichever type shows it.
    lights = {light.name: light for light in panel_lights(m, environment_panel_w_avg(m, env))}
    seen = {}
    for name, panel in solution.panels.items():
        drive = InFrustumDrive(panel.N, panel.N_reason, panel.black_level_offset)
        seen[name] = shown_in_camera(
            lights[name], drive, env.target_chart, solution.correction,
            black_level=env.panel_black_level[name],
        )  # fmt: skip
    both = seen["wall"][1] & seen["floor"][1]
    assert both.sum() >= 18
    assert np.allclose(seen["wall"][0][both], env.target_chart[both], rtol=1e-9, atol=1e-12)
    assert np.allclose(seen["floor"][0][both], env.target_chart[both], rtol=1e-9, atol=1e-12)
    block = solution.diagnostics.panels.in_frustum_match.types["floor"]
    assert solution.diagnostics.panels.in_frustum_match.reference == "wall"
    assert set(block.unreachable) | set(block.unreachable_on_reference) >= set(
        np.flatnonzero(~both).tolist()
    ) - set(np.flatnonzero(~seen["wall"][1] & ~seen["floor"][1]).tolist())


def test_a_dim_floor_cannot_reach_what_the_wall_shows_and_says_so(panel_stage_and_measurements):
    _, m = panel_stage_and_measurements
    m = with_floor(m, gain=0.5)
    solution = solve_environment(m, m.environments[0], method="least-squares")
    block = solution.diagnostics.panels.in_frustum_match.types["floor"]
    assert block.unreachable  # half as bright: the wall's brightest colours are out of reach
    assert block.delta_E_2000_max > 1
    warnings = [w for w in solution.diagnostics.warnings if "panel type floor cannot show" in w]
    assert len(warnings) == 1 and str(block.unreachable) in warnings[0]


def test_one_panel_type_in_the_panels_form_solves_as_a_file_without_it(
    panel_stage_and_measurements,
):
    from ocio_vp.formats.measurements import Environment

    _, m = panel_stage_and_measurements
    wall = m.panels[0]
    single = dataclasses.replace(m, panels=(wall,))
    single = dataclasses.replace(
        single,
        environments=tuple(
            dataclasses.replace(
                e,
                panel_w_avg={"wall": e.panel_w_avg["wall"]},
                panel_black_level={"wall": e.panel_black_level["wall"]},
            )
            for e in m.environments
        ),
    )
    flat = Measurements(
        stage=dataclasses.replace(m.stage, panel=wall.panel, beta=wall.beta),
        SL=wall.SL,
        SRL=wall.SRL,
        environments=tuple(
            Environment(
                e.name,
                e.target_chart,
                w_avg=e.panel_w_avg["wall"],
                black_level=e.panel_black_level["wall"],
            )
            for e in m.environments
        ),
    )
    for a, b in zip(single.environments, flat.environments, strict=True):
        s, f = solve_environment(single, a), solve_environment(flat, b)
        for key in ("M", "Q", "N", "black_level_offset"):
            assert np.array_equal(getattr(s, key), getattr(f, key)), key


def test_fixtures_light_with_the_other_panel_types(panel_stage_and_measurements):
    from ocio_vp.simulator.fixtures import with_simulated_fixtures

    stage, m = panel_stage_and_measurements
    m = with_simulated_fixtures(m, stage.wall, ["rgbw"])
    env = m.environments[1]
    solution = solve_environment(m, env, method="least-squares")
    notes = solution.diagnostics.fixtures
    # The error Q cannot remove with the wall alone counts the ceiling's light (independently:
    # numpy's least squares on the spectral chart of both types).
    lit = spectral_lit_chart(
        stage, env.name, np.linalg.inv(stage.wall.SL), np.linalg.inv(stage.ceiling.SL)
    )
    QT, *_ = np.linalg.lstsq(lit, env.target_chart, rcond=None)
    residual = np.sum((lit @ QT - env.target_chart) ** 2)
    expected = residual / (24 * np.sum(env.target_chart[18] ** 2))
    assert notes.error_wall_only == pytest.approx(expected, rel=1e-9)
    assert notes.applied and notes.error_with_fixtures < notes.error_wall_only


def test_one_panel_type_without_w_avg_takes_it_from_the_white_patch(panel_stage_and_measurements):
    from ocio_vp.errors import InputError

    _, m = panel_stage_and_measurements
    m = dataclasses.replace(m, panels=m.panels[:1])
    env = dataclasses.replace(m.environments[0], panel_w_avg=None, panel_black_level=None)
    solution = solve_environment(dataclasses.replace(m, environments=(env,)), env)
    assert np.allclose(solution.w_avg, env.target_chart[18] / m.stage.white_reflectance)
    target = env.target_chart.copy()
    target[18] = 0.0
    black = dataclasses.replace(env, target_chart=target)
    with pytest.raises(InputError, match=r"environments\[0\]\.target_chart: white patch 18"):
        solve_environment(dataclasses.replace(m, environments=(black,)), black)
