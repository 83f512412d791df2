"""The error promise under hostile input and faults: one line, exit 2, nothing written or replaced.

Every hostile input is generated here (alias bombs, deep nesting, huge integers and names,
FIFOs, devices, duplicate keys, extreme numbers, hand-edited solution.json files, foreign
files where outputs go, a full disk, concurrent runs). Each case checks the command's exit
status, that stderr is exactly one line of at most ~300 characters naming the problem, and
that nothing was written (or that the files that were there are byte-for-byte unchanged).
"""

from __future__ import annotations

import errno
import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import make_measurements_dict
from exr_helpers import write_exr

from ocio_vp.cli import main
from ocio_vp.formats.documents import MAX_DEPTH
from ocio_vp.staging import MARKER

MAX_LINE = 300


def snapshot(folder: Path) -> dict[str, bytes | None]:
    """Every entry under ``folder``: file bytes (None for folders, FIFOs...)."""
    out: dict[str, bytes | None] = {}
    for path in sorted(folder.rglob("*")):
        key = str(path.relative_to(folder))
        out[key] = path.read_bytes() if path.is_file() else None
    return out


def one_line_error(capsys, args: list[str], *, status: int = 2) -> str:
    """Run the CLI in-process; assert ``status`` and one short stderr line; return it."""
    capsys.readouterr()
    assert main(args) == status
    err = capsys.readouterr().err
    assert err.endswith("\n") and err.count("\n") == 1, err[:2000]
    assert len(err) <= MAX_LINE, err
    assert "Traceback" not in err
    return err


def cli_exit(capsys, args: list[str]) -> str:
    """Like :func:`one_line_error` for errors argparse raises itself (SystemExit)."""
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and len(err) <= MAX_LINE, err
    return err


def write_yaml(path: Path, document) -> Path:
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


@pytest.fixture(scope="module")
def solved(tmp_path_factory) -> Path:
    """A solve output folder (two environments) with its measurements file."""
    root = tmp_path_factory.mktemp("solved")
    measurements = write_yaml(root / "stage.yaml", make_measurements_dict())
    assert main(["solve", str(measurements), "--out", str(root / "out")]) == 0
    return root / "out"


# --------------------------------------------------------------------------------------------
# Parser abuse: bounded work, one line, nothing written.

ALIAS_BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 10)}]\n" for i in range(8)
)


def _doc_with(text_for_format: str) -> str:
    body = yaml.safe_dump(make_measurements_dict(), sort_keys=False)
    return body.replace("format: ocio-vp/measurements", f"format: {text_for_format}", 1)


PARSER_CASES = {
    # name: (file name, text, expected words in the message)
    "alias_bomb_in_format": (
        "m.yaml",
        "format: &x0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n"
        + "".join(f"x{i + 1}: &x{i + 1} [{', '.join(['*x' + str(i)] * 9)}]\n" for i in range(9)),
        "aliases expand",
    ),
    "alias_bomb_lists": ("m.yaml", ALIAS_BOMB, "aliases expand"),
    "recursive_alias": ("m.yaml", "format: &a [*a]\n", "refers to itself"),
    # Our bound (MAX_DEPTH, 64 levels) below libyaml's own (1000 flow levels in the libyaml that PyYAML
    # 6.0.4's wheels bundle; none in 6.0.3's): our message, whichever PyYAML is installed.
    "deep_nesting_yaml": (
        "m.yaml",
        "[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1),
        f"nested deeper than {MAX_DEPTH}",
    ),
    # Far deeper: whichever bound stops it first, one line naming the file and the nesting.
    "deep_nesting_yaml_50000": ("m.yaml", "[" * 50_000 + "]" * 50_000, "nest"),
    "deep_nesting_json": ("m.json", "[" * 50_000 + "]" * 50_000, "nested too deep"),
    "int_400_digits_yaml": ("m.yaml", _doc_with("9" * 400), "too large"),
    "int_5000_digits_yaml": ("m.yaml", _doc_with("9" * 5000), "too large"),
    "int_5000_digits_json": ("m.json", '{"format": ' + "9" * 5000 + "}", "too large"),
    "duplicate_key_yaml": ("m.yaml", "format: a\nversion: 1\nformat: b\n", "duplicate key"),
    "duplicate_key_json": ("m.json", '{"version": 1, "version": 2}', "duplicate key"),
    "python_tag": ("m.yaml", "format: !!python/object/apply:os.system [id]\n", "constructor"),
    "not_utf8": ("m.yaml", b"\xff\xfe\x00garbage", "UTF-8"),
    "huge_format_string": ("m.yaml", _doc_with("x" * 10_000_000), "expected 'ocio-vp/"),
    "unhashable_key": ("m.yaml", "? [a, b]\n: 1\n", "key that is a list"),
}


@pytest.mark.parametrize("case", sorted(PARSER_CASES))
def test_parser_abuse_is_one_line(case, tmp_path, capsys):
    name, text, expected = PARSER_CASES[case]
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert expected in err and name in err
    assert not (tmp_path / "out").exists()


def _measurements(tmp_path: Path, edit, suffix: str = ".yaml") -> Path:
    document = make_measurements_dict()
    edit(document)
    path = tmp_path / f"m{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(document))
    else:
        write_yaml(path, document)
    return path


def _scale(section: str, factor: float):
    def edit(d):
        for c in ("red", "green", "blue"):
            d[section][c] = (np.asarray(d[section][c]) * factor).tolist()

    return edit


VALUE_CASES = {
    "name_trailing_newline": (
        lambda d: d["environments"][0].update(name="daylight\n"),
        "unsafe name 'daylight\\n'",
    ),
    "name_with_slash": (lambda d: d["environments"][0].update(name="a/b"), "unsafe name"),
    "primaries_x1e-300": (_scale("primaries", 1e-300), "is the data scaled"),
    "lit_chart_x1e300": (_scale("lit_chart", 1e300), "<= 1e+09"),
    "beta_5e-324": (lambda d: d["stage"].update(beta=5e-324), ">= 1e-06"),
    "panel_1e300_wide": (
        lambda d: d["stage"]["calibration_panel"].update(width=1e300),
        "<= 1000",
    ),
    "white_reflectance_5e-324": (
        lambda d: d["stage"].update(white_reflectance=5e-324),
        ">= 0.01",
    ),
    "target_nan": (
        lambda d: d["environments"][0]["target_chart"][0].__setitem__(0, float("nan")),
        "finite",
    ),
    "target_1e308_int": (
        lambda d: d["environments"][0]["target_chart"][0].__setitem__(0, 10**307),
        "<= 1e+09",
    ),
    "white_patch_huge_int": (lambda d: d["stage"].update(white_patch=10**300), "outside"),
}


@pytest.mark.parametrize("case", sorted(VALUE_CASES))
def test_values_outside_a_meaningful_range_are_one_line(case, tmp_path, capsys):
    edit, expected = VALUE_CASES[case]
    path = _measurements(tmp_path, edit)
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert expected in err, err
    assert not (tmp_path / "out").exists()


def test_a_10_MB_name_is_quoted_in_a_few_characters(tmp_path, capsys):
    text = yaml.safe_dump(make_measurements_dict(), sort_keys=False)
    path = tmp_path / "m.yaml"
    path.write_text(text.replace("name: test-stage", "name: " + "a" * 10_000_000, 1))
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert "stage.name: unsafe name 'aaaa" in err
    assert not (tmp_path / "out").exists()


def test_json_measurements_with_a_400_digit_integer(tmp_path, capsys):
    path = tmp_path / "m.json"
    text = json.dumps(make_measurements_dict()).replace('"version": 1', '"version": ' + "7" * 400)
    path.write_text(text)
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert "too large" in err


def test_file_over_the_size_limit(tmp_path, capsys):
    from ocio_vp.formats.documents import MAX_DOCUMENT_BYTES

    path = tmp_path / "big.yaml"
    with open(path, "wb") as handle:  # sparse: no disk space used, no time spent
        handle.truncate(MAX_DOCUMENT_BYTES + 1)
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert "MiB limit" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null"])
def test_devices_are_refused(device, tmp_path, capsys):
    if not os.path.exists(device):
        pytest.skip(f"{device} does not exist on this system")
    err = one_line_error(capsys, ["solve", device, "--out", str(tmp_path / "out")])
    assert "not a regular file" in err


def test_a_folder_as_measurements(tmp_path, capsys):
    err = one_line_error(capsys, ["solve", str(tmp_path), "--out", str(tmp_path / "out")])
    assert "is a folder" in err


def _run_cli(args: list[str], cwd: Path, timeout: float = 120, **kwargs):
    return subprocess.run(
        [sys.executable, "-m", "ocio_vp.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        **kwargs,
    )


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def _one_plate_capture(corners: list) -> dict:
    """A capture file whose every photograph is ``plate.exr``, the charts at ``corners``."""
    chart = {"plate": "plate.exr", "corners": corners}
    return {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": {"name": "s", "beta": 0.25},
        "chart": {"rows": 4, "columns": 6},
        "primaries": {
            "plate": "plate.exr",
            "red": [0, 0, 2, 2],
            "green": [2, 0, 4, 2],
            "blue": [4, 0, 6, 2],
        },
        "lit_chart": {c: dict(chart) for c in ("red", "green", "blue")},
        "environments": [{"name": "e", "target_chart": dict(chart)}],
    }


def test_fifos_never_block(tmp_path):
    """A FIFO nobody writes, as measurements file and as a plate: refused at once, no hang."""
    os.mkfifo(tmp_path / "m.yaml")
    os.mkfifo(tmp_path / "plate.exr")
    capture = _one_plate_capture([[0, 0], [6, 0], [6, 4], [0, 4]])
    write_yaml(tmp_path / "capture.yaml", capture)
    for args, name in (
        (["solve", "m.yaml", "--out", "out"], "m.yaml"),
        (["measure", "capture.yaml", "--out", "out/m.yaml"], "plate.exr"),
    ):
        result = _run_cli(args, tmp_path, timeout=60)
        assert result.returncode == 2, result.stderr
        assert result.stderr.count("\n") == 1 and len(result.stderr) <= MAX_LINE
        assert "not a regular file" in result.stderr and name in result.stderr
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------------------------
# Command-line values.

ARG_CASES = {
    "dpi_tiny": (["report", "{solved}", "--out", "{tmp}/r", "--dpi", "0.001"], "--dpi"),
    "dpi_inf": (["report", "{solved}", "--out", "{tmp}/r", "--dpi", "inf"], "--dpi"),
    "dpi_huge": (["report", "{solved}", "--out", "{tmp}/r", "--dpi", "100000"], "--dpi"),
    "cube_range_denormal": (
        ["export", "{solved}/env_0", "--out", "{tmp}/x", "--cube-range", "0", "5e-324"],
        "--cube-range",
    ),
    "frames_30M": (
        [
            "apply",
            "{solved}/env_0",
            "{tmp}/f.####.exr",
            "--frames",
            "1-30000000",
            "--out",
            "{tmp}/o",
        ],
        "at most",
    ),
    "frame_pattern_1e9_digits": (
        ["apply", "{solved}/env_0", "{tmp}/f.%01000000000d.exr", "--out", "{tmp}/o"],
        "digits",
    ),
    "frames_huge_number": (
        [
            "apply",
            "{solved}/env_0",
            "{tmp}/f.####.exr",
            "--frames",
            "1-" + "9" * 400,
            "--out",
            "{tmp}/o",
        ],
        "--frames",
    ),
    "panel_1e309": (["simulate", "--out", "{tmp}/s.yaml", "--panel", "1e309x1x1"], "--panel"),
    "hdri_width_0": (
        [
            "solve",
            "{solved}/../stage.yaml",
            "--out",
            "{tmp}/o",
            "--hdri",
            "h.exr",
            "--hdri-width",
            "0",
        ],
        "--hdri-width",
    ),
}


@pytest.mark.parametrize("case", sorted(ARG_CASES))
def test_bad_command_line_values_are_one_line(case, solved, tmp_path, capsys):
    template, expected = ARG_CASES[case]
    args = [a.format(solved=solved, tmp=tmp_path) for a in template]
    before = snapshot(solved.parent)
    err = one_line_error(capsys, args)
    assert expected in err
    assert list(tmp_path.iterdir()) == []
    assert snapshot(solved.parent) == before


def test_argument_type_errors_are_one_line(capsys):
    err = cli_exit(capsys, ["report", "x", "--dpi", "abc" * 100_000])
    assert "--dpi" in err and "--help" in err


# --------------------------------------------------------------------------------------------
# Hand-edited solution.json read by report, export and apply.

SOLUTION_EDITS = {
    "environment_with_slash": (lambda d: d.update(environment="a/b"), "unsafe name"),
    "nul_byte_in_stage": (lambda d: d.update(stage="st\x00age"), "unsafe name"),
    "beta_text": (lambda d: d.update(beta="abc"), "beta"),
    "measurements_list": (lambda d: d.update(measurements=[]), "measurements"),
    "matrix_strings": (lambda d: d.update(M=[["a"] * 3] * 3), "3x3"),
    "matrix_huge": (lambda d: d.update(Q=[[1e308] * 3] * 3), "3x3"),
    "ocio_not_names": (lambda d: d.update(ocio={"config": 5}), "ocio"),
}


@pytest.mark.parametrize("verb", ["report", "export", "apply"])
@pytest.mark.parametrize("case", sorted(SOLUTION_EDITS))
def test_hand_edited_solution_is_one_line(verb, case, solved, tmp_path, capsys):
    edit, expected = SOLUTION_EDITS[case]
    folder = tmp_path / "env_0"
    folder.mkdir()
    for item in (solved / "env_0").iterdir():
        if item.is_file():
            (folder / item.name).write_bytes(item.read_bytes())
    document = json.loads((folder / "solution.json").read_text())
    edit(document)
    (folder / "solution.json").write_text(json.dumps(document))
    before = snapshot(tmp_path)
    frame = tmp_path / "frame.exr"
    args = {
        "report": ["report", str(folder), "--out", str(tmp_path / "r")],
        "export": ["export", str(folder), "--out", str(tmp_path / "x")],
        "apply": ["apply", str(folder), str(frame), "--out", str(tmp_path / "o")],
    }[verb]
    err = one_line_error(capsys, args)
    assert expected in err and "solution.json" in err
    assert snapshot(tmp_path) == before


def test_duplicate_key_in_solution_json(solved, tmp_path, capsys):
    folder = tmp_path / "env_0"
    folder.mkdir()
    text = (solved / "env_0" / "solution.json").read_text()
    (folder / "solution.json").write_text(text.replace("{", '{"beta": 0.5,', 1))
    err = one_line_error(capsys, ["report", str(folder), "--out", str(tmp_path / "r")])
    assert "duplicate key 'beta'" in err


# --------------------------------------------------------------------------------------------
# Disk full, read-only: one line, nothing left behind.


def _fail_writes(monkeypatch, code: int) -> None:
    """Every ``os.replace`` (how outputs are published) fails as the disk would."""

    def fail(src, dst, *args, **kwargs):
        raise OSError(code, os.strerror(code), str(dst))

    monkeypatch.setattr(os, "replace", fail)


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EROFS, errno.EACCES])
def test_write_errors_during_solve_are_one_line(code, tmp_path, capsys, monkeypatch):
    path = write_yaml(tmp_path / "m.yaml", make_measurements_dict())
    _fail_writes(monkeypatch, code)
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "out")])
    assert os.strerror(code) in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("verb", ["export", "report"])
def test_disk_full_during_export_and_report(verb, solved, tmp_path, capsys, monkeypatch):
    before = snapshot(solved)
    _fail_writes(monkeypatch, errno.ENOSPC)
    err = one_line_error(capsys, [verb, str(solved / "env_0"), "--out", str(tmp_path / "x")])
    assert "No space left on device" in err
    assert not (tmp_path / "x").exists()
    assert snapshot(solved) == before


def _file_size_limit(limit: int):
    """For a child process: writes past ``limit`` bytes fail with EFBIG (like a full disk)."""

    def apply() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


@pytest.mark.skipif(not hasattr(signal, "SIGXFSZ"), reason="no RLIMIT_FSIZE on this system")
def test_real_write_failure_in_every_writer_is_one_line(tmp_path):
    """The kernel refuses writes past 2 KB in the child: OCIO, json and staging all hit it."""
    path = write_yaml(tmp_path / "m.yaml", make_measurements_dict())
    result = _run_cli(
        ["solve", "m.yaml", "--out", "out"], tmp_path, preexec_fn=_file_size_limit(2048)
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and len(result.stderr) <= MAX_LINE, result.stderr
    assert "too large" in result.stderr.lower()
    assert not (tmp_path / "out").exists()
    assert path.read_text() == yaml.safe_dump(make_measurements_dict(), sort_keys=False)


# --------------------------------------------------------------------------------------------
# Outputs never replace an input or a file ocio-vp did not write.


@pytest.fixture
def project(tmp_path) -> Path:
    root = tmp_path / "proj"
    root.mkdir()
    write_yaml(root / "stage.yaml", make_measurements_dict())
    return root


def test_solve_never_deletes_a_user_file_in_an_environment_folder(project, capsys):
    assert main(["solve", str(project / "stage.yaml"), "--out", str(project)]) == 0
    (project / "env_0" / "notes.txt").write_text("mine")
    before = snapshot(project)
    err = one_line_error(capsys, ["solve", str(project / "stage.yaml"), "--out", str(project)])
    assert "notes.txt" in err and "did not write" in err
    assert snapshot(project) == before


def test_a_user_file_named_like_an_environment(project, capsys):
    (project / "env_1").write_text("mine")
    before = snapshot(project)
    err = one_line_error(capsys, ["solve", str(project / "stage.yaml"), "--out", str(project)])
    assert "env_1" in err
    assert snapshot(project) == before


def test_a_user_folder_named_like_an_environment(project, capsys):
    (project / "env_0").mkdir()
    (project / "env_0" / "photo.jpg").write_bytes(b"x")
    before = snapshot(project)
    err = one_line_error(capsys, ["solve", str(project / "stage.yaml"), "--out", str(project)])
    assert "not written by ocio-vp" in err
    assert snapshot(project) == before


def test_solve_out_is_or_contains_the_input(project, capsys):
    before = snapshot(project)
    err = one_line_error(
        capsys, ["solve", str(project / "stage.yaml"), "--out", str(project / "stage.yaml")]
    )
    assert "not a folder" in err
    (project / "env_0").mkdir()
    (project / "env_0" / "stage.yaml").write_bytes((project / "stage.yaml").read_bytes())
    before = snapshot(project)
    err = one_line_error(
        capsys, ["solve", str(project / "env_0" / "stage.yaml"), "--out", str(project)]
    )
    assert "contains an input" in err
    assert snapshot(project) == before


def test_simulate_never_replaces_a_user_file(tmp_path, capsys):
    target = tmp_path / "notes.yaml"
    target.write_text("my notes\n")
    err = one_line_error(capsys, ["simulate", "--out", str(target)])
    assert "did not write" in err
    assert target.read_text() == "my notes\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.yaml"]


def test_prepare_hdri_never_replaces_its_input(tmp_path, capsys):
    image = np.full((8, 16, 3), 0.1, np.float32)
    image[2, 3] = 5.0
    source = tmp_path / "in.exr"
    write_exr(source, image)
    before = snapshot(tmp_path)
    err = one_line_error(capsys, ["prepare-hdri", str(source), "--out", str(source)])
    assert "input" in err
    other = tmp_path / "user.exr"
    write_exr(other, image)
    before = snapshot(tmp_path)
    err = one_line_error(capsys, ["prepare-hdri", str(source), "--out", str(other)])
    assert "not an image prepare-hdri wrote" in err
    assert snapshot(tmp_path) == before
    # Its own output may be replaced by a re-run.
    assert main(["prepare-hdri", str(source), "--out", str(tmp_path / "out.exr")]) == 0
    assert main(["prepare-hdri", str(source), "--out", str(tmp_path / "out.exr")]) == 0


def test_apply_out_an_existing_file(solved, tmp_path, capsys):
    frame = tmp_path / "f.0001.exr"
    write_exr(frame, np.full((4, 4, 3), 0.5, np.float32))
    (tmp_path / "o").write_text("mine")
    before = snapshot(tmp_path)
    err = one_line_error(
        capsys, ["apply", str(solved / "env_0"), str(frame), "--out", str(tmp_path / "o")]
    )
    assert "not a folder" in err
    assert snapshot(tmp_path) == before


def test_measure_never_replaces_its_inputs(tmp_path, capsys):
    plate = tmp_path / "plate.exr"
    write_exr(plate, np.full((8, 12, 3), 0.5, np.float32))
    corners = [[0, 0], [12, 0], [12, 8], [0, 8]]
    capture = _one_plate_capture(corners)
    path = write_yaml(tmp_path / "capture.yaml", capture)
    (tmp_path / "notes.txt").write_text("mine")
    before = snapshot(tmp_path)
    for extra, expected in (
        (["--out", str(path)], "also an input"),
        (["--out", str(plate)], "also an input"),
        (["--out", str(tmp_path / "m.yaml"), "--overlays", str(tmp_path)], "contains an input"),
        (
            ["--out", str(tmp_path / "m.yaml"), "--overlays", str(tmp_path / "notes.txt")],
            "not a folder",
        ),
    ):
        err = one_line_error(capsys, ["measure", str(path), *extra])
        assert expected in err, err
        assert snapshot(tmp_path) == before  # no .old-PID leftovers either


def test_demo_with_a_foreign_report_folder_leaves_nothing(tmp_path, capsys):
    (tmp_path / "d" / "report").mkdir(parents=True)
    (tmp_path / "d" / "report" / "mine.html").write_text("mine")
    before = snapshot(tmp_path)
    err = one_line_error(capsys, ["demo", "--out", str(tmp_path / "d")])
    assert "report" in err
    assert snapshot(tmp_path) == before


# --------------------------------------------------------------------------------------------
# Concurrent runs into one folder never mix; re-runs are byte-identical, without absolute paths.


def test_concurrent_solves_never_mix(project):
    methods = ["least-squares", "white-preserving"] * 2
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "ocio_vp.cli",
                "solve",
                "stage.yaml",
                "--out",
                "out",
                "--method",
                m,
            ],
            cwd=project,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for m in methods
    ]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    assert any(code == 0 for code, _ in results), results
    for code, err in results:
        assert code == 0 or (code == 2 and "another ocio-vp run" in err), err
    out = project / "out"
    assert sorted(p.name for p in out.iterdir()) == ["env_0", "env_1"]  # no staging leftovers
    written = {
        json.loads((out / e / "solution.json").read_text())["method"] for e in ("env_0", "env_1")
    }
    assert len(written) == 1  # both environments from the same run


RERUN_COMMANDS = (
    ["solve", "{root}stage.yaml", "--out", "{root}a"],
    ["export", "{root}a/env_0", "--target", "unreal", "--out", "{root}x"],
    ["export", "{root}a/env_0", "--target", "nuke", "--out", "{root}x"],
    ["report", "{root}a/env_0", "--out", "{root}r", "--dpi", "20"],
)


@pytest.fixture(scope="module")
def reruns(tmp_path_factory):
    """solve, export and report run with relative paths, then re-run with absolute ones."""
    root = tmp_path_factory.mktemp("reruns")
    write_yaml(root / "stage.yaml", make_measurements_dict())
    cwd = os.getcwd()
    os.chdir(root)
    try:
        for command in RERUN_COMMANDS:
            assert main([a.format(root="") for a in command]) == 0
        first = {name: snapshot(root / name) for name in ("a", "x", "r")}
    finally:
        os.chdir(cwd)
    for command in RERUN_COMMANDS:  # a re-run replaces its own outputs
        assert main([a.format(root=f"{root}/") for a in command]) == 0
    return root, first


def test_reruns_are_byte_identical_without_absolute_paths(reruns):
    root, first = reruns
    for name, files in first.items():
        assert snapshot(root / name) == files, name  # .ocioz archives and .nk scripts included
    for path in root.rglob("*"):
        if path.is_file() and path.suffix != ".png":
            assert str(root).encode() not in path.read_bytes(), path
    assert (root / "a" / "env_0" / MARKER).is_file()


def test_nuke_script_has_no_absolute_path(reruns):
    root, _ = reruns
    script = (root / "x" / "env_0" / "nuke" / "env_0.nk").read_bytes()
    assert str(root).encode() not in script


def test_one_line_for_an_internal_bug(tmp_path, capsys, monkeypatch):
    """A genuine bug is exit 1, one line, naming it a bug (no traceback)."""
    import ocio_vp.formats.measurements as measurements

    def broken(*args, **kwargs):
        raise ZeroDivisionError("x" * 100_000)

    monkeypatch.setattr(measurements, "measurements_from_dict", broken)
    path = write_yaml(tmp_path / "m.yaml", make_measurements_dict())
    err = one_line_error(capsys, ["solve", str(path), "--out", str(tmp_path / "o")], status=1)
    assert "internal error: ZeroDivisionError" in err and "bug" in err
