"""Sample calibration photographs: ``ocio_vp.simulator.plates`` and ``ocio-vp simulate --plates``."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.formats.measurements import load_measurements
from ocio_vp.plates.capture import capture_from_dict, load_capture
from ocio_vp.plates.measure import measure_capture
from ocio_vp.simulator.plates import (
    CHART_CORNERS,
    PlateOptions,
    homography,
    plate_count,
    raw_clip_note,
    render_chart,
    write_capture,
)

ENVIRONMENT = "incandescent"


@pytest.fixture(scope="module")
def truth():
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    return simulate_measurements([ENVIRONMENT], stage=paper_stage())


def test_patch_centres_carry_their_values():
    values = np.linspace(0.05, 0.9, 72).reshape(24, 3)
    image = render_chart(values)  # no lens, no noise
    H = homography(CHART_CORNERS, 4, 6)
    for j in range(24):
        row, column = divmod(j, 6)
        p = H @ [column + 0.5, row + 0.5, 1.0]
        x, y = int(p[0] / p[2]), int(p[1] / p[2])
        np.testing.assert_allclose(image[y, x], values[j], rtol=1e-6)


def test_measure_gives_back_the_simulated_values(tmp_path, truth):
    """Perspective, 5% vignetting (flat-fielded) and 1% noise: every value within 0.3% of its
    plate's white (observed: at most 0.19%)."""
    options = PlateOptions(footage_frames=1)
    capture = write_capture(truth, tmp_path / "plates", options)
    written = [p for p in (tmp_path / "plates").rglob("*.exr")]
    assert len(written) == plate_count(truth, options) == 4 + 3 + 3 + 1 + 1 + 1
    measured = measure_capture(load_capture(capture)).measurements
    env, got = truth.environments[0], measured.environments[0]
    # Per channel, relative to the white patch's value in that channel (the paper's error scale).
    white = env.target_chart[18]
    # 0.3%: under a tenth of the error the paper reports after calibration (under 4% of the
    # white square on average, its Quantitative Results): measuring adds no visible error.
    assert np.all(np.abs(got.target_chart - env.target_chart) <= 0.003 * white)
    for k in range(3):  # a lit plate's scale: its white's brightest channel
        scale = truth.SRL[18, :, k].max()
        assert np.all(np.abs(measured.SRL[:, :, k] - truth.SRL[:, :, k]) <= 0.003 * scale)
    np.testing.assert_allclose(measured.SL, truth.SL, rtol=0.003)
    np.testing.assert_allclose(got.black_level, env.black_level, rtol=0.01)
    np.testing.assert_allclose(got.w_avg, env.w_avg, rtol=1e-12)  # copied through
    # The same plates with no corners in the capture file: every chart found by itself.
    document = yaml.safe_load(capture.read_text())
    for shot in [*document["lit_chart"].values(), document["environments"][0]["target_chart"]]:
        del shot["corners"]
    result = measure_capture(capture_from_dict(document, source=str(capture)))
    assert len(result.detected) == 4
    for corners in result.detected.values():
        assert np.max(np.abs(corners - CHART_CORNERS)) < 0.5
    again = result.measurements
    np.testing.assert_allclose(again.SRL, measured.SRL, rtol=2e-3, atol=1e-4 * truth.SRL.max())
    np.testing.assert_allclose(
        again.environments[0].target_chart, got.target_chart, rtol=2e-3, atol=1e-4
    )


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_simulate_plates_then_measure_twice(tmp_path, umask_022, capsys):
    """The README's first two steps, run twice; outputs follow the umask (not 0600/0700)."""
    plates, truth_file, stage = (
        tmp_path / "plates",
        tmp_path / "truth.yaml",
        tmp_path / "stage.yaml",
    )
    for _ in range(2):
        args = ["simulate", "--out", str(truth_file), "--plates", str(plates)]
        assert main([*args, "--environment", ENVIRONMENT]) == 0
        assert main(["measure", str(plates / "capture.yaml"), "--out", str(stage)]) == 0
    out = capsys.readouterr().out
    assert f"next: ocio-vp measure {plates / 'capture.yaml'}" in out
    document = yaml.safe_load((plates / "capture.yaml").read_text())
    assert document["format"] == "ocio-vp/capture"
    assert sorted(p.name for p in (plates / "footage").iterdir()) == [
        f"{ENVIRONMENT}.000{i}.exr" for i in (1, 2, 3)
    ]
    assert load_measurements(stage).environments[0].name == ENVIRONMENT
    for path, mode in (
        (stage, 0o644),
        (truth_file, 0o644),
        (plates, 0o755),
        (plates / "capture.yaml", 0o644),
        (tmp_path / "stage.overlays", 0o755),
    ):
        assert stat.S_IMODE(path.stat().st_mode) == mode, path
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no staging left


def test_simulate_refuses_a_foreign_plates_folder(tmp_path, capsys):
    folder = tmp_path / "holiday"
    folder.mkdir()
    (folder / "beach.jpg").write_bytes(b"x")
    out = tmp_path / "truth.yaml"
    assert main(["simulate", "--out", str(out), "--plates", str(folder)]) == 2
    assert "was not written by ocio-vp" in capsys.readouterr().err
    assert not out.exists() and (folder / "beach.jpg").read_bytes() == b"x"


def test_plate_options_without_plates_warn(tmp_path, capsys):
    args = ["simulate", "--out", str(tmp_path / "t.yaml"), "--environment", ENVIRONMENT]
    assert main([*args, "--noise", "0.02"]) == 0
    assert "--noise has no effect without --plates" in capsys.readouterr().err


def test_the_location_charts_above_the_raw_clip_are_named(truth):
    """With --lit-format dng the location charts stay EXR; simulate says why when one would
    pass the DNG sensor's 1.0 clip (sodium vapour's reaches 2.5 on the README's stage)."""
    import dataclasses

    dng = PlateOptions(lit_format="dng")
    assert truth.environments[0].target_chart.max() < 1.0
    assert raw_clip_note(truth, dng) is None
    env = dataclasses.replace(
        truth.environments[0], target_chart=truth.environments[0].target_chart * 3
    )
    bright = dataclasses.replace(truth, environments=(env,))
    note = raw_clip_note(bright, dng)
    peak = 3 * truth.environments[0].target_chart.max()
    assert note is not None and f"{ENVIRONMENT}'s brightest patch is {peak:.2g}" in note
    assert raw_clip_note(bright, PlateOptions()) is None  # EXR lit charts: nothing to say
