"""Chart detection (numpy/scipy, default install) on simulated plates, each degradation apart.

The truth is what the simulator rendered: the chart's corners (``CHART_CORNERS`` or the
degradation's own) and its patch values: the paper stage's chart lit by its blue LEDs alone
(the darkest lit chart: its red patches are near black) and colour-science's ColorChecker 24
(xyY, after November 2014) in linear sRGB as a target chart. Plates are 600 x 400 with the
simulator's usual 1 % noise and 5 % fall-off, plus the degradation named in
``ocio_vp.simulator.plates.DEGRADATIONS`` (amounts stated there).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.plates.detection import DetectionError, detect_chart, detect_chart_corners
from ocio_vp.plates.reader import open_plate
from ocio_vp.plates.sampling import sample_chart
from ocio_vp.simulator.plates import (
    CHART_CORNERS,
    DEGRADATIONS,
    PLATE_SIZE,
    render_chart,
    write_plate,
)

SENSOR = {"noise": 0.01, "read_noise": 1e-4, "vignetting": 0.05}


def colour_checker() -> np.ndarray:
    """colour-science's ColorChecker 24 as linear sRGB (D65), patch order, floored at 0.002."""
    import colour

    chart = colour.CCS_COLOURCHECKERS["ColorChecker24 - After November 2014"]
    xyY = np.array(list(chart.data.values()))
    rgb = colour.XYZ_to_RGB(colour.xyY_to_XYZ(xyY), "sRGB", chart.illuminant)
    return np.maximum(rgb, 0.002)


@pytest.fixture(scope="module")
def charts():
    from ocio_vp.simulator.stage import paper_stage

    stage = paper_stage()
    return {"lit_blue": stage.beta * stage.SRL_unscaled[:, :, 2], "target": colour_checker()}


def _plate(tmp_path, name, values, **options):
    image = render_chart(values, **(SENSOR | options))
    return open_plate(write_plate(tmp_path / f"{name}.exr", image))


# Corner accuracy (pixels) each degradation allows; the chart is ~350 pixels wide, a patch ~50:
# perspective's far side is a third shorter, so its patches' centres extrapolate less well.
TOLERANCE = {"blur": 0.5, "noise": 0.5, "perspective": 2.5, "vignetting": 0.5, "occlusion": 1.5}


@pytest.mark.parametrize("chart", ["lit_blue", "target"])
@pytest.mark.parametrize("degradation", sorted(DEGRADATIONS))
def test_found_under_each_degradation(tmp_path, charts, chart, degradation):
    options = DEGRADATIONS[degradation]
    info = _plate(tmp_path, chart, charts[chart], **options)
    found = detect_chart(info)
    truth = options.get("corners", CHART_CORNERS)
    assert found.corners is not None, found.message()
    assert np.max(np.abs(found.corners - truth)) < TOLERANCE[degradation]
    # What matters downstream: the patches sampled with these corners are the true ones.
    samples = sample_chart(info.path, found.corners, 4, 6, clip_level=np.inf)
    expected = sample_chart(info.path, truth, 4, 6, clip_level=np.inf)
    white = np.abs(expected.means).max()
    # 0.3% of white: under a tenth of the error the paper reports after calibration (under 4%
    # of the white square on average, its Quantitative Results), so detection adds no visible
    # error; the same bound as the whole measurement's (tests/test_simulator_plates.py).
    assert np.max(np.abs(samples.means - expected.means)) < 0.003 * white


def test_occluded_patches_are_left_out_of_the_grid(tmp_path, charts):
    found = detect_chart(_plate(tmp_path, "t", charts["target"], **DEGRADATIONS["occlusion"]))
    # The occluder covers patches 21, 22 and part of 20 and of the two above (15, 16).
    assert found.corners is not None and 18 <= found.patches_found <= 21
    assert {21, 22}.isdisjoint(found.seen) and len(found.seen) == found.patches_found
    assert set(range(15)) <= set(found.seen)


@pytest.mark.parametrize("turn", [1, 2, 3])
def test_a_turned_chart_is_read_from_its_neutral_row(tmp_path, charts, turn):
    """Upside down or on its side, patch 0 is still found where the chart has it."""
    if turn % 2:  # portrait: a chart stood on its side, the grid 6 high and 4 wide
        corners = np.array([[200.0, 40.0], [420.0, 50.0], [410.0, 370.0], [190.0, 360.0]])
    else:
        corners = CHART_CORNERS
    corners = np.roll(corners, turn, axis=0)  # the chart's TL moves round the quadrilateral
    info = _plate(tmp_path, "turned", charts["target"], corners=corners)
    found = detect_chart_corners(info)
    assert np.max(np.abs(found - corners)) < 0.5


def test_a_grid_other_than_the_colour_checker_is_read_upright(tmp_path):
    values = np.linspace(0.05, 0.8, 15)[:, None] * [1.0, 0.8, 0.6]
    info = _plate(tmp_path, "grid", values, rows=3, columns=5)
    found = detect_chart_corners(info, rows=3, columns=5)
    assert np.max(np.abs(found - CHART_CORNERS)) < 0.5


@pytest.mark.parametrize(
    ("reason", "options"),
    [
        ("too dark", {"dark": 2e-4}),
        ("clipped", {"scale": 40.0, "clip": 1.0}),
        ("too small", {"corners": CHART_CORNERS * 0.18 + [200, 150]}),
        ("not found", {"scale": 0.0, "background": 0.3}),
    ],
)
def test_a_failure_says_why_and_what_to_give_instead(tmp_path, reason, options):
    options = dict(options)
    scale, clip = options.pop("scale", 1.0), options.pop("clip", None)
    dark = options.pop("dark", None)
    image = render_chart(colour_checker() * scale, **(SENSOR | options))
    if clip is not None:
        image = np.minimum(image, clip)
    if dark is not None:  # the whole frame underexposed, under the same read noise
        noise = np.random.default_rng(1).normal(0, SENSOR["read_noise"], image.shape)
        image = image * dark + noise
    info = open_plate(write_plate(tmp_path / "bad.exr", image, dtype="float"))
    with pytest.raises(DetectionError) as caught:
        detect_chart_corners(info)
    message = str(caught.value)
    assert f": {reason}: chart not found" in message and "corners" in message
    assert "\n" not in message
    width, height = PLATE_SIZE  # the plate rendered, as rows x columns
    assert caught.value.detection.image.shape[:2] == (height, width)


# -- through `ocio-vp measure` ----------------------------------------------------------------


def _capture(tmp_path, charts, **target_options):
    """A charts-only capture file (one environment's target chart) with no corners given."""
    target = render_chart(charts["target"], seed=9, **(SENSOR | target_options))
    write_plate(tmp_path / "park.exr", target)
    document = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": {"name": "test_stage", "beta": 0.05},
        "environments": [{"name": "park", "target_chart": {"plate": "park.exr"}}],
    }
    path = tmp_path / "capture.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


def test_measure_finds_the_chart_and_records_the_corners(tmp_path, charts, capsys):
    capture = _capture(tmp_path, charts)
    before = capture.read_text()
    out = tmp_path / "charts.yaml"
    assert main(["measure", str(capture), "--out", str(out)]) == 0
    assert capture.read_text() == before  # an input: left alone unless asked
    assert main(["measure", str(capture), "--out", str(out), "--write-corners"]) == 0
    assert "wrote 1 detected chart corner set(s)" in capsys.readouterr().out
    written = yaml.safe_load(capture.read_text())
    corners = np.array(written["environments"][0]["target_chart"]["corners"])
    assert np.max(np.abs(corners - CHART_CORNERS)) < 0.5
    samples = json.loads((tmp_path / "charts.overlays" / "samples.json").read_text())
    target = samples["plates"][0]
    assert target["key"] == "environments[0].target_chart" and target["detected"]
    assert target["detection"]["patches_found"] == 24
    assert (tmp_path / "charts.overlays" / target["detection"]["overlay"]).is_file()
    # A second run reads the corners written back: no search, the same numbers.
    again = tmp_path / "again.yaml"
    assert main(["measure", str(capture), "--out", str(again)]) == 0
    searched = json.loads((tmp_path / "again.overlays" / "samples.json").read_text())
    assert not searched["plates"][0]["detected"] and "detection" not in searched["plates"][0]
    first = yaml.safe_load(out.read_text())["environments"][0]["target_chart"]
    second = yaml.safe_load(again.read_text())["environments"][0]["target_chart"]
    np.testing.assert_allclose(second, first, rtol=1e-4)


def test_measure_refuses_on_one_line_with_the_overlay_only(tmp_path, charts, capsys):
    capture = _capture(tmp_path, charts, corners=CHART_CORNERS * 0.18 + [200, 150])
    before = capture.read_text()
    out = tmp_path / "charts.yaml"
    assert main(["measure", str(capture), "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "environments[0].target_chart" in lines[0]
    assert "too small" in lines[0] and "corners" in lines[0]
    assert "park_target.detection.png" in lines[0]
    folder = tmp_path / "charts.overlays"
    assert sorted(p.name for p in folder.iterdir() if not p.name.startswith(".")) == [
        "park_target.detection.png"
    ]
    assert not out.exists() and capture.read_text() == before
    # Reframed, the next run succeeds and replaces the folder the failure published.
    write_plate(tmp_path / "park.exr", render_chart(charts["target"], **SENSOR))
    assert main(["measure", str(capture), "--out", str(out), "--no-write-back"]) == 0
    assert (folder / "park_target.png").is_file()
