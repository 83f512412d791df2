"""A re-solve keeps an environment's exports and reports and names the stale ones."""

from __future__ import annotations

import json

import yaml
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.formats.provenance import SOURCE_FILE, solution_sha256, stale_outputs


def test_a_resolve_names_exactly_the_stale_outputs(tmp_path, capsys):
    stage, calib = tmp_path / "stage.yaml", tmp_path / "calib"
    stage.write_text(yaml.safe_dump(make_measurements_dict()))
    assert main(["solve", str(stage), "--out", str(calib), "--method", "least-squares"]) == 0
    for env in ("env_0", "env_1"):
        assert main(["export", str(calib / env), "--target", "unreal"]) == 0
    assert main(["report", str(calib / "env_0"), "--dpi", "20"]) == 0
    assert main(["report", str(calib), "--dpi", "20"]) == 0
    record = json.loads((calib / "env_0" / "exports" / "unreal" / SOURCE_FILE).read_text())
    assert record["solution_sha256"] == solution_sha256(calib / "env_0")
    capsys.readouterr()
    # the same solve again: the same solution, nothing stale
    assert main(["solve", str(stage), "--out", str(calib), "--method", "least-squares"]) == 0
    assert "stale" not in "".join(capsys.readouterr())
    # another method for env_1 only: its export and both reports showing it are named
    args = ["--method", "white-preserving", "--environment", "env_1"]
    assert main(["solve", str(stage), "--out", str(calib), *args]) == 0
    err = capsys.readouterr().err.splitlines()
    stale = [line for line in err if line.startswith("warning: stale")]
    assert len(stale) == 2, stale
    assert (
        f"{calib / 'env_1' / 'exports' / 'unreal'}" in stale[0] and "white-preserving" in stale[0]
    )
    assert f"the report {calib / 'report'} " in stale[1] and "env_1" in stale[1]
    # the exports are still usable: Unreal's config is where it was
    assert (calib / "env_1" / "exports" / "unreal" / "config" / "config.ocio").is_file()
    assert stale_outputs(calib, ["env_0"]) == []
