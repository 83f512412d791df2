"""``ocio-vp demo`` and ``ocio-vp simulate`` end to end (files checked by loading them back).

Sources: the simulator (tests/test_spectral.py checks it against direct sums), OCIO's own
``ociocheck`` for the written configs.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from ocio_vp.calibration.diagnostics import summary_errors
from ocio_vp.cli import main
from ocio_vp.formats.measurements import load_measurements
from ocio_vp.formats.solution import load_solution
from ocio_vp.simulator.stage import PAPER_ENVIRONMENTS


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "demo_out"
    import contextlib
    import io

    buffer, errors = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(buffer), contextlib.redirect_stderr(errors):
        code = main(["demo", "--out", str(out), "--method", "least-squares", "--no-report"])
    return code, out, buffer.getvalue() + errors.getvalue()


def test_demo_writes_every_environment(demo):
    code, out, _ = demo
    assert code == 0
    for name in PAPER_ENVIRONMENTS:
        solution = load_solution(out / name)
        assert solution.environment == name
        assert solution.measurements_file == "paper_stage.yaml"
    measurements = load_measurements(out / "paper_stage.yaml")
    assert [e.name for e in measurements.environments] == list(PAPER_ENVIRONMENTS)
    assert not [p.name for p in out.iterdir() if p.name.startswith(".")]  # no staging left


def test_demo_and_solve_print_one_table(demo, tmp_path, capsys):
    """One set of numbers: the demo's rows and warnings are solve's, for the same data, and
    the figures are solution.json's (the lit chart with the drive the wall can emit)."""
    _, out, text = demo
    args = ["solve", str(out / "paper_stage.yaml"), "--out", str(tmp_path / "s")]
    assert main([*args, "--method", "least-squares"]) == 0
    printed = capsys.readouterr()
    solved = printed.out + printed.err
    assert not [line for line in printed.out.splitlines() if line.startswith("warning:")]

    def rows(output: str) -> list[str]:
        names = ("environment", *PAPER_ENVIRONMENTS)
        return [
            line for line in output.splitlines() if line.split()[:1] and line.split()[0] in names
        ]

    def warnings(output: str) -> list[str]:
        return [line for line in output.splitlines() if line.startswith("warning:")]

    assert len(rows(text)) == 1 + len(PAPER_ENVIRONMENTS)
    assert rows(text) == rows(solved)
    assert warnings(text) == warnings(solved) and warnings(text)
    line = {row.split()[0]: row for row in rows(text)}["sodium_vapour"]
    assert "not solved" in line
    diagnostics = load_solution(out / "sodium_vapour").diagnostics
    figures = summary_errors(diagnostics)
    np.testing.assert_array_equal(figures.lit, diagnostics.lit_chart_error_clipped_drive)
    for figure in (figures.lit_baseline, figures.lit, figures.shown_baseline, figures.shown):
        assert (
            f"{100 * np.mean(figures.lit if figure is None else figure):.2f}%"
            in line.replace(">", " ").split()
        )
    gap = re.search(r"agree within (\S+) percentage points", text)
    assert gap and float(gap.group(1)) <= 1e-9  # measurements-based figures = spectral truth
    data = json.loads((out / "sodium_vapour" / "solution.json").read_text())
    assert data["N"] is None


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
def test_demo_configs_pass_ociocheck(demo):
    _, out, _ = demo
    for name in ("direct_sun", "sodium_vapour"):
        result = subprocess.run(
            ["ociocheck", "--iconfig", str(out / name / "config.ocio")],
            capture_output=True,
            text=True,
            check=False,
        )
        assert result.returncode == 0, result.stdout + result.stderr


def test_simulate_writes_a_measurements_file(tmp_path, capsys):
    spectrum = tmp_path / "sodium_dusk.csv"
    wl = np.arange(380, 781, 10)
    spectrum.write_text(
        "wavelength,value\n" + "\n".join(f"{w},{1.0 + (w == 590) * 50}" for w in wl) + "\n"
    )
    out = tmp_path / "stage.json"
    code = main(
        [
            "simulate",
            "--out",
            str(out),
            "--leds",
            "625/18,530/30,465/20",
            "--chart",
            "BabelColor Average",
            "--environment",
            "incandescent",
            "--environment",
            f"dusk={spectrum}",
            "--panel",
            "1.2x1.2x1",
            "--albedo",
            "0",
        ]
    )
    assert code == 0
    m = load_measurements(out)
    assert [e.name for e in m.environments] == ["incandescent", "dusk"]
    assert m.stage.panel.width == 1.2
    assert all(e.black_level is None for e in m.environments)
    # w_avg is normalised to green = 1 for every environment (the simulator's exposure).
    np.testing.assert_allclose([e.w_avg[1] for e in m.environments], 1.0, rtol=1e-12)


def test_simulate_measured_leds_from_csv(tmp_path):
    # Measured spectra given as a CSV on a 1 nm grid: the simulator resamples them linearly, so
    # Gaussian LEDs written out this way reproduce [SL] of the same Gaussians closely.
    from ocio_vp.simulator.stage import spectral_stage

    wl = np.arange(380.0, 781.0, 1.0)
    pairs = ((630.0, 20.0), (525.0, 35.0), (460.0, 22.0))
    sig = [f / (2 * np.sqrt(2 * np.log(2))) for _, f in pairs]
    leds = np.stack(
        [np.exp(-((wl - p) ** 2) / (2 * s**2)) for (p, _), s in zip(pairs, sig, strict=True)], 1
    )
    path = tmp_path / "leds.csv"
    path.write_text(
        "nm,r,g,b\n"
        + "\n".join(
            ",".join(f"{v:.12g}" for v in (w, *row)) for w, row in zip(wl, leds, strict=True)
        )
    )
    out = tmp_path / "m.yaml"
    assert main(["simulate", "--out", str(out), "--leds", str(path), "--environment", "d65"]) == 0
    expected = spectral_stage(leds=pairs, wall_gain=4.0).SL  # simulate's default wall gain
    np.testing.assert_allclose(load_measurements(out).SL, expected, rtol=1e-9)


def test_unwritable_out_exits_2(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    assert main(["demo", "--out", str(blocker), "--no-report"]) == 2
    assert main(["simulate", "--out", str(blocker / "m.yaml"), "--environment", "d65"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all("error:" in line and "a_file" in line for line in err)
    assert blocker.read_text() == "not a folder"


def test_simulate_lists_environments(capsys):
    with pytest.raises(SystemExit) as exited:  # no --out needed
        main(["simulate", "--list-environments"])
    assert exited.value.code == 0
    names = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert set(PAPER_ENVIRONMENTS) <= set(names)
    with pytest.raises(SystemExit) as exited:
        main(["simulate"])  # --out is required, and argparse says so
    assert exited.value.code == 2
    assert "--out" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--leds", "630,525,460"], "--leds"),
        (["--environment", "sodium_vapor"], "sodium_vapour"),
        (["--camera", "Nikon 9999"], "camera"),
        (["--environment", "x=/no/such/file.csv"], "file not found"),
        (["--panel", "1x1"], "--panel"),
    ],
)
def test_simulate_bad_input_exits_2(tmp_path, capsys, args, message):
    out = tmp_path / "x.yaml"
    assert main(["simulate", "--out", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("ocio-vp simulate: error:") and message in err
    assert len(err.splitlines()) == 1
    assert not out.exists()
