"""``ocio-vp apply``: the solution vocabulary and the one warning a risky Q deserves."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.cli import main
from ocio_vp.commands.apply import split_inputs
from ocio_vp.simulator.plates import write_plate

SAMPLE = Path(__file__).resolve().parent.parent / "sample_configs" / "paper_stage"


@pytest.fixture
def calib(tmp_path) -> Path:
    for name in ("direct_sun", "sodium_vapour"):
        shutil.copytree(SAMPLE / name, tmp_path / "calib" / name)
    return tmp_path / "calib"


@pytest.fixture
def frames(tmp_path) -> Path:
    folder = tmp_path / "shot"
    folder.mkdir()
    for i in (1, 2):
        write_plate(folder / f"A001.{i:04d}.exr", np.full((4, 6, 3), 0.18 * i), dtype="float")
    return folder


def _apply(*args) -> int:
    return main(["apply", *map(str, args), "--workers", "1", "--no-progress"])


def test_split_inputs(calib, frames):
    args = [str(calib / "direct_sun"), str(calib), str(frames / "A001.####.exr")]
    assert split_inputs(args) == (args[:2], args[2:])


def test_sodium_warns_once_per_caveat(calib, frames, tmp_path, capsys):
    assert _apply(calib / "sodium_vapour", frames / "A001.####.exr", "--out", tmp_path / "o") == 0
    err = capsys.readouterr().err
    assert err.count("warning: sodium_vapour: Q is rank 1") == 1
    assert err.count("N was not solved") == 1
    assert len(list((tmp_path / "o").iterdir())) == 2


def test_a_safe_solution_says_nothing(calib, frames, tmp_path, capsys):
    assert _apply(calib / "direct_sun", frames / "A001.####.exr", "--out", tmp_path / "o") == 0
    assert "warning" not in capsys.readouterr().err


def test_a_solve_folder_means_every_environment(calib, frames, tmp_path, capsys):
    assert _apply(calib, frames / "A001.####.exr", "--out", tmp_path / "o") == 0
    for name in ("direct_sun", "sodium_vapour"):
        assert sorted(p.name for p in (tmp_path / "o" / name).iterdir()) == [
            "A001.0001.exr",
            "A001.0002.exr",
        ]
    assert "4 frame(s) written" in capsys.readouterr().out


def test_frames_before_solutions_is_an_error(frames, tmp_path, capsys):
    assert _apply(frames / "A001.####.exr", "--out", tmp_path / "o") == 2
    assert "expected the solution(s) first" in capsys.readouterr().err


def test_a_rerun_replaces_only_frames_apply_wrote(calib, frames, tmp_path, capsys):
    out = tmp_path / "o"
    args = (calib / "direct_sun", frames / "A001.####.exr", "--out", out)
    assert _apply(*args) == 0
    capsys.readouterr()
    written = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert _apply(*args) == 0  # its own frames: skipped, then replaced with --overwrite
    assert "0 frame(s) written, 2 already done" in capsys.readouterr().out
    assert _apply(*args, "--overwrite") == 0
    assert "2 frame(s) written" in capsys.readouterr().out
    assert all(p.stat().st_mtime_ns >= written[p.name] for p in out.iterdir())


@pytest.mark.parametrize("overwrite", [False, True])
def test_a_file_apply_did_not_write_is_never_replaced_nor_counted(
    calib, frames, tmp_path, capsys, overwrite
):
    out = tmp_path / "o"
    out.mkdir()
    # Someone's own frame under the name apply would write: a valid EXR, without the mark.
    write_plate(out / "A001.0002.exr", np.full((4, 6, 3), 0.5), dtype="float")
    before = (out / "A001.0002.exr").read_bytes()
    flags = ["--overwrite"] if overwrite else []
    assert _apply(calib / "direct_sun", frames / "A001.####.exr", "--out", out, *flags) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "A001.0002.exr" in err[0]
    assert "was not written by ocio-vp apply" in err[0] and "nothing was written" in err[0]
    assert (out / "A001.0002.exr").read_bytes() == before
    assert sorted(p.name for p in out.iterdir()) == ["A001.0002.exr"]  # frame 1 not written


def test_a_non_image_under_an_output_name_is_foreign(calib, frames, tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    (out / "A001.0001.exr").write_text("notes, not a frame")
    assert _apply(calib / "direct_sun", frames / "A001.####.exr", "--out", out) == 2
    assert "was not written by ocio-vp apply" in capsys.readouterr().err
    assert (out / "A001.0001.exr").read_text() == "notes, not a frame"
