"""The DIT cart's log-in log-out cube: written only where it meets the cube limit, and then
equal to colour-science's encode(Q decode(x)) (read back by OCIO's .cube reader)."""

from __future__ import annotations

import json
from pathlib import Path

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest

from ocio_vp.cli import main
from ocio_vp.exports.cube import CUBE_LIMIT

SAMPLE = Path(__file__).resolve().parent.parent / "sample_configs" / "paper_stage.yaml"


@pytest.fixture(scope="module")
def calib(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("dit") / "calib"
    args = ["solve", str(SAMPLE), "--out", str(out), "--method", "least-squares",
            "--camera-colorspace", "ARRI Wide Gamut 4", "--environment", "rgb_led_white",
            "--environment", "direct_sun"]  # fmt: skip
    assert main(args) == 0
    assert main(["export", str(out), "--target", "dit"]) == 0
    return out


def test_cube_within_the_limit_is_the_post_correction_in_log(calib):
    folder = calib / "rgb_led_white" / "exports" / "dit"
    manifest = json.loads((folder / "dit.json").read_text())
    assert manifest["cube"] and manifest["accuracy"]["max_error"] <= CUBE_LIMIT
    cube = OCIO.FileTransform(src=str(folder / manifest["cube"]),
                              interpolation=OCIO.INTERP_TETRAHEDRAL)  # fmt: skip
    log = np.random.default_rng(0).uniform(0.1, 0.7, (500, 3))
    got = log.astype(np.float32).copy()
    OCIO.Config.CreateRaw().getProcessor(cube).getDefaultCPUProcessor().applyRGB(got)
    Q = np.array(json.loads((calib / "rgb_led_white" / "solution.json").read_text())["Q"])
    with np.errstate(invalid="ignore"):  # colour evaluates both branches of np.where
        want = colour.log_encoding(
            colour.log_decoding(log, function="ARRI LogC4") @ Q.T, function="ARRI LogC4"
        )
    np.testing.assert_allclose(got, want, atol=2 * CUBE_LIMIT)


def test_cube_over_the_limit_is_not_written_and_says_why(calib):
    folder = calib / "direct_sun" / "exports" / "dit"
    manifest = json.loads((folder / "dit.json").read_text())
    assert manifest["cube"] is None and "over the limit" in manifest["not_written"]
    assert "Stage Footage (LogC4)" in manifest["not_written"]
    assert not list(folder.glob("*.cube"))


def test_without_a_camera_gamut_there_is_no_dit_cube(tmp_path, capsys):
    out = tmp_path / "calib"
    args = ["solve", str(SAMPLE), "--out", str(out), "--environment", "direct_sun",
            "--method", "least-squares"]  # fmt: skip
    assert main(args) == 0
    capsys.readouterr()
    assert main(["export", str(out / "direct_sun"), "--target", "dit"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--camera-colorspace" in err
