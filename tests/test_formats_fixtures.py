"""ocio_vp.formats.fixtures: the optional fixtures section of a measurements file."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import measurements_from_dict, measurements_to_dict
from ocio_vp.simulator.fixtures import with_simulated_fixtures
from ocio_vp.simulator.stage import paper_stage, simulate_measurements


@pytest.fixture(scope="module")
def document():
    stage = paper_stage()
    m = with_simulated_fixtures(simulate_measurements(["d65"], stage=stage), stage, ["rgbw"])
    return measurements_to_dict(m)


def test_round_trip(document):
    m = measurements_from_dict(copy.deepcopy(document))
    assert measurements_to_dict(m) == document
    f = m.fixtures[0]
    assert f.channels == ("red", "green", "blue", "white") and f.lit_chart.shape == (4, 24, 3)
    assert np.array_equal(f.per_unit_drive[:, :, 3], f.lit_chart[3] / f.reference_drive)


def _broken(document, edit):
    data = copy.deepcopy(document)
    edit(data["fixtures"][0])
    return data


CASES = [
    (
        lambda f: f["lit_chart"].pop("white"),
        "fixtures[0].lit_chart",
        "missing required key 'white'",
    ),
    (
        lambda f: f["lit_chart"].update(amber=f["lit_chart"]["red"]),
        "fixtures[0].lit_chart.amber",
        "unknown key",
    ),
    (
        lambda f: f["lit_chart"]["white"][3].__setitem__(1, -0.5),
        "fixtures[0].lit_chart.white[3][1]",
        ">= 0",
    ),
    (lambda f: f.pop("reference_drive"), "fixtures[0]", "missing required key 'reference_drive'"),
    (lambda f: f.update(reference_drive=0), "fixtures[0].reference_drive", "> 0"),
    (lambda f: f.update(max_drive=-1), "fixtures[0].max_drive", "> 0"),
    (
        lambda f: f["lit_chart"].update(white=f["lit_chart"]["white"][:20]),
        "fixtures[0].lit_chart.white",
        "20 patches",
    ),
    (lambda f: f.update(channels=["red", "red"]), "fixtures[0].channels", "repeat"),
    (lambda f: f.update(channels=[]), "fixtures[0].channels", "non-empty"),
    (lambda f: f.update(name="a/b"), "fixtures[0].name", "unsafe name"),
    (
        lambda f: f["lit_chart"].update(white=[[0, 0, 0]] * 24),
        "fixtures[0].lit_chart.white",
        "black",
    ),
    (
        lambda f: f.update(dmx={"universe": 1, "address": 506, "mode": "16-bit"}),
        "fixtures[0].dmx.address",
        "end at 513, past 512",
    ),
    (
        lambda f: f.update(dmx={"universe": 1, "address": 0, "mode": "8-bit"}),
        "fixtures[0].dmx.address",
        "1..512",
    ),
    (
        lambda f: f.update(dmx={"universe": 1, "address": 1, "mode": "RGBW"}),
        "fixtures[0].dmx.mode",
        "8-bit",
    ),
    (lambda f: f.update(dmx={"universe": 1, "address": 1}), "fixtures[0].dmx", "'mode'"),
]


def test_dmx_patch_round_trips(document):
    data = copy.deepcopy(document)
    data["fixtures"][0]["dmx"] = {"universe": 0, "address": 505, "mode": "16-bit"}  # ends at 512
    m = measurements_from_dict(data)
    assert m.fixtures[0].dmx.address == 505
    assert measurements_to_dict(m)["fixtures"][0]["dmx"] == data["fixtures"][0]["dmx"]


@pytest.mark.parametrize(("edit", "key", "problem"), CASES)
def test_bad_fixture_data_is_one_clear_error(document, edit, key, problem):
    with pytest.raises(InputError) as info:
        measurements_from_dict(_broken(document, edit), source="stage.yaml")
    message = str(info.value)
    assert message.startswith(f"stage.yaml: {key}") and problem in message
    assert "\n" not in message


def test_duplicate_fixture_names(document):
    data = copy.deepcopy(document)
    data["fixtures"].append(copy.deepcopy(data["fixtures"][0]))
    with pytest.raises(InputError, match=r"fixtures\[1\]\.name: fixture name 'rgbw' is used twice"):
        measurements_from_dict(data)


def test_solve_exits_2_with_one_line_on_bad_fixtures(document, tmp_path, capsys):
    path = tmp_path / "stage.yaml"
    path.write_text(yaml.safe_dump(_broken(document, lambda f: f.pop("reference_drive"))))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "fixtures[0]" in err and "reference_drive" in err and err.count("\n") == 0
    assert not (tmp_path / "out").exists()
