"""``ocio-vp validate``: the calibration shown on the (simulated) wall, filmed and judged.

The day in small: simulate a stage (its calibration take included), measure, solve one
environment with the paper's least squares, write its validation patterns, film them on the
simulated stage lit by that environment, validate.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ocio_vp.cli import main

ENV = "direct_sun"


@pytest.fixture(scope="module")
def day(tmp_path_factory):
    root = tmp_path_factory.mktemp("day")
    truth, plates, stage = root / "truth.yaml", root / "plates", root / "stage.yaml"
    assert (
        main(["simulate", "--out", str(truth), "--plates", str(plates), "--environment", ENV]) == 0
    )
    assert main(["measure", str(plates / "capture.yaml"), "--out", str(stage)]) == 0
    assert (
        main(["solve", str(stage), "--out", str(root / "calib"), "--method", "least-squares"]) == 0
    )
    check = root / "check"
    assert (
        main(
            [
                "patterns",
                "--out",
                str(check),
                "--validate",
                str(root / "calib" / ENV),
                "--size",
                "16x9",
            ]
        )
        == 0
    )
    args = ["simulate", "--out", str(truth), "--environment", ENV]
    assert main([*args, "--film", str(check / "sequence.yaml"), "--take", str(root / "take")]) == 0
    return root


def _validate(day, *extra):
    return main(
        [
            "validate",
            str(day / "calib" / ENV),
            str(day / "take" / "A001.####.exr"),
            "--sequence",
            str(day / "check" / "sequence.yaml"),
            *extra,
        ]
    )


def test_a_good_calibration_passes(day, capsys):
    out = day / "calib" / ENV / "validation"
    assert _validate(day, "--out", str(out)) == 0
    printed = capsys.readouterr().out
    assert "PASS: p95" in printed and "ΔE2000 mean" in printed
    report = json.loads((out / "validation.json").read_text())
    stats = report["delta_e2000"]
    assert report["passed"] and len(report["patches"]) == 24
    assert np.isfinite([stats["mean"], stats["p95"], stats["max"]]).all()
    # observed: mean 0.3, p95 0.5 -- the noise of the plates the calibration came from
    assert stats["p95"] < 1.0 and stats["mean"] < 0.6
    shown = [p for p in report["patches"] if p["shown"]]
    # every patch is judged: those N would drive outside the LEDs' gamut are shown pulled
    # towards grey, their intent recomputed (before: 14 of 24)
    assert stats["patches_judged"] == len(shown) == 24
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.patterns.sequence import load_sequence
    from ocio_vp.patterns.validation import GAMUT_MARGIN, in_frustum_light

    pulled = dict(load_sequence(day / "check" / "sequence.yaml").validation.pulled)
    assert pulled and all(0 <= k < 1 for k in pulled.values())
    assert {int(j) for j in report["pulled_into_gamut"]} == set(pulled)
    light = in_frustum_light(
        load_solution(day / "calib" / ENV), np.array([p["intended"] for p in report["patches"]])
    )
    assert light.min() >= GAMUT_MARGIN - 1e-9 and light.max() <= 1 - GAMUT_MARGIN + 1e-9
    # people read patches numbered from 1, with names; the file keeps 0-based indices
    assert f"{len(pulled)} patch(es) need light outside the LEDs' gamut" in printed
    worst = stats["worst_patch"]
    assert f"({worst['index'] + 1} {worst['name'].partition(' (')[2][:-1]})" in printed
    assert max(p["delta_e2000"] for p in shown) == stats["max"]
    # the post-correction is Q (least squares): corrected = Q measured, from solution.json
    Q = np.array(json.loads((day / "calib" / ENV / "solution.json").read_text())["Q"])
    for p in report["patches"]:
        np.testing.assert_allclose(p["corrected"], Q @ np.array(p["measured"]), rtol=1e-12)
    # where the wall cannot show a patch, the error is what the clipped light predicts
    for p in report["patches"]:
        if not p["shown"]:
            assert abs(p["delta_e2000"] - p["expected_delta_e2000"]) < 1.0
    html = (out / "index.html").read_text()
    assert "PASS" in html and "take.svg" in html and (out / "take.svg").exists()


def test_a_failed_threshold_is_exit_status_3(day, tmp_path, capsys):
    assert _validate(day, "--out", str(tmp_path / "v"), "--threshold", "0.05") == 3
    assert "FAIL: p95" in capsys.readouterr().out
    assert json.loads((tmp_path / "v" / "validation.json").read_text())["passed"] is False


def test_patterns_of_another_solve_are_refused(day, tmp_path, capsys):
    other = tmp_path / "calib"
    stage = day / "stage.yaml"
    assert main(["solve", str(stage), "--out", str(other), "--method", "diagonal"]) == 0
    capsys.readouterr()
    out = tmp_path / "v"
    code = main(
        [
            "validate",
            str(other / ENV),
            str(day / "take" / "A001.####.exr"),
            "--sequence",
            str(day / "check" / "sequence.yaml"),
            "--out",
            str(out),
        ]
    )
    assert code == 2 and not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "made from another solution" in err
    # what differs is named: the model (the environment is the same one)
    assert "model least-squares (here diagonal)" in err and "environment" not in err


def test_a_resolve_marks_the_validation_stale(day, tmp_path, capsys):
    import shutil

    calib = tmp_path / "calib"
    shutil.copytree(day / "calib", calib)
    out = calib / ENV / "validation"
    code = main(
        [
            "validate",
            str(calib / ENV),
            str(day / "take" / "A001.####.exr"),
            "--sequence",
            str(day / "check" / "sequence.yaml"),
            "--out",
            str(out),
        ]
    )
    assert code == 0
    stage = str(day / "stage.yaml")
    capsys.readouterr()
    # the same solve again: the same solution, the verdict still holds
    assert main(["solve", stage, "--out", str(calib), "--method", "least-squares"]) == 0
    assert "stale" not in capsys.readouterr().err
    assert main(["solve", stage, "--out", str(calib), "--method", "diagonal"]) == 0
    stale = [x for x in capsys.readouterr().err.splitlines() if x.startswith("warning: stale")]
    assert len(stale) == 1 and f"{out} validated an earlier solution of {ENV}" in stale[0]
    assert "model diagonal" in stale[0] and "ocio-vp validate" in stale[0]
    assert (out / "validation.json").exists()  # kept, and named


def test_a_calibration_sequence_is_not_a_validation_one(day, tmp_path, capsys):
    out = tmp_path / "v"
    code = main(
        [
            "validate",
            str(day / "calib" / ENV),
            str(day / "take" / "A001.####.exr"),
            "--sequence",
            str(day / "plates" / "patterns" / "sequence.yaml"),
            "--out",
            str(out),
        ]
    )
    assert code == 2 and not out.exists()
    assert "a calibration sequence, not a validation one" in capsys.readouterr().err
