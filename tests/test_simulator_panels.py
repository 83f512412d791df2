"""ocio_vp.simulator.panels: a stage whose ceiling is another panel model, its scenes, plates,
and the gain of one calibration per panel type over a calibration of the wall alone."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import load_measurements
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.panels import (
    SCENES,
    panel_held_out_errors,
    panel_stage,
    scene_light,
    simulate_panel_measurements,
    wall_only_measurements,
)
from ocio_vp.simulator.stage import camera_rgb, paper_stage, spectral_stage
from ocio_vp.simulator.truth import held_out_reflectances


@pytest.mark.parametrize("name", [*SCENES, "direct_sun"])
def test_scene_light_splits_the_environment(name):
    stage = paper_stage()
    light = scene_light(stage, name)
    green = {k: camera_rgb(stage, v)[1] for k, v in light.items()}
    assert green["wall"] + green["ceiling"] == pytest.approx(1.0, rel=1e-12)
    share = SCENES[name].share if name in SCENES else 0.35
    assert green["ceiling"] == pytest.approx(share, rel=1e-12)


@pytest.mark.parametrize("white", ["xyz", "camera"])
def test_the_ceiling_is_matched_to_the_walls_white(white):
    import colour

    from ocio_vp.spectra import spectral_shape

    stage = panel_stage(paper_stage(), white=white)
    if white == "xyz":  # as a spectroradiometer sees them: colour's CIE 1931 observer
        cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy()
        observer = np.asarray(cmfs.align(spectral_shape()).values)
    else:
        observer = stage.wall.camera
    wall = observer.T @ stage.wall.leds.sum(axis=1)
    ceiling = observer.T @ stage.ceiling.leds.sum(axis=1)
    assert np.allclose(ceiling, wall, rtol=1e-10)
    assert not np.allclose(stage.ceiling.SL, stage.wall.SL, rtol=0.05)  # another panel model


def test_one_calibration_per_panel_type_renders_held_out_colours_better():
    """Sigma camera, the wider LEDs on the wall, a third LED set on the ceiling (a stage the
    other tests do not use), 60 held-out reflectances, the default method."""
    wall = spectral_stage(camera="Sigma SDMerill (NPL)", leds=((620, 30), (530, 45), (465, 25)))
    stage = panel_stage(wall, ceiling_leds=((628, 18), (520, 32), (455, 20)))
    m = simulate_panel_measurements(stage, ("overcast", "golden_hour"))
    baseline = wall_only_measurements(m)
    reflectances = held_out_reflectances()["rawtoaces"][::3]
    for env, flat in zip(m.environments, baseline.environments, strict=True):
        ours = solve_environment(m, env)
        theirs = solve_environment(baseline, flat)
        M = {"wall": ours.panels["wall"].M, "ceiling": ours.panels["ceiling"].M}
        a = panel_held_out_errors(stage, env.name, M=M, correct=ours.correction.apply,
                                  reflectances=reflectances).delta_E_2000.mean()  # fmt: skip
        b = panel_held_out_errors(stage, env.name, M={"wall": theirs.M, "ceiling": theirs.M},
                                  correct=theirs.correction.apply,
                                  reflectances=reflectances).delta_E_2000.mean()  # fmt: skip
        assert a < 0.9 * b, (env.name, a, b)


def test_simulate_with_a_ceiling_then_plates_measure_and_solve(tmp_path, capsys):
    out = tmp_path / "sim.yaml"
    args = ["simulate", "--out", str(out), "--ceiling-leds", "618/24,538/40,470/26"]
    args += ["--environment", "interior", "--plates", str(tmp_path / "plates")]
    assert main(args) == 0
    truth = load_measurements(out)
    assert [p.name for p in truth.panels] == ["wall", "ceiling"]
    capture = yaml.safe_load((tmp_path / "plates" / "capture.yaml").read_text())
    assert [p["name"] for p in capture["panels"]] == ["wall", "ceiling"]
    assert (tmp_path / "plates" / "ceiling_lit_red.exr").is_file()
    assert (tmp_path / "plates" / "interior_wall_black.exr").is_file()
    measured_path = tmp_path / "m.yaml"
    assert (
        main(["measure", str(tmp_path / "plates" / "capture.yaml"), "--out", str(measured_path)])
        == 0
    )
    measured = load_measurements(measured_path)
    for a, b in zip(truth.panels, measured.panels, strict=True):
        assert (a.name, a.in_frustum, a.regions) == (b.name, b.in_frustum, b.regions)
        for k in range(3):  # within the plates' 1% noise, relative to the white's channel
            scale = a.SRL[18, :, k].max()
            assert np.all(np.abs(b.SRL[:, :, k] - a.SRL[:, :, k]) <= 0.003 * scale)
        assert np.allclose(b.SL, a.SL, rtol=0.01, atol=0.003 * a.SL.max())
    env_a, env_b = truth.environments[0], measured.environments[0]
    assert env_b.panel_w_avg.keys() == env_a.panel_w_avg.keys()
    assert np.allclose(env_b.panel_black_level["wall"], env_a.panel_black_level["wall"], rtol=0.02)
    assert main(["solve", str(measured_path), "--out", str(tmp_path / "calib")]) == 0
    assert "panels, interior: wall" in capsys.readouterr().out


def test_ceiling_gain_needs_a_ceiling(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path / "s.yaml"), "--ceiling-gain", "2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--ceiling-gain: only with --ceiling-leds" in err
    assert main(["simulate", "--out", str(tmp_path / "s.yaml"), "--ceiling-leds", "1,2"]) == 2
    assert "--ceiling-leds: expected PEAK/FWHM" in capsys.readouterr().err


def test_a_ceiling_of_leds_the_camera_cannot_tell_apart_names_the_ceiling():
    # The ceiling's LEDs are refused under their own name, not as the wall's --leds.
    with pytest.raises(InputError) as caught:
        panel_stage(paper_stage(), ceiling_leds=((530, 30), (530, 30), (530, 30)))
    assert caught.value.key == "ceiling_leds"
    assert "cannot tell these LEDs apart" in caught.value.problem
