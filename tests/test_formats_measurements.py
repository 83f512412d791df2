"""The measurements file: round trips and the data model."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make_measurements_dict

from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import (
    load_measurements,
    measurements_from_dict,
    measurements_to_dict,
    save_measurements,
)


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_save_load_round_trip_is_exact(tmp_path, suffix) -> None:
    original = measurements_from_dict(make_measurements_dict(seed=2), source="mem")
    path = tmp_path / f"stage{suffix}"
    save_measurements(original, path)
    loaded = load_measurements(path)
    np.testing.assert_array_equal(loaded.SL, original.SL)  # floats round-trip bit for bit
    np.testing.assert_array_equal(loaded.SRL, original.SRL)
    for a, b in zip(loaded.environments, original.environments, strict=True):
        assert a.name == b.name
        np.testing.assert_array_equal(a.target_chart, b.target_chart)
        np.testing.assert_array_equal(a.black_level, b.black_level)
    assert measurements_to_dict(loaded) == measurements_to_dict(original)
    assert len(loaded.sha256) == 64


def test_layout_of_SL_and_SRL() -> None:
    data = make_measurements_dict()
    m = measurements_from_dict(data)
    # [SL]: camera channels along rows, LED channels along columns (paper, Section 3.3).
    np.testing.assert_array_equal(m.SL[:, 1], data["primaries"]["green"])
    np.testing.assert_array_equal(m.SRL[5][:, 2], data["lit_chart"]["blue"][5])
    assert m.n_patches == 24


def test_explicit_beta_and_defaults() -> None:
    data = make_measurements_dict()
    del data["stage"]["calibration_panel"]
    data["stage"]["beta"] = 0.311
    m = measurements_from_dict(data)
    assert m.stage.beta == 0.311 and m.stage.panel is None
    assert (m.stage.white_patch, m.stage.white_reflectance) == (18, 0.9)


def test_beta_above_one_rejected() -> None:
    data = make_measurements_dict()
    data["stage"]["beta"] = 1.5
    with pytest.raises(InputError, match=r"stage\.beta: a form factor is at most 1"):
        measurements_from_dict(data, source="s.yaml")


def test_unknown_key_suggests_the_right_one() -> None:
    data = make_measurements_dict()
    data["environments"][0]["blacklevel"] = [0, 0, 0]
    with pytest.raises(InputError, match="did you mean 'black_level'"):
        measurements_from_dict(data)


def test_misspelt_required_key_is_named_as_a_typo() -> None:
    """A misspelt required key is reported as unknown (with the suggestion), not only missing."""
    data = make_measurements_dict()
    data["primaries_"] = data.pop("primaries")
    with pytest.raises(InputError, match=r"primaries_: unknown key \(did you mean 'primaries'\?\)"):
        measurements_from_dict(data)
    del data["primaries_"]
    with pytest.raises(InputError, match="missing required key 'primaries'"):
        measurements_from_dict(data)


def test_bool_is_not_a_number() -> None:
    data = make_measurements_dict()
    data["primaries"]["red"][0] = True
    with pytest.raises(InputError, match=r"primaries\.red\[0\]: expected a number"):
        measurements_from_dict(data)


def test_load_solution_reports_missing_keys(tmp_path) -> None:
    from ocio_vp.formats.solution import load_solution

    (tmp_path / "solution.json").write_text('{"format": "ocio-vp/solution", "version": 1}')
    with pytest.raises(InputError, match="missing required key 'stage'"):
        load_solution(tmp_path)


def test_priority_and_skin_patches_round_trip(tmp_path) -> None:
    data = make_measurements_dict()
    data["stage"]["skin_patches"] = [0, 1]
    data["environments"][0]["priority"] = "skin"
    m = measurements_from_dict(data)
    assert m.stage.skin_patches == (0, 1)
    assert [e.priority for e in m.environments] == ["skin", None]
    save_measurements(m, tmp_path / "m.yaml")
    again = load_measurements(tmp_path / "m.yaml")
    assert again.stage.skin_patches == (0, 1) and again.environments[0].priority == "skin"


@pytest.mark.parametrize(
    ("where", "value", "message"),
    [
        ("priority", "faces", r"environments\[0\]\.priority: expected one of general, skin"),
        ("skin_patches", [0, 24], r"stage\.skin_patches\[1\]: index 24 is outside the 24"),
        ("skin_patches", [1, 1], r"stage\.skin_patches: names a patch twice"),
        ("skin_patches", "0,1", r"stage\.skin_patches: expected a list of patch indices"),
    ],
)
def test_bad_priority_or_skin_patches_are_refused_on_one_line(where, value, message) -> None:
    data = make_measurements_dict()
    if where == "priority":
        data["environments"][0]["priority"] = value
    else:
        data["stage"]["skin_patches"] = value
    with pytest.raises(InputError, match=message) as error:
        measurements_from_dict(data, source="m.yaml")
    assert "\n" not in str(error.value)
