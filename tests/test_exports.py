"""The export command's contract: all or nothing, clear one-line errors (exit 2), templates
shipped inside the package (read as resources, so a zipped package works). Independent checks:
the file system, pyproject.toml and a fresh interpreter importing the package from a zip.

Exports of a config that carries the panel-linearity LUT sidecar (``luts/*.clf``): the sidecar
must travel with every exported config (``ociocheck`` parses every LUT and fails on a missing
file), be inside the ``.ocioz``, and the wall CLFs must carry the LUT1D: checked with
``ociochecklut`` against the original config's processor at the solve's location."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict
from test_exports_unreal import run_tool, solve_to

import ocio_vp.exports as exports
from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.exports import export_solutions
from ocio_vp.exports.templating import read_template
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    return solve_to(tmp_path_factory.mktemp("cli") / "solved")


def copy_solution(source: Path, folder: Path) -> None:
    shutil.copytree(source, folder, ignore=shutil.ignore_patterns("exports"))


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_failure_mid_way_publishes_nothing(solved, tmp_path, monkeypatch):
    out = tmp_path / "o"
    export_solutions(solved, targets=["unreal", "nuke"], out=out)
    before = snapshot(out)

    def broken(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setitem(exports.EXPORT_TARGETS, "resolve", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        export_solutions(solved, targets=["unreal", "nuke", "resolve"], out=out)
    assert snapshot(out) == before  # old exports intact, no new target, no staging leftovers
    assert sorted(p.name for p in (out / "env_0").iterdir()) == ["nuke", "unreal"]


def test_one_bad_environment_never_stops_the_others(solved, tmp_path, capsys):
    """A broken folder and a folder OCIO refuses are reported on stderr, one line each; the
    good environment is exported (exit 0) and the bad ones' folders stay untouched."""
    good, bad, refused = tmp_path / "good", tmp_path / "bad", tmp_path / "refused"
    for folder in (good, bad, refused):
        copy_solution(solved[0], folder)
    (bad / "solution.json").write_text("{")
    config = refused / "config.ocio"
    config.write_text(
        config.read_text().replace("ocio_profile_version: 2.1", "ocio_profile_version: 9")
    )
    assert main(["export", str(good), str(bad), str(refused), "--target", "nuke"]) == 0
    captured = capsys.readouterr()
    assert "env_0: nuke -> " in captured.out
    lines = captured.err.splitlines()
    assert len(lines) == 2 and all(line.startswith("not exported: ") for line in lines)
    assert str(bad) in lines[0] and str(refused) in lines[1]
    assert (good / "exports" / "nuke").is_dir()
    assert not (bad / "exports").exists() and not (refused / "exports").exists()


def test_an_ocio_failure_in_one_environment_keeps_the_others(solved, tmp_path, monkeypatch):
    """Each environment is all or nothing: env_1's failing target leaves no env_1 folder,
    env_0 is published whole."""
    import PyOpenColorIO as OCIO

    nuke = exports.EXPORT_TARGETS["nuke"]

    def fails_for_env_1(source, folder, cubes):
        if source.solution.environment == "env_1":
            raise OCIO.Exception("simulated OCIO failure")
        return nuke(source, folder, cubes)

    monkeypatch.setitem(exports.EXPORT_TARGETS, "nuke", fails_for_env_1)
    report = export_solutions(solved, targets=["unreal", "nuke"], out=tmp_path / "o")
    assert [(r.environment, r.target) for r in report] == [("env_0", "unreal"), ("env_0", "nuke")]
    assert len(report.failures) == 1 and "simulated OCIO failure" in report.failures[0].reason
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["env_0"]
    assert sorted(p.name for p in (tmp_path / "o" / "env_0").iterdir()) == ["nuke", "unreal"]


def test_nothing_exported_is_one_line_exit_2(solved, tmp_path, capsys):
    a, b = tmp_path / "a", tmp_path / "b"
    for folder in (a, b):
        copy_solution(solved[0], folder)
        (folder / "solution.json").write_text("{")
    assert main(["export", str(a), str(b)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ocio-vp export: error: nothing exported: ") and err.count("\n") == 1
    # Both failures named, within the one-line limit of ~300 characters.
    assert "a/solution.json" in err and "b/solution.json" in err and len(err) <= 300


def test_all_targets_default_location(solved, capsys):
    assert main(["export", *map(str, solved)]) == 0
    for folder in solved:
        assert sorted(p.name for p in (folder / "exports").iterdir()) == [
            "nuke",
            "resolve",
            "unreal",
        ]
    out = capsys.readouterr().out
    assert out.count("->") == 6


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda d: d.pop("M"), "M: expected a finite 3x3 matrix"),
        (lambda d: d.pop("stage"), "missing required key 'stage'"),
        (lambda d: d["ocio"].update(in_frustum="Nope"), "'Nope' is not in the config"),
        (lambda d: d.update(format="other"), "not an ocio-vp/solution file"),
    ],
)
def test_broken_solution_exits_2(solved, tmp_path, capsys, edit, words):
    folder = tmp_path / "env"
    copy_solution(solved[0], folder)
    data = json.loads((folder / "solution.json").read_text())
    edit(data)
    (folder / "solution.json").write_text(json.dumps(data))
    assert main(["export", str(folder)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ocio-vp export: error: ") and err.count("\n") == 1
    assert words in err
    assert not (folder / "exports").exists()


def test_missing_folder_and_config(tmp_path, solved, capsys):
    assert main(["export", str(tmp_path / "nope")]) == 2
    assert "nope: SOLUTION_DIR: no such file or folder" in capsys.readouterr().err
    folder = tmp_path / "env"
    copy_solution(solved[0], folder)
    (folder / "config.ocio").unlink()
    with pytest.raises(InputError, match="cannot load the OCIO config"):
        export_solutions([folder], targets=["unreal"])


def test_same_environment_twice_into_one_out(solved, tmp_path):
    with pytest.raises(InputError, match="would both write"):
        export_solutions([solved[0], solved[0]], targets=["nuke"], out=tmp_path / "o")
    assert not (tmp_path / "o").exists()


def test_n_not_solved_is_said(solved, tmp_path):
    folder = tmp_path / "env"
    copy_solution(solved[0], folder)
    data = json.loads((folder / "solution.json").read_text())
    data["N"] = None
    data["diagnostics"]["N_reason"] = "cond(Q) too high"
    (folder / "solution.json").write_text(json.dumps(data))
    export_solutions([folder], targets=["unreal"])
    text = (folder / "exports" / "unreal" / "UNREAL.md").read_text()
    assert "N was not solved" in text and "`cond(Q) too high`" in text
    mapping = json.loads((folder / "exports" / "unreal" / "unreal_ocio.json").read_text())
    assert mapping["N_solved"] is False


def test_templates_are_package_resources():
    """The templates are read from the package, which ships the top-level templates/ folder."""
    assert (ROOT / "ocio_vp" / "templates").resolve() == (ROOT / "templates").resolve()
    assert '"templates/*.j2"' in (ROOT / "pyproject.toml").read_text()
    sources = sorted((ROOT / "templates").glob("*.j2"))
    assert {"nuke_environment.nk.j2", "resolve_matrix.dctl.j2", "UNREAL.md.j2"} <= {
        p.name for p in sources
    }
    for source in sources:
        assert read_template(source.name) == source.read_text(encoding="utf-8")


def test_templates_load_from_a_zipped_package(tmp_path):
    """A zip on sys.path (no folder to look in) still renders: resources, not paths."""
    archive = tmp_path / "ocio_vp.zip"
    with zipfile.ZipFile(archive, "w") as bundle:
        for folder, _, files in os.walk(ROOT / "ocio_vp", followlinks=True):
            for name in files:
                if name.endswith((".py", ".j2")):
                    path = Path(folder) / name
                    bundle.write(path, path.relative_to(ROOT).as_posix())
    script = (
        "import sys; sys.path.insert(0, sys.argv[1]); "
        "import ocio_vp.exports.templating as t; "
        "assert t.__file__.startswith(sys.argv[1]), t.__file__; "
        "print(t.read_template('UNREAL.md.j2') == open(sys.argv[2], encoding='utf-8').read())"
    )
    result = subprocess.run(
        [sys.executable, "-c", script, str(archive), str(ROOT / "templates" / "UNREAL.md.j2")],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "True"


CHANNELS = ("red", "green", "blue")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    data = make_measurements_dict(environments=1)
    SL = np.array([data["primaries"][c] for c in CHANNELS]).T
    drive = np.linspace(0.0, 1.0, 17)
    curves = (drive**1.1, drive, drive)  # a red channel that is not linear (paper, Sec. 3.2)
    data["ramps"] = {
        c: {"drive": drive.tolist(), "camera": (np.outer(curves[k], SL[:, k]) + 0.002).tolist()}
        for k, c in enumerate(CHANNELS)
    }
    root = tmp_path_factory.mktemp("lut")
    write_solutions(solve_measurements(measurements_from_dict(data, source="t")), root / "s")
    folder = root / "s" / "env_0"
    assert (folder / "luts").is_dir(), "a solve with ramps must write the linearity LUT sidecar"
    export_solutions([folder], targets=["unreal", "nuke", "resolve"], cube_size=17)
    return folder


def test_sidecar_travels_with_every_config(exported, tmp_path):
    luts = sorted(p.name for p in (exported / "luts").iterdir())
    assert luts
    for target in ("unreal", "nuke"):
        config = exported / "exports" / target / "config"
        assert sorted(p.name for p in (config / "luts").iterdir()) == luts
        result = run_tool("ociocheck", "--iconfig", str(config / "config.ocio"))
        assert result.returncode == 0, result.stdout + result.stderr
    with zipfile.ZipFile(exported / "exports" / "unreal" / "env_0.ocioz") as archive:
        archive.extractall(tmp_path)
    assert sorted(p.name for p in (tmp_path / "luts").iterdir()) == luts
    result = run_tool("ociocheck", "--iconfig", str(tmp_path / "config.ocio"))
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize(("stem", "space"), [("wall_out_of_frustum", OUT_OF_FRUSTUM),
                                             ("wall_in_frustum", IN_FRUSTUM)])  # fmt: skip
def test_wall_clf_carries_the_lut(exported, stem, space):
    clf = exported / "exports" / "resolve" / f"{stem}.clf"
    assert "LUT1D" in clf.read_text()
    config = OCIO.Config.CreateFromFile(str(exported / "config.ocio"))
    cpu = config.getProcessor(REFERENCE, space).getDefaultCPUProcessor()
    for rgb in ([0.1, 0.05, 0.02], [0.3, 0.2, 0.1], [0.05, 0.1, 0.2]):
        want = np.array(cpu.applyRGB([float(v) for v in rgb]))
        result = run_tool("ociochecklut", str(clf), *(repr(float(v)) for v in rgb))
        assert result.returncode == 0, result.stderr
        got = np.array([float(v) for v in result.stdout.split()[-3:]])
        np.testing.assert_allclose(got, want, rtol=2e-6, atol=2e-6)


def test_wall_cubes_are_not_written_and_the_manifest_says_why(exported):
    """The linearity LUT clips drive at black: no 17^3 lattice follows that to 1/1023."""
    folder = exported / "exports" / "resolve"
    manifest = json.loads((folder / "manifest.json").read_text())
    for stem in ("wall_out_of_frustum", "wall_in_frustum"):
        assert not (folder / f"{stem}_17.cube").exists()
        reason = manifest["not_written"][f"{stem}_17.cube"]
        assert "over the limit" in reason and f"use {stem}.clf (exact)" in reason
    accuracy = manifest["files"]["post_correction_Q_17.cube"]["accuracy"]
    assert accuracy["max_error"] <= accuracy["limit"]
