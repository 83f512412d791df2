"""Several measurements files, one solve: parts validated alone, merged, conflicts refused."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import check_measurements_part, load_measurements
from ocio_vp.formats.merge import load_measurement_files, merge_measurement_documents


def _write(path, data):
    path.write_text(yaml.safe_dump(data))
    return path


def _split(data):
    wall = {k: data[k] for k in ("format", "version", "stage", "primaries")}
    charts = {k: data[k] for k in ("format", "version", "stage", "lit_chart", "environments")}
    return copy.deepcopy(wall), copy.deepcopy(charts)


def test_wall_and_charts_files_give_the_same_measurements_as_one(tmp_path):
    data = make_measurements_dict()
    wall, charts = _split(data)
    whole = load_measurements(_write(tmp_path / "all.yaml", data))
    merged = load_measurement_files(
        [_write(tmp_path / "wall.yaml", wall), _write(tmp_path / "charts.yaml", charts)]
    )
    np.testing.assert_array_equal(merged.SL, whole.SL)
    np.testing.assert_array_equal(merged.SRL, whole.SRL)
    assert [e.name for e in merged.environments] == [e.name for e in whole.environments]
    assert merged.source == "wall.yaml + charts.yaml" and len(merged.sha256) == 64


def test_environments_join_by_name_and_equal_repeats_are_fine(tmp_path):
    data = make_measurements_dict(environments=3)
    wall, charts = _split(data)
    first, second = copy.deepcopy(charts), copy.deepcopy(charts)
    first["environments"] = charts["environments"][:2]
    second["environments"] = charts["environments"][1:]  # env_1 in both, equal
    merged = merge_measurement_documents([(wall, "w"), (first, "a"), (second, "b")])
    assert [e["name"] for e in merged["environments"]] == ["env_0", "env_1", "env_2"]


def test_a_solve_of_two_files_equals_the_solve_of_one(tmp_path, capsys):
    data = make_measurements_dict(environments=1)
    wall, charts = _split(data)
    paths = [_write(tmp_path / "wall.yaml", wall), _write(tmp_path / "charts.yaml", charts)]
    assert main(["solve", *map(str, paths), "--out", str(tmp_path / "two")]) == 0
    assert (
        main(["solve", str(_write(tmp_path / "one.yaml", data)), "--out", str(tmp_path / "one")])
        == 0
    )
    a = yaml.safe_load((tmp_path / "two" / "env_0" / "solution.json").read_text())
    b = yaml.safe_load((tmp_path / "one" / "env_0" / "solution.json").read_text())
    for key in ("M", "Q", "N", "black_level_offset"):
        np.testing.assert_array_equal(a[key], b[key])


CONFLICTS = {
    "stage key": (lambda w, c: c["stage"].update(name="another-stage"), "stage.name"),
    "section": (
        lambda w, c: c.update(primaries={k: [1.0, 0.1, 0.1] for k in ("red", "green", "blue")}),
        "primaries",
    ),
    "environment": (
        lambda w, c: w.update(environments=[dict(c["environments"][0], w_avg=[1, 1, 1])]),
        "environments 'env_0'",
    ),
}


@pytest.mark.parametrize("case", sorted(CONFLICTS))
def test_a_key_given_twice_with_different_values_is_refused(tmp_path, capsys, monkeypatch, case):
    change, key = CONFLICTS[case]
    wall, charts = _split(make_measurements_dict())
    change(wall, charts)
    # Relative paths: the one-line message shortens long ones (a deep temporary folder).
    monkeypatch.chdir(tmp_path)
    _write(tmp_path / "wall.yaml", wall), _write(tmp_path / "charts.yaml", charts)
    out = tmp_path / "calib"
    assert main(["solve", "wall.yaml", "charts.yaml", "--out", "calib"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert f"{key}: also given in" in err and "wall.yaml" in err and "charts.yaml" in err
    assert not out.exists()


def test_missing_sections_and_bad_parts_name_their_file(tmp_path, capsys):
    wall, charts = _split(make_measurements_dict())
    wall_path = _write(tmp_path / "wall.yaml", wall)
    assert main(["solve", str(wall_path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "missing required key 'lit_chart'" in err and "WALL.yaml CHARTS.yaml" in err
    charts["lit_chart"]["red"][0][0] = -1.0
    bad = _write(tmp_path / "charts.yaml", charts)
    assert main(["solve", str(wall_path), str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "charts.yaml: lit_chart.red[0][0]: expected a number >= 0" in capsys.readouterr().err
    with pytest.raises(InputError, match="holds no measurements"):
        check_measurements_part(
            {"format": "ocio-vp/measurements", "version": 1, "stage": wall["stage"]}
        )
    with pytest.raises(InputError, match="given twice"):
        load_measurement_files([wall_path, wall_path])
