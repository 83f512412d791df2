"""Hostile names never become code or paths outside the output folder.

Names are validated when an export loads a (possibly hand-edited) solution.json, and escaped
on output. Independent checks: ``tclsh`` in a safe interp (does the Tcl word read back
literally, and does injected code run?), ``gcc -fpreprocessed -E`` (what is left of the DCTL
once comments are stripped) and the file system itself."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from test_exports_resolve import COLOURS, compile_dctl, run_dctl
from test_exports_unreal import solve_to

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.exports import export_solutions
from ocio_vp.exports.escape import c_comment, inside, markdown_text, nuke_identifier, tcl_string
from ocio_vp.exports.nuke import render_nuke_script
from ocio_vp.exports.resolve import render_dctl

HOSTILE = [
    "[exec rm -rf ~]",
    "[pwned]",
    '"; system("touch /tmp/pwned"); "',
    "$env(HOME)",
    "../../etc",
    "a\nb",
    "x}\npwned\n{",
    "tail\\",
    '*/ system("id"); /*',
    "??/\nsystem(1);",
    "name with ünïcode ✓",
]


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    return solve_to(tmp_path_factory.mktemp("safety") / "solved", environments=1)[0]


def hand_edit(solved, tmp_path, key: str, value: str):
    folder = tmp_path / "edited"
    shutil.copytree(solved, folder)
    data = json.loads((folder / "solution.json").read_text())
    data[key] = value
    (folder / "solution.json").write_text(json.dumps(data))
    return folder


class TestValidationOnLoad:
    @pytest.mark.parametrize("key", ["environment", "stage"])
    @pytest.mark.parametrize("name", HOSTILE)
    def test_hand_edited_names_are_refused(self, solved, tmp_path, key, name):
        folder = hand_edit(solved, tmp_path, key, name)
        before = sorted(p for p in tmp_path.rglob("*"))
        with pytest.raises(InputError, match="unsafe name"):
            export_solutions([folder], targets=["unreal", "nuke", "resolve"], out=tmp_path / "o")
        with pytest.raises(InputError):
            export_solutions([folder], targets=["unreal", "nuke", "resolve"])
        assert sorted(p for p in tmp_path.rglob("*")) == before  # nothing written anywhere

    def test_cli_exit_2(self, solved, tmp_path, capsys):
        folder = hand_edit(solved, tmp_path, "environment", "../../etc")
        assert main(["export", str(folder), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err
        assert "solution.json: environment: unsafe name" in err
        assert not (tmp_path / "o").exists() and not (tmp_path / "etc").exists()

    def test_config_name_cannot_leave_the_folder(self, solved, tmp_path):
        folder = hand_edit(solved, tmp_path, "ocio", {"config": "../../x/config.ocio"})
        with pytest.raises(InputError, match=r"file name beside solution\.json"):
            export_solutions([folder], targets=["unreal"])

    def test_inside(self, tmp_path):
        assert inside(tmp_path / "a" / "b", tmp_path) == tmp_path / "a" / "b"
        with pytest.raises(InputError, match="outside"):
            inside(tmp_path / "a" / ".." / ".." / "etc", tmp_path)


TCL_READBACK = r"""
set child [interp create -safe]
set ::ran 0
proc flag args { set ::ran 1 }
interp alias $child pwned {} flag
interp alias $child exec {} flag
interp alias $child system {} flag
set f [open [lindex $argv 0] r]
fconfigure $f -encoding utf-8
set script [read $f]
close $f
set value [$child eval $script]
puts "ran $::ran"
puts [binary encode hex [encoding convertto utf-8 $value]]
"""


class TestTclEscaping:
    @pytest.mark.parametrize("name", HOSTILE)
    def test_word_reads_back_literally(self, name, tmp_path):
        """``set v <word>`` (a command) and ``list knob <word>`` in a braced knob block (how
        .nk knobs are read) both give back exactly the string, and nothing runs."""
        if shutil.which("tclsh") is None:
            pytest.skip("tclsh is not on PATH")
        word = tcl_string(name)
        assert "\n" not in word
        harness = tmp_path / "h.tcl"
        harness.write_text(TCL_READBACK)
        for script in (f"set v {word}", f"lindex {{knob {word}}} 1"):
            path = tmp_path / "s.tcl"
            path.write_text(script, encoding="utf-8")
            result = subprocess.run(
                ["tclsh", str(harness), str(path)], capture_output=True, text=True, check=False
            )
            assert result.returncode == 0, result.stderr
            ran, value = result.stdout.splitlines()
            assert ran == "ran 0"
            assert bytes.fromhex(value).decode("utf-8") == name

    def test_nuke_renderer_refuses_hostile_names(self):
        for name in HOSTILE:
            with pytest.raises(InputError, match="unsafe name"):
                render_nuke_script(
                    stage="s", environment=name, Q=np.eye(3), config_path="/c", names={}
                )

    def test_nuke_identifier(self):
        for name in HOSTILE:
            ident = nuke_identifier(name, prefix="ocio_vp_")
            assert ident.replace("_", "").isalnum() and ident.isascii()


class TestCEscaping:
    def test_dctl_with_hostile_names_is_still_only_the_matrix(self, tmp_path):
        if shutil.which("gcc") is None:
            pytest.skip("gcc is not on PATH")
        matrix = np.array([[0.9, 0.1, 0.0], [0.05, 0.9, 0.05], [0.0, 0.2, 0.8]])
        text = render_dctl(
            title=HOSTILE[8],
            stage=HOSTILE[2],
            environment=HOSTILE[9],
            description="\n".join(HOSTILE),
            matrix=matrix,
        )
        dctl = tmp_path / "q.dctl"
        dctl.write_text(text)
        # What the compiler sees once comments are gone: no trace of the names.
        result = subprocess.run(
            ["gcc", "-fpreprocessed", "-E", "-x", "c", str(dctl)],
            capture_output=True,
            text=True,
            check=True,
        )
        code = result.stdout
        assert "system" not in code and "touch" not in code and "pwned" not in code
        np.testing.assert_allclose(
            run_dctl(compile_dctl(dctl, tmp_path), COLOURS), COLOURS @ matrix.T, atol=1e-6
        )

    @pytest.mark.parametrize("name", HOSTILE)
    def test_c_comment(self, name):
        text = c_comment(name)
        assert "*/" not in text and "/*" not in text and "??" not in text
        assert "\n" not in text and "\\" not in text and text.isascii()


@pytest.mark.parametrize("name", HOSTILE)
def test_markdown_inline_code_cannot_be_broken(name):
    text = markdown_text(name)
    assert "\n" not in text
    ticks = len(text) - len(text.lstrip("`"))
    assert "`" * ticks not in text[ticks:-ticks]
