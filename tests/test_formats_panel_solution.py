"""ocio_vp.formats.panel_solution: solution.json's panels block, written and read back."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.solution import load_solution, solution_to_json
from ocio_vp.pipeline import solve_environment


@pytest.fixture(scope="module")
def written(panel_stage_and_measurements, tmp_path_factory):
    _, m = panel_stage_and_measurements
    solution = solve_environment(m, m.environments[0], method="least-squares")
    path = tmp_path_factory.mktemp("sol") / "solution.json"
    path.write_text(solution_to_json(solution))
    return solution, path


def test_round_trip(written):
    solution, path = written
    back = load_solution(path)
    for name, panel in solution.panels.items():
        again = back.panels[name]
        assert again.in_frustum == panel.in_frustum and again.share == panel.share
        for key in ("SL", "M", "w_avg", "drive"):
            assert np.array_equal(getattr(again, key), getattr(panel, key))
    assert back.panels["ceiling"].N is None and back.panels["ceiling"].black_level_offset is None
    assert np.array_equal(back.panels["wall"].N, solution.N)
    assert solution_to_json(back) == path.read_text()  # byte for byte


def _edited(path, tmp_path, edit):
    data = json.loads(path.read_text())
    edit(data)
    out = tmp_path / "solution.json"
    out.write_text(json.dumps(data))
    return out


@pytest.mark.parametrize(
    ("edit", "key"),
    [
        (lambda d: d["panels"]["ceiling"].update(M=[[1, 2], [3, 4]]), "panels.ceiling.M"),
        (lambda d: d["panels"]["ceiling"].update(in_frustum="no"), "panels.ceiling"),
        (lambda d: d["panels"]["wall"].update(share=2.0), "panels.wall.share"),
        (lambda d: d["panels"]["wall"].update(in_frustum=False), "panels"),
        (lambda d: d["panels"].update({"a/b": copy.deepcopy(d["panels"]["wall"])}), "panels"),
        (lambda d: d["panels"]["wall"].update(ocio={"in_frustum": 3}), "panels.wall.ocio"),
    ],
)
def test_hand_edited_panels_are_one_clear_error(written, tmp_path, edit, key):
    with pytest.raises(InputError) as info:
        load_solution(_edited(written[1], tmp_path, edit))
    assert f"solution.json: {key}:" in str(info.value) and "\n" not in str(info.value)
