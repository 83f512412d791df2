"""The Unreal editor script: it compiles, and run against a stand-in of the ``unreal`` module
for each engine version it sets only editor properties that Epic's Python API documents for
that struct in that version. Nothing here runs Unreal.

The table below is written from Epic's Python API reference pages
(dev.epicgames.com/documentation/en-us/unreal-engine/python-api/class/<Class>?application_version=V)
and, where the Python page was not at hand, the C++ page of the same struct (the Python name is
the C++ member in snake case): the first version that lists each property as Read-Write.
"""

from __future__ import annotations

import ast
import sys
import types

import pytest
from test_exports_unreal import solve_to

from ocio_vp.exports import export_solutions
from ocio_vp.exports.unreal_script import SCRIPT_FILE

DOCUMENTED = {
    # OpenColorIOConfiguration (5.1 page; ``context`` from 5.5: C++ UOpenColorIOConfiguration 5.5,
    # Python page 5.7)
    ("OpenColorIOConfiguration", "configuration_file"): (5, 1),
    ("OpenColorIOConfiguration", "desired_color_spaces"): (5, 1),
    ("OpenColorIOConfiguration", "desired_display_views"): (5, 1),
    ("OpenColorIOConfiguration", "context"): (5, 5),
    ("FilePath", "file_path"): (5, 1),
    # OpenColorIOColorSpace: Read-Only in 5.1, Read-Write with a constructor from 5.3
    ("OpenColorIOColorSpace", "color_space_name"): (5, 3),
    ("OpenColorIOColorSpace", "color_space_index"): (5, 3),
    ("OpenColorIOColorSpace", "family_name"): (5, 3),
    # OpenColorIOColorConversionSettings (5.1 page)
    ("OpenColorIOColorConversionSettings", "configuration_source"): (5, 1),
    ("OpenColorIOColorConversionSettings", "source_color_space"): (5, 1),
    ("OpenColorIOColorConversionSettings", "destination_color_space"): (5, 1),
    # DisplayClusterConfigurationOCIOConfiguration (5.7 page; 5.0 had ocio_configuration)
    ("DisplayClusterConfigurationOCIOConfiguration", "is_enabled"): (5, 1),
    ("DisplayClusterConfigurationOCIOConfiguration", "color_configuration"): (5, 1),
    ("DisplayClusterConfigurationData", "stage_settings"): (5, 1),
    ("DisplayClusterConfigurationICVFX_StageSettings", "viewport_ocio"): (5, 1),
    ("DisplayClusterConfigurationICVFX_StageSettings", "lightcard"): (5, 1),
    # FDisplayClusterConfigurationICVFX_ViewportOCIO (C++ 5.4: BlueprintReadWrite)
    ("DisplayClusterConfigurationICVFX_ViewportOCIO", "all_viewports_ocio_configuration"): (5, 1),
    # FDisplayClusterConfigurationICVFX_LightcardOCIO (C++ 5.2; Python page 5.7)
    ("DisplayClusterConfigurationICVFX_LightcardSettings", "lightcard_ocio"): (5, 2),
    ("DisplayClusterConfigurationICVFX_LightcardOCIO", "lightcard_ocio_mode"): (5, 2),
    ("DisplayClusterICVFXCameraComponent", "camera_settings"): (5, 1),
    # FDisplayClusterConfigurationICVFX_CameraSettings::CameraOCIO (C++ 5.5); CameraOCIO page 5.6
    ("DisplayClusterConfigurationICVFX_CameraSettings", "camera_ocio"): (5, 1),
    ("DisplayClusterConfigurationICVFX_CameraOCIO", "all_nodes_ocio_configuration"): (5, 1),
}
#: The struct each get_editor_property returns (the types on the same pages).
RETURNS = {
    "stage_settings": "DisplayClusterConfigurationICVFX_StageSettings",
    "viewport_ocio": "DisplayClusterConfigurationICVFX_ViewportOCIO",
    "lightcard": "DisplayClusterConfigurationICVFX_LightcardSettings",
    "lightcard_ocio": "DisplayClusterConfigurationICVFX_LightcardOCIO",
    "camera_settings": "DisplayClusterConfigurationICVFX_CameraSettings",
    "camera_ocio": "DisplayClusterConfigurationICVFX_CameraOCIO",
}


@pytest.fixture(scope="module")
def script(tmp_path_factory):
    dirs = solve_to(tmp_path_factory.mktemp("unreal_script") / "solved")
    export_solutions(dirs[:1], targets=["unreal"])
    return (dirs[0] / "exports" / "unreal" / SCRIPT_FILE).read_text(encoding="utf-8")


def test_script_compiles_and_names_no_host_path(script):
    compile(script, SCRIPT_FILE, "exec")
    assert "/tmp" not in script


def _stand_in(version: tuple[int, int], calls: list) -> types.ModuleType:
    """An ``unreal`` module whose structs record every property set on them."""

    class Struct:
        def __init__(self, **kwargs):
            for key in kwargs:
                calls.append((type(self).__name__, key))

        def set_editor_property(self, name, value):
            calls.append((type(self).__name__, name))

        def get_editor_property(self, name):
            return getattr(unreal, RETURNS[name])()

    unreal = types.ModuleType("unreal")
    names = {cls for cls, _ in DOCUMENTED} | set(RETURNS.values())
    for name in names:
        setattr(unreal, name, type(name, (Struct,), {}))

    class Root(Struct):
        def get_config_data(self):
            return unreal.DisplayClusterConfigurationData()

        def get_components_by_class(self, cls):
            return [cls(), cls()]

        def get_name(self):
            return "root"

    unreal.DisplayClusterRootActor = Root
    unreal.DisplayClusterConfigurationViewportLightcardOCIOMode = types.SimpleNamespace(
        N_DISPLAY="N_DISPLAY"
    )
    unreal.SystemLibrary = types.SimpleNamespace(
        get_engine_version=lambda: f"{version[0]}.{version[1]}.0-x"
    )
    assets = types.SimpleNamespace(
        does_asset_exist=lambda path: False,
        load_asset=lambda path: unreal.OpenColorIOConfiguration(),
        save_loaded_asset=lambda asset: True,
    )
    unreal.EditorAssetLibrary = assets
    tools = types.SimpleNamespace(create_asset=lambda *a: unreal.OpenColorIOConfiguration())
    unreal.AssetToolsHelpers = types.SimpleNamespace(get_asset_tools=lambda: tools)
    subsystem = types.SimpleNamespace(get_all_level_actors=lambda: [Root(), object()])
    unreal.EditorActorSubsystem = object
    unreal.get_editor_subsystem = lambda cls: subsystem
    unreal.log = unreal.log_warning = lambda message: calls.append(("log", message))
    return unreal


@pytest.mark.parametrize("version", [(5, 1), (5, 2), (5, 3), (5, 4), (5, 5), (5, 7)])
def test_script_sets_only_documented_properties(script, version, monkeypatch, tmp_path):
    calls: list = []
    monkeypatch.setitem(sys.modules, "unreal", _stand_in(version, calls))
    monkeypatch.setattr(sys, "argv", ["ocio_vp_setup.py", str(tmp_path)])
    exec(compile(script, SCRIPT_FILE, "exec"), {"__name__": "__main__"})
    sets = [call for call in calls if call[0] != "log"]
    for owner, name in sets:
        assert (owner, name) in DOCUMENTED, (owner, name)
        assert DOCUMENTED[owner, name] <= version, (owner, name, version)
    done = {name for _, name in sets}
    assert "configuration_file" in done
    assert ("context" in done) == (version >= (5, 5))
    assert ("all_nodes_ocio_configuration" in done) == (version >= (5, 3))
    assert ("lightcard_ocio_mode" in done) == (version >= (5, 3))
    if version < (5, 3):
        assert any("pick them by hand" in str(c[1]) for c in calls if c[0] == "log")


def test_every_set_property_is_a_string_literal(script):
    """So the check above sees every property the script can set."""
    for node in ast.walk(ast.parse(script)):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "set_editor_property":
            assert isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str)
