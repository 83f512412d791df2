"""``solution.json`` (ocio_vp.formats.solution): the diagnostics block keeps its keys and order,
and a file round-trips byte for byte, including an older file's missing or unknown keys.

Independent source: the JSON text itself (``json`` from the standard library)."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping

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
    "model_description", "extrapolation", "skin",
    "assumed",  # the test file gives no stage.white_patch: what the solve assumed is stated
]  # fmt: skip


@pytest.fixture(scope="module")
def solution():
    m = measurements_from_dict(make_measurements_dict(environments=1), source="m.yaml")
    return solve_environment(m, m.environments[0])


def test_a_solve_writes_every_diagnostics_key_in_order(solution):
    assert isinstance(solution.diagnostics, Diagnostics)
    assert not isinstance(solution.diagnostics, Mapping)  # read by attribute, never by string
    assert list(solution.diagnostics.to_dict()) == DIAGNOSTICS_KEYS
    assert list(json.loads(solution_to_json(solution))["diagnostics"]) == DIAGNOSTICS_KEYS
    np.testing.assert_array_equal(
        solution.diagnostics.out_of_frustum_drive, solution.M @ solution.w_avg
    )


def _types(value):
    """The type tree of a record: the class of every field, nested records and arrays'
    dtype and shape included."""
    if dataclasses.is_dataclass(value):
        return (
            type(value),
            {
                f.name: _types(getattr(value, f.name))
                for f in dataclasses.fields(value)
                if f.name != "present"
            },
        )
    if isinstance(value, np.ndarray):
        return (np.ndarray, value.dtype, value.shape)
    if isinstance(value, (list, tuple)):
        return (type(value), [_types(v) for v in value])
    if isinstance(value, dict):
        return (dict, {k: _types(v) for k, v in value.items()})
    return float if isinstance(value, np.floating) else type(value)


def test_diagnostics_have_the_same_types_and_values_after_a_load(solution, tmp_path):
    (tmp_path / "solution.json").write_text(solution_to_json(solution))
    loaded = load_solution(tmp_path).diagnostics
    fresh = solution.diagnostics
    assert _types(loaded) == _types(fresh)
    assert isinstance(loaded.charts.lit_corrected, np.ndarray)
    assert loaded.charts.lit_corrected.dtype == np.float64
    for name in ("lit_chart_error", "cross_validated_error", "residuals_per_patch"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(fresh, name))
    assert loaded.extrapolation == fresh.extrapolation
    assert loaded.in_frustum_drive_range == fresh.in_frustum_drive_range


def test_a_malformed_diagnostics_value_names_its_key(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    data["diagnostics"]["charts"]["target"][3] = "grey"
    (tmp_path / "solution.json").write_text(json.dumps(data))
    with pytest.raises(
        InputError, match=r"diagnostics\.charts\.target: expected a list of numbers"
    ):
        load_solution(tmp_path)


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
    assert d.model is None and "model" not in d.to_dict()
    assert d.extra == {"retired_number": 3.5}
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
    from ocio_vp.ocio.description import ocio_transform

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
    processor = OCIO.Config.CreateRaw().getProcessor(ocio_transform(inverse))
    cpu = processor.getDefaultCPUProcessor()
    columns = np.array([cpu.applyRGB([float(v) for v in e]) for e in np.eye(3)]).T
    if invertible:
        assert note == ""
        np.testing.assert_allclose(columns, np.linalg.inv(Q), rtol=1e-5, atol=1e-3)
    else:
        assert "cannot be inverted" in note
        # the bounded stand-in: gain at most MAX_CONDITION_INVERSE / sigma_max
        assert np.linalg.norm(columns, 2) <= MAX_CONDITION_INVERSE * 1.0001
        np.testing.assert_allclose(columns @ Q @ columns, columns, atol=1e-5)


def test_white_patch_0_is_honoured_after_a_solve_and_a_load(tmp_path):
    """The same chart with its white patch moved to index 0: every figure made relative to the
    white patch is the same as with it at 18 (Fig. 11 does not depend on the order)."""
    from ocio_vp.patterns.validation import content_scale
    from ocio_vp.report.data import infer_white_patch

    data = make_measurements_dict(environments=1)
    moved = json.loads(json.dumps(data))
    moved["stage"]["white_patch"] = 0
    for c in ("red", "green", "blue"):
        moved["lit_chart"][c] = np.roll(data["lit_chart"][c], -18, axis=0).tolist()
    env = moved["environments"][0]
    env["target_chart"] = np.roll(env["target_chart"], -18, axis=0).tolist()
    solved = []
    for document in (data, moved):
        m = measurements_from_dict(document, source="m.yaml")
        solved.append(solve_environment(m, m.environments[0], method="least-squares"))
    at_18, at_0 = solved
    assert at_0.diagnostics.white_patch == 0
    np.testing.assert_allclose(
        at_0.diagnostics.lit_chart_error, at_18.diagnostics.lit_chart_error, rtol=1e-9
    )
    (tmp_path / "solution.json").write_text(solution_to_json(at_0))
    loaded = load_solution(tmp_path)
    assert loaded.diagnostics.white_patch == 0
    target = loaded.diagnostics.charts.target
    assert content_scale(loaded, target) == content_scale(at_18, at_18.diagnostics.charts.target)
    charts = loaded.diagnostics.charts.to_dict()
    assert infer_white_patch(loaded, charts) == 0


def test_no_module_reads_a_solve_result_by_string():
    """``solution.diagnostics["..."]``, ``solution.ocio["..."]`` and their ``.get("...")`` are
    gone from the package: both blocks are typed records (read by attribute, checked by type
    checkers)."""
    import ast
    from pathlib import Path

    package = Path(__file__).resolve().parents[1] / "ocio_vp"
    found = []
    for path in sorted(package.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            target = None
            if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
                target = node.value
            elif (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "get"
            ):
                target = node.func.value
            while isinstance(target, ast.Attribute):  # solution.diagnostics.charts[...] too
                if target.attr in ("diagnostics", "ocio"):
                    found.append(f"{path.relative_to(package)}:{node.lineno}")
                    break
                target = target.value
    assert found == []


def _lamp() -> dict:
    return {
        "channels": ["red", "blue"],
        "drive": {"red": 0.5, "blue": 0.25},
        "dmx": {"universe": 1, "address": 10, "mode": "16-bit"},
    }


CHANNELS = "fixtures.lamp: expected channels and a drive for each"
DMX = r"fixtures.lamp.dmx: expected universe, address \(integers\) and mode \(8-bit or 16-bit\)"


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda f: f["drive"].pop("blue"), CHANNELS),
        (lambda f: f.update(channels="red"), CHANNELS),
        (lambda f: f["drive"].update(blue="inf"), "fixtures.lamp: expected finite drives"),
        (lambda f: f["dmx"].update(mode="RGBW"), DMX),
        (lambda f: f["dmx"].update(universe="1"), DMX),
        (lambda f: f["dmx"].update(address=10.0), DMX),
        (lambda f: f.update(dmx=[1, 10, "8-bit"]), DMX),
    ],
    ids=["missing-drive", "channels-text", "inf-drive", "mode", "universe", "address", "dmx-list"],
)
def test_a_malformed_fixture_block_says_what_it_expects(solution, tmp_path, edit, message):
    data = json.loads(solution_to_json(solution))
    data["fixtures"] = {"lamp": _lamp()}
    edit(data["fixtures"]["lamp"])
    (tmp_path / "solution.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match=f"solution.json: {message}$"):
        load_solution(tmp_path)


def test_a_well_formed_fixture_block_loads(solution, tmp_path):
    data = json.loads(solution_to_json(solution))
    data["fixtures"] = {"lamp": _lamp()}
    (tmp_path / "solution.json").write_text(json.dumps(data))
    lamp = load_solution(tmp_path).fixtures["lamp"]
    assert lamp.channels == ("red", "blue") and dict(lamp.drive) == {"red": 0.5, "blue": 0.25}
    assert (lamp.dmx.universe, lamp.dmx.address, lamp.dmx.mode) == (1, 10, "16-bit")


def test_a_stale_export_of_a_solution_that_no_longer_loads_names_its_model(solution, tmp_path):
    """The model of an edited solution.json is read from the file as written."""
    from ocio_vp.formats.provenance import SOURCE_FILE, stale_outputs

    data = json.loads(solution_to_json(solution))
    data["Q"][0][0] *= 1 + 1e-6  # refused on load (see above)
    env = tmp_path / "env"
    _write(data, env)
    record = {"model": "white-preserving", "solution_sha256": "an earlier solution"}
    (env / "exports" / "nuke").mkdir(parents=True)
    (env / "exports" / "nuke" / SOURCE_FILE).write_text(json.dumps(record))
    [line] = stale_outputs(tmp_path, ["env"])
    assert data["diagnostics"]["model"] and data["diagnostics"]["model"] != "white-preserving"
    assert f"(model white-preserving, now {data['diagnostics']['model']})" in line
    data["diagnostics"]["model"], data["method"] = None, "a-method"  # an older file: its method
    _write(data, env)
    assert "now a-method)" in stale_outputs(tmp_path, ["env"])[0]
