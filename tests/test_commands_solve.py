"""`ocio-vp solve` end to end: outputs, determinism, and bad input (exit 2, one line, no output)."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import make_measurements_dict

from ocio_vp.cli import main


def _write(tmp_path: Path, data, name: str = "stage.yaml") -> Path:
    path = tmp_path / name
    if name.endswith(".json"):
        path.write_text(json.dumps(data))
    else:
        path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_solve_writes_every_environment(tmp_path, capsys) -> None:
    path = _write(tmp_path, make_measurements_dict(environments=3))
    assert (
        main(["solve", str(path), "--out", str(tmp_path / "calib"), "--method", "least-squares"])
        == 0
    )
    for name in ("env_0", "env_1", "env_2"):
        folder = tmp_path / "calib" / name
        assert (folder / "config.ocio").is_file()
        solution = json.loads((folder / "solution.json").read_text())
        assert solution["environment"] == name
        assert solution["method"] == "least-squares"
        assert np.asarray(solution["M"]).shape == (3, 3)
        assert solution["ocio"]["in_frustum"] == "LED Wall - Inner Frustum"
    table = capsys.readouterr().out
    assert "cond[SL]" in table and "env_2" in table
    assert not list((tmp_path / "calib").glob(".ocio-vp-staging-*"))


@pytest.mark.writer_helper  # as the command runs: the helper writes one of the two
def test_second_run_is_byte_identical(tmp_path) -> None:
    path = _write(tmp_path, make_measurements_dict())
    for out in ("a", "b"):
        assert main(["solve", str(path), "--out", str(tmp_path / out)]) == 0
    files_a = sorted(
        p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file()
    )
    files_b = sorted(
        p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file()
    )
    assert files_a == files_b and files_a
    for rel in files_a:
        assert (tmp_path / "a" / rel).read_bytes() == (tmp_path / "b" / rel).read_bytes(), rel


def test_json_and_yaml_give_the_same_solution(tmp_path) -> None:
    data = make_measurements_dict()
    for name in ("stage.yaml", "stage.json"):
        out = str(tmp_path / f"out-{name}")
        assert main(["solve", str(_write(tmp_path, data, name)), "--out", out]) == 0
    a = json.loads((tmp_path / "out-stage.yaml" / "env_0" / "solution.json").read_text())
    b = json.loads((tmp_path / "out-stage.json" / "env_0" / "solution.json").read_text())
    assert a["Q"] == b["Q"] and a["N"] == b["N"]


def _broken(mutate):
    data = make_measurements_dict()
    mutate(data)
    return data


def _set(path, value):
    def mutate(data):
        node = data
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value

    return mutate


def _delete(path):
    def mutate(data):
        node = data
        for key in path[:-1]:
            node = node[key]
        del node[path[-1]]

    return mutate


BAD_INPUTS = {
    "wrong format": (_set(["format"], "something-else"), "format"),
    "wrong version": (_set(["version"], 2), "version"),
    "unknown top key": (_set(["primaries_typo"], 1), "primaries_typo"),
    "unknown stage key": (_set(["stage", "white_pach"], 18), "stage.white_pach"),
    "missing primaries": (_delete(["primaries"]), "missing required key 'primaries'"),
    "primary not rgb": (_set(["primaries", "green"], [0.1, 0.2]), "primaries.green"),
    "negative primary": (_set(["primaries", "red", 1], -0.5), "primaries.red[1]"),
    "nan in chart": (_set(["lit_chart", "blue", 3, 0], float("nan")), "lit_chart.blue[3][0]"),
    "inf in target": (
        _set(["environments", 1, "target_chart", 5, 2], float("inf")),
        "environments[1].target_chart[5][2]",
    ),
    "patch counts disagree": (
        lambda d: d["lit_chart"]["green"].pop(),
        "lit_chart.green",
    ),
    "target count disagrees": (
        lambda d: d["environments"][0]["target_chart"].pop(),
        "environments[0].target_chart",
    ),
    "unsafe environment name": (
        _set(["environments", 0, "name"], "../../etc"),
        "environments[0].name",
    ),
    "hostile environment name": (
        _set(["environments", 1, "name"], "[exec rm -rf ~]"),
        "environments[1].name",
    ),
    "duplicate environment names": (
        _set(["environments", 1, "name"], "env_0"),
        "duplicate name",
    ),
    "white patch out of range": (_set(["stage", "white_patch"], 24), "stage.white_patch"),
    "string instead of number": (_set(["stage", "white_reflectance"], "0.9"), "white_reflectance"),
    "no beta nor panel": (_delete(["stage", "calibration_panel"]), "calibration_panel"),
    "zero panel distance": (
        _set(["stage", "calibration_panel", "distance"], 0),
        "stage.calibration_panel.distance",
    ),
    "singular primaries": (
        lambda d: d["primaries"].update(blue=list(d["primaries"]["green"])),
        "badly conditioned",
    ),
    "unknown camera colourspace": (
        _set(["stage", "camera_colorspace"], "ARRI Wide Gamut 5"),
        "close matches: ARRI Wide Gamut 4, ARRI Wide Gamut 3",
    ),
    "empty environments": (_set(["environments"], []), "environments"),
    "black w_avg": (_set(["environments", 0, "w_avg"], [0, 0, 0]), "environments[0].w_avg"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_exits_2_with_one_line_and_no_output(case, tmp_path, capsys) -> None:
    mutate, expected = BAD_INPUTS[case]
    data = copy.deepcopy(make_measurements_dict())
    mutate(data)
    path = _write(tmp_path, data)
    out = tmp_path / "calib"
    assert main(["solve", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert str(path) in err and expected in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("format: [unclosed", "invalid YAML at line"),
        ("just a string", "expected a mapping"),
        ("", "expected a mapping, got nothing"),
    ],
)
def test_unparseable_files(content, expected, tmp_path, capsys) -> None:
    path = tmp_path / "stage.yaml"
    path.write_text(content)
    assert main(["solve", str(path), "--out", str(tmp_path / "o")]) == 2
    assert expected in capsys.readouterr().err


def test_missing_file(tmp_path, capsys) -> None:
    assert main(["solve", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "o")]) == 2
    assert "nope.yaml: file not found" in capsys.readouterr().err


def test_existing_output_is_kept_when_a_later_environment_fails(tmp_path) -> None:
    good = _write(tmp_path, make_measurements_dict(), "good.yaml")
    out = tmp_path / "calib"
    assert main(["solve", str(good), "--out", str(out)]) == 0
    before = (out / "env_0" / "solution.json").read_bytes()
    bad = make_measurements_dict()
    bad["primaries"]["blue"] = list(bad["primaries"]["green"])
    assert main(["solve", str(_write(tmp_path, bad, "bad.yaml")), "--out", str(out)]) == 2
    assert (out / "env_0" / "solution.json").read_bytes() == before


def test_console_script_exit_code(tmp_path) -> None:
    bad = make_measurements_dict()
    bad["version"] = 9
    path = _write(tmp_path, bad)
    result = subprocess.run(
        [sys.executable, "-m", "ocio_vp.cli", "solve", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert result.stderr.strip().endswith("this ocio-vp reads version 1, got 9")


def test_output_path_that_is_a_file(tmp_path, capsys) -> None:
    path = _write(tmp_path, make_measurements_dict())
    blocker = tmp_path / "calib"
    blocker.write_text("not a folder")
    assert main(["solve", str(path), "--out", str(blocker)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    assert blocker.read_text() == "not a folder"


@pytest.mark.parametrize("knee", ["0", "1", "-0.2", "1.5", "nan"])
def test_soft_clip_knee_outside_0_1_is_refused(knee, tmp_path, capsys) -> None:
    path = _write(tmp_path, make_measurements_dict(environments=1))
    out = tmp_path / "calib"
    assert main(["solve", str(path), "--out", str(out), "--soft-clip", knee]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--soft-clip: expected a knee in (0, 1)" in err
    assert not out.exists()


def test_soft_clip_is_written_and_said(tmp_path, capsys) -> None:
    path = _write(tmp_path, make_measurements_dict(environments=1))
    args = ["solve", str(path), "--out", str(tmp_path / "calib"), "--method", "least-squares"]
    assert main([*args, "--soft-clip", "0.75"]) == 0
    solution = json.loads((tmp_path / "calib" / "env_0" / "solution.json").read_text())
    assert solution["linearity"]["soft_clip"]["knee"] == 0.75
    assert "soft clip from 75% of full drive" in capsys.readouterr().out
    assert "LogCameraTransform" in (tmp_path / "calib" / "env_0" / "config.ocio").read_text()


def test_missing_optional_measurements_are_stated(tmp_path, capsys) -> None:
    """No black_level, no stage.white_patch: the terminal and solution.json say what was
    assumed; a file that gives both says nothing of the kind."""
    data = make_measurements_dict(environments=1, black_level=False)
    data["stage"].pop("white_patch", None)
    out = tmp_path / "calib"
    args = ["--method", "least-squares", "--out"]
    assert main(["solve", str(_write(tmp_path, data)), *args, str(out)]) == 0
    printed = capsys.readouterr().out
    assumed = json.loads((out / "env_0" / "solution.json").read_text())["diagnostics"]["assumed"]
    assert len(assumed) == 2
    assert "no stage.white_patch: patch 19 white 9.5 (.05 D) (index 18)" in assumed[0]
    assert assumed[1].startswith("no black_level: no in-frustum black-level offset")
    for text in assumed:
        assert f"note: env_0: {text}" in printed
    full = make_measurements_dict(environments=1)
    full["stage"]["white_patch"] = 18
    assert (
        main(["solve", str(_write(tmp_path, full, "full.yaml")), *args, str(tmp_path / "f")]) == 0
    )
    solution = json.loads((tmp_path / "f" / "env_0" / "solution.json").read_text())
    printed = capsys.readouterr().out
    assert "assumed" not in solution["diagnostics"] and "no black_level" not in printed
    assert "no stage.white_patch" not in printed


def test_a_repeated_environment_is_refused_before_solving(tmp_path, capsys, monkeypatch) -> None:
    """``--environment X --environment X`` would write X's folder twice (a FileExistsError
    traceback once both were solved): one line naming the option and the name, exit 2,
    nothing solved or written."""
    import ocio_vp.pipeline

    def no_solving(*args, **kwargs):
        raise AssertionError("solved although the command line was refused")

    monkeypatch.setattr(ocio_vp.pipeline, "solve_environment", no_solving)
    path = _write(tmp_path, make_measurements_dict(environments=2))
    out = tmp_path / "calib"
    picks = ["--environment", "env_1", "--environment", "env_0", "--environment", "env_1"]
    assert main(["solve", str(path), "--out", str(out), *picks]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "--environment" in err and "'env_1' is given more than once" in err, err
    assert not out.exists()
