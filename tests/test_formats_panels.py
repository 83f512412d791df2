"""ocio_vp.formats.panels: the optional panels list of a measurements file (several panel types)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import (
    load_measurements,
    measurements_from_dict,
    measurements_to_dict,
    save_measurements,
)
from ocio_vp.formats.panels import PanelRegion, primary_panel


@pytest.fixture(scope="module")
def document(panel_stage_and_measurements):
    return measurements_to_dict(panel_stage_and_measurements[1])


def test_round_trip_through_a_file(document, tmp_path):
    m = measurements_from_dict(copy.deepcopy(document))
    assert measurements_to_dict(m) == document
    save_measurements(m, tmp_path / "stage.yaml")
    again = load_measurements(tmp_path / "stage.yaml")
    assert measurements_to_dict(again) == document
    wall, ceiling = again.panels
    assert (wall.name, wall.in_frustum, ceiling.name, ceiling.in_frustum) == (
        "wall", True, "ceiling", False
    )  # fmt: skip
    # The top-level arrays are the first in-frustum type's (for single-wall readers).
    assert primary_panel(again.panels) is wall
    assert np.array_equal(again.SL, wall.SL) and np.array_equal(again.SRL, wall.SRL)
    env = again.environments[0]
    assert set(env.panel_w_avg) == {"wall", "ceiling"} and set(env.panel_black_level) == {"wall"}
    assert env.w_avg is None and env.black_level is None
    assert ceiling.regions == (PanelRegion(elevation=(40.0, 90.0)),)


def _broken(document, edit):
    data = copy.deepcopy(document)
    edit(data)
    return data


def _rename(data, index, name):
    data["panels"][index]["name"] = name


CASES = [
    # A panel named twice.
    (lambda d: _rename(d, 1, "wall"), "panels[1].name", "duplicate name 'wall' (also panels[0])"),
    # w_avg for an unknown panel type, and a missing one.
    (
        lambda d: d["environments"][0]["w_avg"].update(roof=[0.1, 0.1, 0.1]),
        "environments[0].w_avg.roof",
        "unknown panel type",
    ),
    (
        lambda d: d["environments"][0]["w_avg"].pop("ceiling"),
        "environments[0].w_avg",
        "missing panel type 'ceiling'",
    ),
    (
        lambda d: d["environments"][1]["w_avg"].update(ceilng=d["environments"][1]["w_avg"].pop("ceiling")),
        "environments[1].w_avg.ceilng",
        "did you mean 'ceiling'?",
    ),
    # A file mixing both forms.
    (
        lambda d: d.update(primaries=d["panels"][0]["primaries"]),
        "primaries",
        "a file with panels gives each panel type its own primaries",
    ),
    (
        lambda d: d.update(lit_chart=d["panels"][0]["lit_chart"]),
        "lit_chart",
        "its own primaries, lit_chart and ramps",
    ),
    (
        lambda d: d["stage"].update(beta=0.2),
        "stage.beta",
        "with panels, each panel type gives its own calibration_panel or beta",
    ),
    (
        lambda d: d["environments"][0].update(w_avg=[0.5, 0.5, 0.5]),
        "environments[0].w_avg",
        "with panels, expected a mapping of panel type -> [r, g, b]",
    ),
    # Per-panel rules.
    (
        lambda d: d["environments"][0]["black_level"].update(ceiling=[0.01, 0.01, 0.01]),
        "environments[0].black_level.ceiling",
        "is not an in-frustum panel type",
    ),
    (
        lambda d: [p.update(in_frustum=False) for p in d["panels"]],
        "panels",
        "no panel type has in_frustum: true",
    ),
    (lambda d: d["panels"][1].update(in_frustum="no"), "panels[1].in_frustum", "true or false"),
    (
        lambda d: d["panels"][1]["lit_chart"].update(red=d["panels"][1]["lit_chart"]["red"][:20]),
        "panels[1].lit_chart.red",
        "has 20 patches, expected 24 like panels[0].lit_chart.red",
    ),
    (
        lambda d: d["panels"][1].pop("calibration_panel"),
        "panels[1]",
        "give either calibration_panel",
    ),
    (
        lambda d: d["panels"][1].update(region={"elevation": [30, 90]}),
        "panels[1].region",
        "overlaps panels[0].region (wall)",
    ),
    (
        lambda d: d["panels"][1].update(region={"elevation": [60, 40]}),
        "panels[1].region.elevation",
        "min < max",
    ),
    (lambda d: d["panels"][1].update(encoding="PQ"), "panels[1].encoding", "unknown encoding"),
    (lambda d: d["panels"][1].update(peak_nits=1000), "panels[1].peak_nits", "only with encoding: pq"),
    (lambda d: d.update(panels=[]), "panels", "non-empty list"),
    (
        lambda d: d["panels"][1]["primaries"].update(red=[0, 0, "x"]),
        "panels[1].primaries.red[2]",
        "expected a number",
    ),
    (
        lambda d: d["environments"][0].update(w_avg={"wall": [0, 0, 0], "ceiling": [0, 0, 0]}),
        "environments[0].w_avg",
        "black for every panel type",
    ),
]  # fmt: skip


@pytest.mark.parametrize(("edit", "key", "problem"), CASES)
def test_bad_panels_input_is_one_clear_error(document, edit, key, problem):
    with pytest.raises(InputError) as info:
        measurements_from_dict(_broken(document, edit), source="stage.yaml")
    message = str(info.value)
    assert message.startswith(f"stage.yaml: {key}:"), message
    assert problem in message and "\n" not in message


def test_panel_ramps_errors_name_their_panel(document):
    data = copy.deepcopy(document)
    data["panels"][1]["ramps"] = {"red": {"drive": [0, 1], "camera": [[0, 0, 0], [1, 1, 1]]}}
    with pytest.raises(InputError, match=r"stage\.yaml: panels\[1\]\.ramps"):
        measurements_from_dict(data, source="stage.yaml")


def test_a_file_without_panels_reads_as_before(measurements_dict):
    m = measurements_from_dict(copy.deepcopy(measurements_dict))
    assert m.panels == ()
    written = measurements_to_dict(m)
    assert measurements_to_dict(measurements_from_dict(written)) == written
    keys = ["format", "version", "stage", "primaries", "lit_chart", "environments"]
    assert list(written) == keys  # the file's key order, no panels


def test_solve_refuses_bad_panels_in_one_line(document, tmp_path, capsys):
    path = tmp_path / "stage.yaml"
    path.write_text(yaml.safe_dump(_broken(document, lambda d: _rename(d, 1, "wall"))))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "panels[1].name: duplicate name 'wall'" in err
    assert not (tmp_path / "out").exists()


def test_without_w_avg_several_panel_types_need_an_hdri(document, tmp_path, capsys):
    data = copy.deepcopy(document)
    del data["environments"][0]["w_avg"]
    path = tmp_path / "stage.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "environments[0].w_avg: with several panel types" in err


def test_a_file_with_panels_is_solved_alone(document, tmp_path, capsys):
    # A panels file holds the whole stage; merging it with another file is refused in one
    # line, and on its own it solves (the multi-file solve loads it whole).
    path = tmp_path / "panels.yaml"
    path.write_text(yaml.safe_dump(document))
    other = tmp_path / "charts.yaml"
    other.write_text(yaml.safe_dump({k: document[k] for k in ("format", "version", "stage")}))
    assert main(["solve", str(path), str(other), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "panels: a measurements file with panels holds the whole stage" in err
    assert err.count("\n") == 1 and not (tmp_path / "o").exists()
