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
