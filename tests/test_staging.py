"""Output folders: replaced only when ocio-vp wrote everything in them."""

from __future__ import annotations


def test_a_solve_replaces_its_environment_with_the_exports_and_report_inside(tmp_path, capsys):
    """The README's day run twice: an environment folder holding ocio-vp's own exports/ and
    report/ (each with its marker) is replaced, keeping them (the config a host points at is
    still there); a stranger's file in there stops the run."""
    from ocio_vp.cli import main
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.stage import simulate_measurements

    stage, calib = tmp_path / "stage.yaml", tmp_path / "calib"
    save_measurements(simulate_measurements(["direct_sun"]), stage)
    assert main(["solve", str(stage), "--out", str(calib)]) == 0
    assert main(["export", str(calib / "direct_sun"), "--target", "nuke"]) == 0
    assert main(["report", str(calib / "direct_sun"), "--dpi", "20"]) == 0
    assert main(["solve", str(stage), "--out", str(calib)]) == 0
    kept = calib / "direct_sun" / "exports" / "nuke" / "direct_sun.nk"
    assert kept.is_file()
    assert main(["export", str(calib / "direct_sun"), "--target", "nuke"]) == 0
    (calib / "direct_sun" / "exports" / "nuke" / "mine.txt").write_text("keep")
    capsys.readouterr()
    assert main(["solve", str(stage), "--out", str(calib)]) == 2
    assert "exports/nuke/mine.txt" in capsys.readouterr().err
    assert (calib / "direct_sun" / "exports" / "nuke" / "mine.txt").read_text() == "keep"


#: ``ocio-vp solve`` (``ocio_vp.cli.main``, as ``python -m ocio_vp.cli`` runs it) with one
#: pause: once this process has written an environment into the staging folder (the helper
#: process has its share by then), it touches the file argv[1] and waits there until a stop
#: signal ends the wait. functools.wraps keeps the real function's name, so the helper (which
#: pickles write_environment by name) bakes its environment with the real one meanwhile.
STOPPABLE_SOLVE = """
import functools, pathlib, sys, time
from ocio_vp.cli import main
from ocio_vp.ocio import writer

real = writer.write_environment

@functools.wraps(real)
def wait_while_writing(solution, folder):
    real(solution, folder)  # the staging folder holds this environment's files
    pathlib.Path(sys.argv[1]).touch()
    while True:
        time.sleep(0.01)

writer.write_environment = wait_while_writing
sys.exit(main(sys.argv[2:]))
"""


def test_a_stopped_solve_leaves_no_staging_folder(tmp_path):
    """A real ``ocio-vp solve`` stopped by SIGINT (Ctrl-C) and one stopped by SIGTERM (kill,
    timeout), each while its environments are being written into the staging folder: exit
    128 + the signal, one line, and no staging folder, half-published environment or helper
    process left behind. Both run at once (the test's cost is one solve's start). The signal
    is sent once the run says it is writing (:data:`STOPPABLE_SOLVE`), not when a poll happens
    to see the staging folder: the moment is the same on a slow or loaded machine."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.stage import simulate_measurements

    # Two environments with emitter-protected Q: the helper process bakes one's LUT chains
    # while this process writes the other.
    stage = tmp_path / "stage.yaml"
    save_measurements(simulate_measurements(["incandescent", "warm_white_led"]), stage)
    runs = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        out, writing = tmp_path / sig.name, tmp_path / f"writing-{sig.name}"
        cmd = [sys.executable, "-c", STOPPABLE_SOLVE, str(writing)]
        cmd += ["solve", str(stage), "--out", str(out), "--protect-emitters"]
        runs[sig] = (out, writing, subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True))
    deadline = time.monotonic() + 300  # a generous bound for a loaded machine, never reached
    waiting = dict(runs)
    while waiting and time.monotonic() < deadline:
        for sig, (out, writing, proc) in list(waiting.items()):
            assert proc.poll() is None, ("the solve ended before it was stopped", sig)
            if writing.exists():
                staged = [p.name for p in out.iterdir() if p.name.startswith(".ocio-vp-staging-")]
                assert len(staged) == 1, (sig, staged)  # stopped while writing into it
                assert any((out / staged[0]).rglob("config.ocio")), sig  # files in it
                proc.send_signal(sig)
                del waiting[sig]
        time.sleep(0.01)
    assert not waiting, "no environment was written"
    for sig, (out, _, proc) in runs.items():
        _, err = proc.communicate(timeout=60)  # the helper process has ended too (pipe closed)
        assert proc.returncode == 128 + sig.value, (sig, proc.returncode, err)
        assert err.strip() == "ocio-vp solve: interrupted", err
        left = sorted(p.name for p in out.iterdir()) if out.exists() else []
        assert left == [], (sig, left)  # nothing was published, and no staging folder
    assert not any(p.name.startswith(".ocio-vp") for p in tmp_path.rglob("*"))
    assert os.path.isfile(stage)  # the input is untouched


def _held_elsewhere(folder):
    """Lock ``folder`` as another process's ``output_lock`` would (flock is per open file, so
    a second descriptor in this process conflicts like another process); returns the fd."""
    import fcntl
    import os

    fd = os.open(folder, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return fd


def test_a_run_refused_by_the_lock_leaves_the_folder_it_made(tmp_path, monkeypatch):
    """Two solves into one new folder: both find it missing, one makes it, the other locks it
    first. The one refused must not remove the folder (it made it, but the other run is now
    writing there): removing it under that run made the other's staging folder fail, so every
    run of ``test_concurrent_solves_never_mix`` could fail (its flake), and a third run could
    lock a new folder of the same name and mix outputs."""
    import os

    import pytest

    from ocio_vp import staging
    from ocio_vp.errors import InputError

    out = tmp_path / "out"
    real = staging._make_dirs
    fds = []

    def made_then_locked_by_another(folder):
        created = real(folder)
        fds.append(_held_elsewhere(folder))  # the other run locks it between mkdir and lock
        return created

    monkeypatch.setattr(staging, "_make_dirs", made_then_locked_by_another)
    try:
        with pytest.raises(InputError, match="another ocio-vp run"):
            with staging.staged_dir(out):
                pass
        assert out.is_dir()  # still there for the run that holds it
    finally:
        for fd in fds:
            os.close(fd)
    monkeypatch.setattr(staging, "_make_dirs", real)
    with staging.staged_dir(out) as stage:  # free again: a run writes, its stage goes
        assert stage.parent == out
    assert list(out.iterdir()) == []


def test_a_lock_on_a_folder_removed_meanwhile_is_refused(tmp_path, monkeypatch):
    """The folder is removed (and made again) by another run between opening and locking it:
    the lock would be on a folder nobody else writes into, so the run stops on one line."""
    import fcntl

    import pytest

    from ocio_vp import staging
    from ocio_vp.errors import InputError

    out = tmp_path / "out"
    out.mkdir()

    class Meanwhile:
        LOCK_EX, LOCK_NB = fcntl.LOCK_EX, fcntl.LOCK_NB

        @staticmethod
        def flock(fd, flags):
            out.rmdir()
            out.mkdir()
            fcntl.flock(fd, flags)

    monkeypatch.setattr(staging, "fcntl", Meanwhile)
    with pytest.raises(InputError, match="another ocio-vp run"):
        with staging.output_lock(out):
            pass
    assert staging._LOCKS == {}


def test_an_unlocked_stage_remakes_a_folder_removed_meanwhile(tmp_path, monkeypatch):
    """solve's staging folder (unlocked: solve locks only to publish). The run that made the
    output folder removes it, empty, as it gives up, between this run finding it and making
    its staging folder in it: this run makes it again, leaves it unlocked while staging, and
    removes it at the end (it made it, and it is empty)."""
    import os

    from ocio_vp import staging

    out = tmp_path / "out"
    out.mkdir()
    real = staging._make_dirs
    calls = []

    def then_removed(folder):
        created = real(folder)
        calls.append(created)
        if len(calls) == 1:
            folder.rmdir()  # the other run gave up
        return created

    monkeypatch.setattr(staging, "_make_dirs", then_removed)
    with staging.staged_dir(out, locked=False) as stage:
        assert stage.parent == out and stage.is_dir()
        os.close(_held_elsewhere(out))  # another run may lock it meanwhile
    assert calls == [[], [out]]
    assert not out.exists()
