"""ocio_vp.exports.panels: the Unreal mapping of a stage of several panel types (per-viewport
and per-node OCIO profiles, property names as in Epic's nDisplay API reference)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from ocio_vp.errors import InputError
from ocio_vp.exports import export_solutions
from ocio_vp.exports.panels import panel_assignments, panel_notes
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements


@pytest.fixture(scope="module")
def solved(panel_stage_and_measurements, tmp_path_factory):
    _, m = panel_stage_and_measurements
    out = tmp_path_factory.mktemp("calib")
    write_solutions(solve_measurements(m, method="least-squares"), out)
    return out


@pytest.fixture(scope="module")
def exported(solved):
    out = solved
    export_solutions([out / "overcast"], targets=("unreal",), out=out / "exports")
    folder = out / "exports" / "overcast" / "unreal"
    return json.loads((folder / "unreal_ocio.json").read_text()), (folder / "UNREAL.md").read_text()


def test_the_ceiling_is_assigned_per_viewport(exported):
    mapping, _ = exported
    asset = mapping["configuration_asset"]
    assert "LED Ceiling - Outer Frustum" in asset["desired_color_spaces"]
    assert {"display": "LED Wall", "view": "Ceiling Outer Frustum"} in asset[
        "desired_display_views"
    ]
    ceiling = [a for a in mapping["assignments"] if a.get("role") == "ceiling.out_of_frustum"]
    assert len(ceiling) == 1
    profile = ceiling[0]
    # FDisplayClusterConfigurationICVFX_ViewportOCIO.PerViewportOCIOProfiles holds
    # FDisplayClusterConfigurationOCIOProfile (bIsEnabled, ApplyOCIOToObjects, ColorConfiguration).
    assert profile["property"] == "StageSettings.ViewportOCIO.PerViewportOCIOProfiles"
    assert set(profile["append"]) == {
        "bIsEnabled",
        "ApplyOCIOToObjects",
        "ColorConfiguration.SourceColorSpace",
        "ColorConfiguration.DestinationColorSpace",
    }
    assert profile["destination"] == "LED Ceiling - Outer Frustum"
    # The wall keeps the stage-wide slots; no inner frustum for an out-of-frustum ceiling.
    roles = [a["role"] for a in mapping["assignments"]]
    assert roles.count("in_frustum") == 1 and "ceiling.in_frustum" not in roles


def test_unreal_md_says_where_the_ceiling_goes(exported):
    _, text = exported
    assert "Per-Viewport OCIO Overrides" in text and "`LED Ceiling - Outer Frustum`" in text
    assert "Per-Node" not in text  # the ceiling is never in frame


def test_a_stage_of_one_panel_type_has_no_profiles(tmp_path):
    from conftest import make_measurements_dict

    from ocio_vp.formats.measurements import measurements_from_dict

    m = measurements_from_dict(make_measurements_dict(environments=1))
    write_solutions(solve_measurements(m, method="least-squares"), tmp_path / "c")
    export_solutions([tmp_path / "c" / "env_0"], targets=("unreal",), out=tmp_path / "e")
    mapping = json.loads((tmp_path / "e" / "env_0" / "unreal" / "unreal_ocio.json").read_text())
    assert "panel_types_checked" not in mapping
    assert not any("PerViewport" in a["property"] for a in mapping["assignments"])


def test_a_panel_type_missing_a_name_is_refused_naming_the_key(solved, tmp_path):
    """Not left out of the export: the stage engineer would miss a panel type's profile."""
    folder = tmp_path / "overcast"
    folder.mkdir()
    for path in (solved / "overcast").iterdir():
        if path.is_file():
            (folder / path.name).write_bytes(path.read_bytes())
    data = json.loads((folder / "solution.json").read_text())
    del data["panels"]["ceiling"]["ocio"]["out_of_frustum"]
    (folder / "solution.json").write_text(json.dumps(data))
    with pytest.raises(InputError) as error:
        export_solutions([folder], targets=("unreal",), out=tmp_path / "e")
    where = f"{folder / 'solution.json'}: panels.ceiling.ocio.out_of_frustum: expected the name"
    assert where in str(error.value)
    assert not (tmp_path / "e" / "overcast").exists()


@pytest.mark.parametrize("role", ["in_frustum", "out_of_frustum"])
def test_an_in_frustum_type_needs_both_names(solved, role):
    solution = load_solution(solved / "overcast")
    ceiling = solution.panels["ceiling"]
    names = dataclasses.replace(ceiling.ocio, in_frustum="LED Ceiling - Inner Frustum")
    panel = dataclasses.replace(
        ceiling, in_frustum=True, ocio=dataclasses.replace(names, **{role: None})
    )
    solution = dataclasses.replace(solution, panels={**solution.panels, "ceiling": panel})
    for call in (
        lambda: panel_assignments(solution, "ACEScg", "x/solution.json"),
        lambda: panel_notes(solution, "x/solution.json"),
    ):
        with pytest.raises(InputError, match=f"ceiling panels' {role} colour space") as error:
            call()
        assert (error.value.key, error.value.source) == (
            f"panels.ceiling.ocio.{role}",
            "x/solution.json",
        )
    complete = dataclasses.replace(panel, ocio=names)
    solution = dataclasses.replace(solution, panels={**solution.panels, "ceiling": complete})
    roles = [a["role"] for a in panel_assignments(solution, "ACEScg").assignments]
    assert roles == ["ceiling.out_of_frustum", "ceiling.in_frustum"]
