"""``solution.json`` (ocio_vp.formats.solution): the diagnostics block keeps its keys and order,
and a file round-trips byte for byte, including an older file's missing or unknown keys.

Independent source: the JSON text itself (``json`` from the standard library)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import make_measurements_dict

from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.formats.solution import Diagnostics, load_solution, solution_to_json
from ocio_vp.model.correction import MAX_CONDITION_INVERSE, MatrixCorrection
from ocio_vp.pipeline import solve_environment

#: The ``diagnostics`` keys of format ocio-vp/solution v1, in file order (the contract).
DIAGNOSTICS_KEYS = [
    "white_patch", "cond_SL", "cond_Q", "rank_Q", "N_solved", "N_reason",
    "max_condition_q_for_N", "lit_chart_error_baseline", "lit_chart_error", "residual_rms",
    "displayed_chart_error_baseline", "displayed_chart_error", "out_of_frustum_drive",
    "method_notes", "warnings", "charts", "model", "model_reason", "rank_target",
    "cross_validated_error", "residuals_per_patch", "out_of_frustum_negative_channels",
    "lit_chart_error_clipped_drive", "lit_chart_error_baseline_clipped_drive",
    "charts_clipped_drive", "in_frustum_drive_range", "black_level_bounce",
    "clipped_patches", "N_equals_M", "identity_check", "patch_screening", "excluded_patches",
    "model_description", "extrapolation",
]  # fmt: skip


@pytest.fixture(scope="module")
def solution():
    m = measurements_from_dict(make_measurements_dict(environments=1), source="m.yaml")
    return solve_environment(m, m.environments[0])


def test_a_solve_writes_every_diagnostics_key_in_order(solution):
    assert isinstance(solution.diagnostics, Diagnostics)
    assert list(solution.diagnostics) == DIAGNOSTICS_KEYS
    assert list(json.loads(solution_to_json(solution))["diagnostics"]) == DIAGNOSTICS_KEYS
    assert solution.diagnostics["cond_Q"] == solution.diagnostics.cond_Q
    np.testing.assert_array_equal(
        solution.diagnostics["out_of_frustum_drive"], solution.M @ solution.w_avg
    )


def test_solution_json_round_trips_byte_for_byte(solution, tmp_path):
    text = solution_to_json(solution)
    (tmp_path / "solution.json").write_text(text)
    loaded = load_solution(tmp_path)
    assert isinstance(loaded.diagnostics, Diagnostics)
    assert solution_to_json(loaded) == text


def test_an_older_file_keeps_its_keys(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    del data["diagnostics"]["model"]
    data["diagnostics"]["retired_number"] = 3.5
    (tmp_path / "solution.json").write_text(json.dumps(data))
    d = load_solution(tmp_path).diagnostics
    assert "model" not in d and d.get("model", "fallback") == "fallback"
    with pytest.raises(KeyError):
        d["model"]
    assert d["retired_number"] == 3.5
    assert (
        json.loads(solution_to_json(load_solution(tmp_path)))["diagnostics"] == data["diagnostics"]
    )


def test_diagnostics_that_are_not_a_mapping_are_a_clear_error(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    data["diagnostics"] = [1, 2]
    (tmp_path / "solution.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match="diagnostics: expected a mapping"):
        load_solution(tmp_path)


# --- Q is derived from the post-correction: one truth -------------------------------------


def _write(data: dict, folder) -> None:
    folder.mkdir(exist_ok=True)
    (folder / "solution.json").write_text(json.dumps(data))


def test_q_is_the_post_corrections_matrix(solution):
    data = json.loads(solution_to_json(solution))
    assert solution.Q is solution.correction.matrix
    assert data["Q"] == data["post_correction"]["parameters"]["Q"]


def test_an_edited_q_is_refused_in_one_line_with_exit_2(solution, tmp_path, capsys):
    from ocio_vp.cli import main

    data = json.loads(solution_to_json(solution))
    data["Q"][0][0] *= 1 + 1e-6  # far below anything a person sees, far above JSON's rounding
    env = tmp_path / "env"
    _write(data, env)
    capsys.readouterr()
    assert main(["export", str(env), "--target", "nuke"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert f"{env / 'solution.json'}: Q: differs from post_correction's matrix" in err[0]
    assert not (env / "exports").exists()


def test_q_within_json_rounding_of_its_post_correction_loads(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    Q = np.array(data["Q"])
    data["Q"] = (Q * (1 + 1e-12)).tolist()  # e.g. a tool that rewrote the file in float32-free JSON
    _write(data, tmp_path)
    loaded = load_solution(tmp_path)
    np.testing.assert_array_equal(loaded.Q, np.array(data["post_correction"]["parameters"]["Q"]))


def test_a_file_without_a_post_correction_block_loads_as_its_q(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    del data["post_correction"]
    data["Q"][0][0] += 0.01  # nothing to disagree with: Q is the matrix the old file means
    _write(data, tmp_path)
    loaded = load_solution(tmp_path)
    assert isinstance(loaded.correction, MatrixCorrection)
    np.testing.assert_array_equal(loaded.Q, np.array(data["Q"]))
    written = json.loads(solution_to_json(loaded))
    assert written["Q"] == data["Q"]  # the key and its meaning unchanged for readers
    assert written["post_correction"]["parameters"]["Q"] == data["Q"]


@pytest.mark.parametrize("cond", [999.0, 1001.0])
def test_invertibility_is_decided_once_by_the_model(solution, cond):
    import dataclasses

    import PyOpenColorIO as OCIO

    from ocio_vp.calibration.equations import solve_N
    from ocio_vp.ocio.config import post_correction_transforms

    rotation = np.linalg.qr(np.arange(1.0, 10.0).reshape(3, 3) + np.eye(3))[0]
    Q = rotation @ np.diag([1.0, 0.5, 1.0 / cond]) @ rotation.T
    assert np.linalg.cond(Q) == pytest.approx(cond)
    correction = MatrixCorrection(Q)
    invertible = cond <= MAX_CONDITION_INVERSE
    assert correction.invertible is invertible
    # N (the calibration) and the config's inverse direction ask the same rule
    assert (solve_N(np.eye(3), Q)[0] is not None) is invertible
    _, inverse, note = post_correction_transforms(
        dataclasses.replace(solution, post_correction=correction)
    )
    cpu = OCIO.Config.CreateRaw().getProcessor(inverse).getDefaultCPUProcessor()
    columns = np.array([cpu.applyRGB([float(v) for v in e]) for e in np.eye(3)]).T
    if invertible:
        assert note == ""
        np.testing.assert_allclose(columns, np.linalg.inv(Q), rtol=1e-5, atol=1e-3)
    else:
        assert "cannot be inverted" in note
        # the bounded stand-in: gain at most MAX_CONDITION_INVERSE / sigma_max
        assert np.linalg.norm(columns, 2) <= MAX_CONDITION_INVERSE * 1.0001
        np.testing.assert_allclose(columns @ Q @ columns, columns, atol=1e-5)
