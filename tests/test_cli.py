"""The command line explains itself: --version, python -m ocio_vp, defaults in every --help."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import pytest

import ocio_vp
from ocio_vp.cli import COMMANDS, build_parser, main
from ocio_vp.correction.registry import Q_SOLVE_METHODS
from ocio_vp.pipeline import DEFAULT_METHOD


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"ocio-vp {ocio_vp.__version__}"


def test_python_dash_m():
    result = subprocess.run(
        [sys.executable, "-m", "ocio_vp", "--version"], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"ocio-vp {ocio_vp.__version__}"


@pytest.mark.parametrize("verb", [name.replace("_", "-") for name in COMMANDS])
def test_every_option_says_its_default(verb):
    """Every option with a value names its default; every argument is described."""
    parser = _subparsers()[verb]
    text = parser.format_help()
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        assert action.help, f"{verb} {action.dest}: no help"
        helped = parser._get_formatter()._expand_help(action)
        takes_value = action.option_strings and action.nargs != 0 and not action.required
        if takes_value:
            assert "default" in helped.lower(), f"{verb} {action.option_strings}: {helped!r}"
    assert "%(" not in text


def test_method_lists_the_registry():
    for verb in ("solve", "demo"):
        action = next(a for a in _subparsers()[verb]._actions if a.dest == "method")
        assert tuple(action.choices) == tuple(Q_SOLVE_METHODS)
        assert action.default == DEFAULT_METHOD
        helped = _subparsers()[verb]._get_formatter()._expand_help(action)
        assert all(name in helped for name in Q_SOLVE_METHODS)
        assert f"(default: {DEFAULT_METHOD})" in helped


def test_unknown_method_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as info:
        main(["solve", "x.yaml", "--out", "o", "--method", "least-square"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'least-square'" in err and "did you mean 'least-squares'?" in err


@pytest.mark.parametrize(
    ("argv", "suggestion"),
    [
        (["solv", "x.yaml"], "'solve'"),
        (["solve", "x.yaml", "--out", "o", "--wall-encodng", "pq"], "'--wall-encoding'"),
        (["solve", "x.yaml", "--out", "o", "--wall-encoding", "gama2.4"], "'gamma2.4'"),
        (["export", "d", "--target", "unrael"], "'unreal'"),
    ],
)
def test_a_mistyped_command_option_or_choice_gets_a_did_you_mean(argv, suggestion, capsys):
    with pytest.raises(SystemExit) as info:
        main(argv)
    err = capsys.readouterr().err
    assert info.value.code == 2 and f"did you mean {suggestion}?" in err
    assert err.count("\n") == 1


def test_options_without_effect_are_refused_and_encodings_ignore_case(tmp_path, capsys):
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.stage import simulate_measurements

    stage = tmp_path / "stage.yaml"
    save_measurements(simulate_measurements(["direct_sun"]), stage)
    assert main(["solve", str(stage), "--out", str(tmp_path / "a"), "--peak-nits", "600"]) == 2
    err = capsys.readouterr().err
    assert "--peak-nits: applies only to a PQ wall" in err and err.count("\n") == 1
    assert not (tmp_path / "a").exists()
    args = ["solve", str(stage), "--out", str(tmp_path / "b"), "--wall-encoding", "PQ"]
    assert main([*args, "--peak-nits", "600"]) == 0
    out = capsys.readouterr().out
    assert "wall signal: PQ (SMPTE ST 2084), drive 1.0 = 600 cd/m2" in out


def test_solve_runs_openblas_single_threaded_unless_the_user_chose(tmp_path):
    """A fresh solve (or demo) sets OPENBLAS_NUM_THREADS=1 for itself and the processes it
    starts, before numpy loads; another command, or a user's own setting, is left alone."""
    script = (
        "import os, sys\n"
        "from ocio_vp.cli import main\n"
        "main(sys.argv[1:])\n"  # each stops with one line, exit 2: the file is missing
        "print(os.environ.get('OPENBLAS_NUM_THREADS'))\n"
    )
    missing = str(tmp_path / "missing.yaml")
    commands = {"solve": ["solve", missing, "--out", str(tmp_path / "out")]}
    commands["export"] = ["export", missing]
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    for given, command, expected in (
        (None, "solve", "1"),
        (None, "export", "None"),
        ("2", "solve", "2"),
    ):
        if given:
            env["OPENBLAS_NUM_THREADS"] = given
        run = subprocess.run(
            [sys.executable, "-c", script, *commands[command]],
            env=env,
            capture_output=True,
            text=True,
        )
        assert run.stdout.split() == [expected], (command, run.stderr)
