"""Nuke export: the .nk is parsed by a real Tcl interpreter (``tclsh``), in a *safe* interp
that defines one proc per node class and records the knobs; the values read back must equal
Q (float64, exactly) and the exported config path. Independent sources: tclsh, ociocheck and
an OCIO processor on the named transform the script points at."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import oracle_correction
from test_exports_unreal import run_tool, solve_to

from ocio_vp.exports import export_solutions
from ocio_vp.formats.solution import load_solution
from ocio_vp.model import correction_to_dict

NODE_CLASSES = ("Root", "Group", "Input", "OCIONamedTransform", "ColorMatrix", "Output")
#: Every class the harness knows (a root-polynomial Q adds its CLF fallback node).
KNOWN_CLASSES = (*NODE_CLASSES, "OCIOFileTransform")

# Runs the script in a safe interpreter; every node class is a proc that records its knob
# list; `pwned` records that injected code ran. Knob values leave as hex so nothing is lost.
TCL_HARNESS = r"""
set path [lindex $argv 0]
set calls {}
proc record {cls knobs} { lappend ::calls [list $cls $knobs] }
set child [interp create -safe]
interp alias $child record {} record
foreach cls {NODE_CLASSES} { $child eval [list proc $cls {knobs} "record $cls \$knobs"] }
$child eval {proc version args {}}
$child eval {proc end_group {} { record end_group {} }}
$child eval {proc pwned args { record PWNED {} }}
set f [open $path r]
fconfigure $f -encoding utf-8
set script [read $f]
close $f
$child eval $script
foreach call $calls {
    set cls [lindex $call 0]
    puts "node $cls"
    foreach {key value} [lindex $call 1] {
        puts "knob $key [binary encode hex [encoding convertto utf-8 $value]]"
    }
}
""".replace("NODE_CLASSES", " ".join(KNOWN_CLASSES))


def parse_nk(path: Path, tmp_path: Path) -> list[tuple[str, dict[str, str]]]:
    """Run the .nk through tclsh; returns [(node class, {knob: value})] in file order."""
    if shutil.which("tclsh") is None:
        pytest.skip("tclsh is not on PATH")
    harness = tmp_path / "harness.tcl"
    harness.write_text(TCL_HARNESS)
    result = subprocess.run(
        ["tclsh", str(harness), str(path)], capture_output=True, text=True, timeout=30, check=False
    )
    assert result.returncode == 0, result.stderr
    nodes: list[tuple[str, dict[str, str]]] = []
    for line in result.stdout.splitlines():
        kind, rest = line.split(" ", 1)
        if kind == "node":
            nodes.append((rest, {}))
        else:
            key, _, value = rest.partition(" ")
            nodes[-1][1][key] = bytes.fromhex(value).decode("utf-8")
    return nodes


# Nuke evaluates a file knob's Tcl when it reads it; `value root.name` is the script's path.
TCL_KNOB = r"""
proc value {name} { return [lindex $::argv 1] }
puts [subst [lindex $argv 0]]
"""


def nuke_path(knob: str, script: Path, tmp_path: Path) -> Path:
    """The file a path knob names when Nuke opens ``script`` (tclsh evaluates the knob)."""
    harness = tmp_path / "knob.tcl"
    harness.write_text(TCL_KNOB)
    result = subprocess.run(
        ["tclsh", str(harness), knob, str(script)], capture_output=True, text=True, timeout=30
    )
    assert result.returncode == 0, result.stderr
    return Path(result.stdout.strip())


def tcl_matrix(text: str) -> np.ndarray:
    rows = re.findall(r"\{([^{}]*)\}", text)
    return np.array([[float(v) for v in row.split()] for row in rows])


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    dirs = solve_to(tmp_path_factory.mktemp("nuke") / "solved")
    export_solutions(dirs, targets=["nuke"])
    return dirs


class TestNukeScript:
    @pytest.mark.parametrize("index", [0, 1])
    def test_knobs_read_back(self, exported, index, tmp_path):
        folder = exported[index] / "exports" / "nuke"
        nodes = parse_nk(folder / f"env_{index}.nk", tmp_path)
        classes = [cls for cls, _ in nodes]
        assert classes == [*NODE_CLASSES, "end_group"]
        knobs = dict(nodes)
        config = folder / "config" / "config.ocio"
        knob = knobs["Root"]["customOCIOConfigPath"]
        assert knob == "[file dirname [value root.name]]/config/config.ocio"
        assert nuke_path(knob, folder / f"env_{index}.nk", tmp_path) == config
        assert knobs["OCIONamedTransform"]["key1"] == "VP_ENVIRONMENT"
        assert knobs["OCIONamedTransform"]["value1"] == f"env_{index}"
        assert knobs["Root"]["OCIO_config"] == "custom"
        assert knobs["Root"]["colorManagement"] == "OCIO"
        solution = load_solution(exported[index])
        # float64 repr round trip: exactly Q.
        np.testing.assert_array_equal(tcl_matrix(knobs["ColorMatrix"]["matrix"]), solution.Q)
        assert knobs["ColorMatrix"]["disable"] == "true"
        assert knobs["Group"]["name"] == f"ocio_vp_env_{index}"
        named = knobs["OCIONamedTransform"]["named_transform"]
        assert named == solution.ocio.post_correction
        assert "PWNED" not in classes

    def test_named_transform_is_Q(self, exported, tmp_path):
        """The named transform the script uses, from the config the Root points at, is Q."""
        import PyOpenColorIO as OCIO

        script = exported[0] / "exports" / "nuke" / "env_0.nk"
        knobs = dict(parse_nk(script, tmp_path))
        config_path = str(nuke_path(knobs["Root"]["customOCIOConfigPath"], script, tmp_path))
        result = run_tool("ociocheck", "--iconfig", config_path)
        assert result.returncode == 0, result.stdout + result.stderr
        config = OCIO.Config.CreateFromFile(config_path)
        named = config.getNamedTransform(knobs["OCIONamedTransform"]["named_transform"])
        processor = config.getProcessor(named.getTransform(OCIO.TRANSFORM_DIR_FORWARD))
        rgb = np.array([[0.18, 0.18, 0.18], [0.9, 0.1, 0.3]], dtype=np.float32)
        out = rgb.copy()
        processor.getDefaultCPUProcessor().applyRGB(out)
        expected = rgb.astype(np.float64) @ load_solution(exported[0]).Q.T
        np.testing.assert_allclose(out, expected, atol=1e-6)

    def test_a_hostile_output_path_never_reaches_the_script(self, exported, tmp_path):
        """Nuke evaluates [..] in path knobs: the script holds no output path at all, so an
        output folder named like Tcl is harmless, and the script opens from a moved folder."""
        out = tmp_path / "[pwned]"
        export_solutions(exported[:1], targets=["nuke"], out=out)
        script = out / "env_0" / "nuke" / "env_0.nk"
        assert str(tmp_path).encode() not in script.read_bytes()
        moved = tmp_path / "moved"
        shutil.move(out / "env_0" / "nuke", moved)
        knobs = dict(parse_nk(moved / "env_0.nk", tmp_path))
        config = nuke_path(knobs["Root"]["customOCIOConfigPath"], moved / "env_0.nk", tmp_path)
        assert config == moved / "config" / "config.ocio" and config.is_file()
        assert "PWNED" not in knobs

    def test_out_folder_layout(self, exported, tmp_path):
        results = export_solutions(exported, targets=["nuke"], out=tmp_path / "o")
        assert [r.folder for r in results] == [
            tmp_path / "o" / "env_0" / "nuke",
            tmp_path / "o" / "env_1" / "nuke",
        ]
        json.dumps([r.summary.to_dict() for r in results])  # summaries are plain data
        script = tmp_path / "o" / "env_1" / "nuke" / "env_1.nk"
        knobs = dict(parse_nk(script, tmp_path))
        expected = tmp_path / "o" / "env_1" / "nuke" / "config" / "config.ocio"
        assert nuke_path(knobs["Root"]["customOCIOConfigPath"], script, tmp_path) == expected
        assert expected.is_file()


def test_root_polynomial_q_has_its_clf_fallback(tmp_path):
    """A root-polynomial Q: the OCIO node reads the config's LUT bake; a disabled
    OCIOFileTransform reads the Q CLF sidecar (valid for ociochecklut, and the exact model
    within the bake limit); the ColorMatrix is labelled as the 3x3 approximation. A simulated
    stage: a root-polynomial fitted to the synthetic random chart of the other tests folds."""
    from ocio_vp.ocio import write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("incandescent",))
    solution = solve_environment(m, m.environments[0], method="root-polynomial")
    write_solutions([solution], tmp_path / "solved")
    folder = tmp_path / "solved" / "incandescent"
    export_solutions([folder], targets=["nuke"])
    nodes = parse_nk(folder / "exports" / "nuke" / "incandescent.nk", tmp_path)
    classes = [cls for cls, _ in nodes]
    assert classes == [*NODE_CLASSES[:4], "OCIOFileTransform", *NODE_CLASSES[4:], "end_group"]
    knobs = dict(nodes)
    script = folder / "exports" / "nuke" / "incandescent.nk"
    lut = nuke_path(knobs["OCIOFileTransform"]["file"], script, tmp_path)
    assert lut.is_file() and lut.suffix == ".clf" and lut.parent.parent.name == "config"
    assert knobs["OCIOFileTransform"]["disable"] == "true"
    assert "3x3 approximation" in knobs["ColorMatrix"]["label"]
    solution = load_solution(folder)
    # the OCIO node says how close the config's chain is, read back through Tcl
    measured = solution.diagnostics.post_correction_ocio.agreement
    label = knobs["OCIONamedTransform"]["label"]
    assert f"within {measured.overall[0]:.2g} ΔE2000 (p99)" in label
    assert "ocio-vp apply" in label
    rgb = np.array([0.3, 0.2, 0.1])
    result = run_tool("ociochecklut", str(lut), *map(str, rgb))
    assert result.returncode == 0, result.stdout + result.stderr
    got = np.array(result.stdout.split()[-3:], dtype=float)
    expected = oracle_correction(correction_to_dict(solution.correction), rgb)
    assert np.abs(got - expected).max() <= 1e-3 * np.abs(expected).max()
