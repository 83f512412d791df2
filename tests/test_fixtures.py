"""ocio_vp.fixtures: the drive solve, the lighting it gives the solve, DMX levels.

Oracles: numpy's own least squares for the error Q cannot remove, colour-science's CIEDE2000
for the white-point limit, the spectral simulator's ground truth (held-out reflectances under
the light the stage really emits) for the gain, and closed forms for DMX values.
"""

from __future__ import annotations

import dataclasses
import json

import colour
import numpy as np
import pytest

from ocio_vp.calibration.geometry import stage_beta
from ocio_vp.cli import main
from ocio_vp.correction.joint import DEFAULT_MAX_DELTA_E
from ocio_vp.errors import InputError
from ocio_vp.fixtures import (
    DriveProblem,
    content_matrix,
    dmx_rows,
    dmx_values,
    irreducible_error,
    solve_fixture_drives,
)
from ocio_vp.formats.fixtures import DmxPatch, Fixture
from ocio_vp.formats.measurements import save_measurements
from ocio_vp.formats.solution import FixtureDrive, load_solution, solution_to_json
from ocio_vp.metrics import sample_camera_to_xyz
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.fixtures import fixture_spectra, with_simulated_fixtures
from ocio_vp.simulator.stage import paper_stage, simulate_measurements
from ocio_vp.simulator.truth import held_out_errors, held_out_reflectances


@pytest.fixture(scope="module")
def stage():
    return paper_stage()


@pytest.fixture(scope="module")
def rgbw(stage):
    base = simulate_measurements(["d65", "incandescent", "sodium_vapour"], stage=stage)
    return with_simulated_fixtures(base, stage, ["rgbw"])


@pytest.fixture(scope="module")
def solved(rgbw):
    return {
        env.name: solve_environment(rgbw, env, method="least-squares") for env in rgbw.environments
    }


def test_irreducible_error_is_the_least_squares_residual_numpy_finds():
    rng = np.random.default_rng(1)
    A = rng.uniform(0.0, 1.0, (24, 3, 5))
    P = rng.uniform(0.05, 1.0, (24, 3))
    w = rng.uniform(0.5, 1.0, 24)
    z = rng.uniform(0.1, 1.0, 5)
    problem = DriveProblem(A, P, w, z, np.ones(5), np.eye(3), white_patch=18)
    X = A @ z
    sw = np.sqrt(w)[:, None]
    QT, *_ = np.linalg.lstsq(X * sw, P * sw, rcond=None)  # the oracle: numpy's own solve
    residual = float(np.sum(w[:, None] * (X @ QT - P) ** 2))
    expected = residual / (w.sum() * np.sum(P[18] ** 2))
    assert irreducible_error(problem, z) == pytest.approx(expected, rel=1e-12)


def test_fixtures_respect_every_limit(solved, rgbw):
    xyz = sample_camera_to_xyz()
    for name in ("d65", "incandescent"):
        solution = solved[name]
        notes = solution.diagnostics.fixtures
        assert notes.applied
        drives = np.array(list(solution.fixtures["rgbw"].drive.values()))
        assert np.all(drives >= 0) and np.all(drives <= 1.0 + 1e-9)
        wall = np.asarray(notes.wall_drive)
        baseline = np.linalg.inv(rgbw.SL) @ solution.w_avg
        assert np.all(wall >= -1e-12) and np.all(wall <= baseline.max() * (1 + 1e-9))
        # The light on the white patch: luminance kept, chromaticity within 2 ΔE2000 (colour).
        fixture = rgbw.fixtures[0]
        beta = stage_beta(rgbw)
        white0 = rgbw.SRL[18] @ baseline / beta
        white = rgbw.SRL[18] @ wall / beta + fixture.per_unit_drive[18] @ drives
        xyz0, xyz1 = xyz @ white0, xyz @ white
        assert xyz1[1] == pytest.approx(xyz0[1], rel=1e-4)
        ref = colour.XYZ_to_xy(xyz0)
        lab0 = colour.XYZ_to_Lab(xyz0 / xyz0[1], ref)
        lab1 = colour.XYZ_to_Lab(xyz1 / xyz1[1], ref)
        # The joint method's white-point limit, which the drive solve shares.
        assert colour.delta_E(lab0, lab1, method="CIE 2000") <= DEFAULT_MAX_DELTA_E + 1e-5
        assert notes.error_with_fixtures < notes.error_wall_only


def test_n_stays_exact_for_the_calibrated_wall(solved, rgbw):
    for name in ("d65", "incandescent"):
        s = solved[name]
        assert np.allclose(s.Q @ rgbw.SL @ s.N, np.eye(3), atol=1e-12)
        # M lights with the solved wall drive for the average light.
        assert np.allclose(s.M @ s.w_avg, s.diagnostics.fixtures.wall_drive, rtol=1e-12)


def test_fixtures_lower_held_out_error_by_40_percent_in_a_broadband_scene(stage, rgbw, solved):
    # Ground truth: 190 reflectances not on the chart under the light the stage really emits.
    refl = held_out_reflectances()["rawtoaces"]
    _, spectra = fixture_spectra(stage, "rgbw")
    for name in ("d65", "incandescent"):
        with_f = solved[name]
        wall = solve_environment(
            rgbw, rgbw.environment(name), method="least-squares", fixtures=False
        )
        drives = np.array(
            [with_f.fixtures["rgbw"].drive[c] for c in with_f.fixtures["rgbw"].channels]
        )
        de_f = held_out_errors(
            stage, name, M=with_f.M, w_avg=with_f.w_avg, Q=with_f.Q, reflectances=refl,
            extra_emission=spectra @ drives,
        ).delta_E_2000.mean()  # fmt: skip
        de_w = held_out_errors(
            stage, name, M=wall.M, w_avg=wall.w_avg, Q=wall.Q, reflectances=refl
        ).delta_E_2000.mean()
        # The bound: at least 40 % lower in broadband scenes.
        assert de_f <= 0.6 * de_w, (name, de_w, de_f)


def test_fixtures_that_add_nothing_stay_off(stage):
    # A fixture whose channels are the wall's own LEDs cannot change the light's spectrum.
    base = simulate_measurements(["d65"], stage=stage)
    same = Fixture("rgb", ("red", "green", "blue"), 1.0, np.moveaxis(base.SRL, 2, 0) / stage.beta)
    m = dataclasses.replace(base, fixtures=(same,))
    s = solve_environment(m, m.environments[0], method="least-squares")
    wall = solve_environment(m, m.environments[0], method="least-squares", fixtures=False)
    assert not s.diagnostics.fixtures.applied
    assert all(v == 0.0 for v in s.fixtures["rgb"].drive.values())
    assert np.array_equal(s.M, wall.M) and np.array_equal(s.Q, wall.Q)


def test_without_a_fixtures_section_nothing_changes(stage):
    m = simulate_measurements(["d65"], stage=stage)
    a = solve_environment(m, m.environments[0], fixtures=True)
    b = solve_environment(m, m.environments[0], fixtures=False)
    assert solution_to_json(a) == solution_to_json(b)
    assert "fixtures" not in json.loads(solution_to_json(a))


def test_joint_with_fixtures_is_refused_in_one_line(rgbw):
    with pytest.raises(InputError, match="joint"):
        solve_environment(rgbw, rgbw.environments[0], method="joint")


def test_drive_solve_without_luminance_keeps_the_wall():
    A = np.zeros((24, 3, 4))
    problem = DriveProblem(A, np.ones((24, 3)), np.ones(24), np.zeros(4), np.ones(4), np.eye(3))
    result = solve_fixture_drives(problem)
    assert not result.applied and np.all(np.isfinite(result.drive))


def test_dmx_values_closed_form():
    for level in (0.0, 0.25, 0.5, 0.999, 1.0):
        v = dmx_values(level)
        assert v["dmx8"] == round(level * 255)
        assert v["dmx16"] == round(level * 65535)
        assert v["dmx16_coarse"] * 256 + v["dmx16_fine"] == v["dmx16"]
    assert dmx_values(1.7)["dmx16"] == 65535 and dmx_values(-1)["dmx8"] == 0


def test_dmx_rows_keep_channel_order_and_scale_by_max_drive():
    block = FixtureDrive(("white", "red"), {"red": 0.5, "white": 1.0}, max_drive=2.0)
    rows = dmx_rows("key", block)
    assert [r["channel"] for r in rows] == ["white", "red"]
    assert [r["level"] for r in rows] == [0.5, 0.25]


def test_content_matrix_maps_the_average_light_to_the_drives():
    u, w = np.array([0.1, 0.3, 0.05, 0.6]), np.array([0.8, 1.0, 0.6])
    m = content_matrix(u, w, 1.0)
    K = np.array(m["matrix"])
    assert K.shape == (4, 3) and np.allclose(K @ w, u, rtol=1e-12)
    assert m["max_content_scale"] == pytest.approx(1.0 / 0.6)


def test_cli_solve_and_export_lights(tmp_path, stage, capsys):
    m = with_simulated_fixtures(simulate_measurements(["d65"], stage=stage), stage, ["rgbacl"])
    patch = DmxPatch(universe=3, address=101, mode="16-bit")
    m = dataclasses.replace(
        m, fixtures=tuple(dataclasses.replace(f, dmx=patch) for f in m.fixtures)
    )
    path = tmp_path / "stage.yaml"
    save_measurements(m, path)
    assert (
        main(["solve", str(path), "--out", str(tmp_path / "calib"), "--method", "least-squares"])
        == 0
    )
    out = capsys.readouterr().out
    assert "fixtures, d65: rgbacl" in out
    assert main(["export", str(tmp_path / "calib" / "d65"), "--target", "lights"]) == 0
    folder = tmp_path / "calib" / "d65" / "exports" / "lights"
    document = json.loads((folder / "lights.json").read_text())
    solution = load_solution(tmp_path / "calib" / "d65")
    channels = document["fixtures"][0]["channels"]
    assert [c["channel"] for c in channels] == list(solution.fixtures["rgbacl"].channels)
    for row in channels:
        assert row["drive"] == pytest.approx(solution.fixtures["rgbacl"].drive[row["channel"]])
    csv_lines = (folder / "lights.csv").read_text().splitlines()
    assert len(csv_lines) == 1 + len(channels)
    # the patch: universe, mode and two slots per channel from the start address
    assert document["fixtures"][0]["dmx"] == {"universe": 3, "address": 101, "mode": "16-bit"}
    assert csv_lines[0].startswith(
        "fixture,channel_index,channel,universe,mode,address,fine_address"
    )
    assert [row["address"] for row in channels] == [101 + 2 * i for i in range(len(channels))]
    assert all(
        row["fine_address"] == row["address"] + 1 and row["universe"] == 3 for row in channels
    )
    assert main(["report", str(tmp_path / "calib" / "d65")]) == 0
    html = next((tmp_path / "calib").rglob("index.html")).read_text()
    assert "fixture rgbacl" in html and "error Q cannot remove" in html


def test_export_lights_without_fixtures_says_why(tmp_path, stage, capsys):
    m = simulate_measurements(["d65"], stage=stage)
    path = tmp_path / "stage.yaml"
    save_measurements(m, path)
    assert main(["solve", str(path), "--out", str(tmp_path / "calib")]) == 0
    capsys.readouterr()
    assert main(["export", str(tmp_path / "calib" / "d65"), "--target", "lights"]) == 2
    err = capsys.readouterr().err
    assert "no fixtures" in err and err.count("\n") == 1
