"""``ocio-vp apply``: the solution vocabulary and the one warning a risky Q deserves."""

from __future__ import annotations

import os
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


def test_frames_of_another_solution_are_never_kept_as_done(calib, frames, tmp_path, capsys):
    """A rerun with another solution refuses on one line (nothing written); --overwrite redoes
    them, and the header then names the new solution."""
    from ocio_vp.footage.sequences import SOLUTION_MARK, output_solution

    out = tmp_path / "o"
    assert _apply(calib / "direct_sun", frames / "A001.####.exr", "--out", out) == 0
    first = output_solution(out / "A001.0001.exr")
    assert first.startswith("paper-stage/direct_sun post-correction sha256:")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    args = (calib / "sodium_vapour", frames / "A001.####.exr", "--out", out)
    assert _apply(*args) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after sodium's own warnings
    assert err.startswith("ocio-vp apply: error: ") and len(err) < 300 + len(str(out)), err
    assert "direct_sun" in err and "sodium_vapour" in err, err
    assert "--overwrite" in err and "2 frames" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert _apply(*args, "--overwrite") == 0
    assert "sodium_vapour" in output_solution(out / "A001.0001.exr")
    assert SOLUTION_MARK == "ocio_vp:solution"


def test_log_footage_is_decoded_corrected_and_encoded(calib, tmp_path):
    """--footage-encoding "ARRI LogC4": encode(Q decode(x)) within 1e-4 (colour-science's
    curves and the solution's Q, computed here)."""
    import json

    import colour
    import OpenImageIO as oiio

    folder = tmp_path / "log"
    folder.mkdir()
    log = np.random.default_rng(0).uniform(0.05, 0.95, (8, 10, 3))
    write_plate(folder / "B001.0001.exr", log, dtype="float")
    out = tmp_path / "o"
    assert _apply(calib / "direct_sun", folder / "B001.0001.exr", "--out", out,
                  "--footage-encoding", "ARRI LogC4") == 0  # fmt: skip
    got = oiio.ImageBuf(str(out / "B001.0001.exr")).get_pixels(oiio.FLOAT)[..., :3]
    Q = np.array(json.loads((calib / "direct_sun" / "solution.json").read_text())["Q"])
    stored = log.astype(np.float32).astype(np.float64)
    with np.errstate(invalid="ignore"):
        want = colour.log_encoding(
            colour.log_decoding(stored, function="ARRI LogC4") @ Q.T, function="ARRI LogC4"
        )
    np.testing.assert_allclose(got, want, atol=1e-4)
    assert np.abs(got - stored).max() > 1e-3  # it did change the footage


def test_unknown_footage_encoding_is_one_line(calib, frames, tmp_path, capsys):
    args = (calib / "direct_sun", frames / "A001.####.exr", "--out", tmp_path / "o")
    assert _apply(*args, "--footage-encoding", "LogC5") == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--footage-encoding" in err and "LogC5" in err


def _four_frames(folder: Path) -> Path:
    folder.mkdir()
    for i in range(1, 5):
        write_plate(folder / f"B001.{i:04d}.exr", np.full((4, 6, 3), 0.1 * i), dtype="float")
    return folder / "B001.####.exr"


def _one_error_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    assert lines[0].startswith("ocio-vp apply: error: ") and len(lines[0]) <= 400, lines[0]
    return lines[0]


def test_a_disk_that_fills_during_apply_stops_on_one_line_and_a_rerun_continues(
    calib, tmp_path, capsys, monkeypatch
):
    """Frames 3 and 4 meet a full disk (OSError ENOSPC from the writer, as OpenImageIO's
    failing write becomes): exit 2, one line naming frame 3 and saying 2 of 4 are done; frames
    1-2 are complete EXRs under their names, no partial file is left, and the same command
    continues with frames 3-4 once there is room."""
    import errno

    import OpenImageIO as oiio

    import ocio_vp.footage.apply as apply_module

    pattern, out = _four_frames(tmp_path / "shot"), tmp_path / "o"
    real_write = apply_module._write_all

    def full_disk(dst, parts):
        if dst.name.startswith((".B001.0003", ".B001.0004")):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
        real_write(dst, parts)

    monkeypatch.setattr(apply_module, "_write_all", full_disk)
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 2
    line = _one_error_line(capsys)
    assert str(out / "B001.0003.exr") in line and "No space left on device" in line, line
    assert "2 of 4 frames done (complete, kept)" in line and ".partial" not in line, line
    assert sorted(p.name for p in out.iterdir()) == ["B001.0001.exr", "B001.0002.exr"]
    for name in ("B001.0001.exr", "B001.0002.exr"):  # complete: every pixel reads back
        assert oiio.ImageBuf(str(out / name)).get_pixels(oiio.FLOAT).shape == (4, 6, 3)
    monkeypatch.setattr(apply_module, "_write_all", real_write)
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 0
    assert "2 frame(s) written, 2 already done, 0 failed" in capsys.readouterr().out


@pytest.mark.parametrize("problem", ["permission", "under a file", "temporary name taken"])
def test_every_write_failure_is_one_line_exit_2(calib, tmp_path, capsys, monkeypatch, problem):
    """No permission (injected: tests may run as root, whom chmod does not stop), an output
    folder under a file, and a real OpenImageIO failure (a folder where the temporary frame
    goes): each one line, exit 2, the first frame named, nothing written."""
    import errno

    import ocio_vp.footage.apply as apply_module

    pattern, out = _four_frames(tmp_path / "shot"), tmp_path / "o"
    if problem == "permission":

        def refuse(dst, parts):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(dst))

        monkeypatch.setattr(apply_module, "_write_all", refuse)
    elif problem == "under a file":
        (tmp_path / "notes").write_text("a file")
        out = tmp_path / "notes" / "o"
    else:
        (out / f".B001.0001.partial-{os.getpid()}.exr").mkdir(parents=True)
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 2
    line = _one_error_line(capsys)
    assert str(out / "B001.0001.exr") in line and "continues from here" in line, line
    reason = {"permission": "Permission denied", "under a file": "Not a directory"}
    assert reason.get(problem, "(Is a directory)") in line, line
    written = sorted(p.name for p in out.glob("B001.*")) if out.is_dir() else []
    # Frame 2 is written while frame 1 fails (pipelined) unless every write fails; it counts.
    assert written in ([], ["B001.0002.exr"]) and f"{len(written)} of 4 frames done" in line


def test_a_disk_clearly_too_small_is_refused_before_any_frame(calib, tmp_path, capsys, monkeypatch):
    """The outputs are estimated at their inputs' size; free space under 0.8x that stops the
    run before it writes anything, on one line; enough space (or frames already done) runs."""
    import collections
    import shutil as shutil_module

    from ocio_vp.commands.apply import FREE_SPACE_MARGIN

    pattern, out = _four_frames(tmp_path / "shot"), tmp_path / "o"
    need = sum(p.stat().st_size for p in (tmp_path / "shot").iterdir())
    usage = collections.namedtuple("usage", "total used free")
    free = {"bytes": int(FREE_SPACE_MARGIN * need) - 1}
    monkeypatch.setattr(shutil_module, "disk_usage", lambda path: usage(1, 1, free["bytes"]))
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 2
    line = _one_error_line(capsys)
    assert "not enough free space" in line and "nothing was written" in line, line
    assert not out.exists() or not list(out.iterdir())
    free["bytes"] = int(FREE_SPACE_MARGIN * need) + 1
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 0
    free["bytes"] = 0  # every frame is done already: nothing to write, nothing refused
    assert _apply(calib / "direct_sun", pattern, "--out", out) == 0


def test_run_task_reports_a_write_failure_apart_from_a_bad_frame(calib, tmp_path, monkeypatch):
    """The pool's and Dask's path (run_task): a failing write is a write-error (the command
    stops on it), a bad input frame an input-error (the others go on)."""
    import errno

    import ocio_vp.footage.apply as apply_module
    from ocio_vp.footage.apply import FrameTask, load_post_correction, run_task

    _four_frames(tmp_path / "shot")
    post = load_post_correction(calib / "direct_sun")
    src = tmp_path / "shot" / "B001.0001.exr"
    bad = tmp_path / "shot" / "B001.0002.exr"
    bad.write_bytes(b"not an image")
    assert run_task(FrameTask(str(bad), str(tmp_path / "o" / "b.exr"), post)).status == (
        "input-error"
    )

    def full(dst, parts):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(apply_module, "_write_all", full)
    result = run_task(FrameTask(str(src), str(tmp_path / "o" / "a.exr"), post))
    assert (result.status, result.message) == ("write-error", "No space left on device")
    assert not list((tmp_path / "o").iterdir())


def test_via_config_runs_the_configs_chain_and_marks_its_frames(tmp_path, capsys):
    """``--via config`` on a root-polynomial solution: the pixels are OCIO's processor of the
    config's Stage Footage -> reference (its LUT chain, read here by OCIO directly), within the
    chain's recorded agreement of the model; the frames' header says so, so a rerun with the
    exact model refuses them rather than mixing the two in one sequence."""
    import PyOpenColorIO as OCIO
    import yaml

    from ocio_vp.footage.sequences import output_solution
    from ocio_vp.formats.solution import load_solution
    from tests.conftest import make_measurements_dict

    path = tmp_path / "stage.yaml"
    path.write_text(yaml.safe_dump(make_measurements_dict(environments=1)))
    calib = tmp_path / "calib"
    assert main(["solve", str(path), "--out", str(calib), "--method", "root-polynomial"]) == 0
    folder = calib / "env_0"
    rng = np.random.default_rng(4)
    shot = tmp_path / "shot"
    shot.mkdir()
    rgb = rng.uniform(0.01, 1.0, (8, 16, 3))
    write_plate(shot / "C001.0001.exr", rgb, dtype="float")
    out = tmp_path / "o"
    assert _apply(folder, shot / "C001.####.exr", "--out", out, "--via", "config") == 0
    got = oiio_pixels(out / "C001.0001.exr")
    config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
    names = load_solution(folder).ocio
    cpu = config.getProcessor(names.post_correction_colorspace, names.reference)
    expected = np.asarray(
        cpu.getDefaultCPUProcessor().applyRGB(rgb.astype(np.float32).ravel().tolist())
    ).reshape(rgb.shape)
    np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-7)
    model = load_solution(folder).correction.apply(rgb.astype(np.float32))
    assert np.abs(got - model).max() > 1e-5  # the LUT bake, not the model
    assert output_solution(out / "C001.0001.exr").endswith(", via config")
    assert "via config" in output_solution(out / "C001.0001.exr")
    capsys.readouterr()
    assert _apply(folder, shot / "C001.####.exr", "--out", out) == 2  # the exact model
    assert "via config, not" in capsys.readouterr().err


def oiio_pixels(path: Path) -> np.ndarray:
    import OpenImageIO as oiio

    return np.asarray(oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT), dtype=np.float64)
