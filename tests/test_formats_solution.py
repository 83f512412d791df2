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
    "model_description", "extrapolation", "skin",
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
