"""``ocio-vp target-chart``: HDRI -> synthesized target -> solve -> config.ocio, and bad options.

End to end on the spectral simulator: an equirectangular HDRI written with OpenImageIO whose
diffuse integral is, in closed form, the camera RGB of CIE D55 (a uniform sky of that radiance;
the sun behind the chart adds nothing to a chart facing the image centre). The synthesized chart
is compared with the simulator's photograph of the chart under D55, and the Q solved from it
with the Q solved from that photograph.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import subprocess

import colour
import numpy as np
import pytest
from exr_helpers import write_exr

from ocio_vp.cli import main
from ocio_vp.formats.measurements import load_measurements, save_measurements
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.simulator import paper_stage, paper_stage_measurements

NIKON = "Nikon 5100 (NPL)"


@pytest.fixture(scope="module")
def stage_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("target_chart")
    measurements = paper_stage_measurements(["direct_sun", "incandescent"])
    path = folder / "stage.yaml"
    save_measurements(measurements, path)
    sky = measurements.environment("direct_sun").w_avg
    image = np.empty((64, 128, 3))
    image[:] = sky
    image[28:36, 0:4] = 50.0 * sky  # a sun straight behind the chart: no diffuse contribution
    write_exr(folder / "sky.exr", image)
    return path


def _run(capsys, *argv):
    code = main(["target-chart", *map(str, argv)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_hdri_to_config_with_m_q_and_n(stage_file, tmp_path, capsys):
    out = tmp_path / "cg.yaml"
    code, printed, _ = _run(
        capsys,
        stage_file,
        "--environment",
        "cg_sky",
        "--hdri",
        stage_file.parent / "sky.exr",
        "--camera",
        NIKON,
        "--out",
        out,
    )
    assert code == 0, printed
    assert "CIE daylight" in printed
    cg = load_measurements(out)
    real = cg.environment("direct_sun")
    synth = cg.environment("cg_sky")
    assert synth.synthesized.illuminant == "CIE daylight" and synth.synthesized.hdri == "sky.exr"
    assert synth.synthesized.cct == pytest.approx(5540, abs=60)  # D55 as the Nikon sees it
    np.testing.assert_allclose(synth.w_avg, real.w_avg, rtol=1e-6)
    to_xyz = camera_to_xyz_matrix(paper_stage().camera)
    errors = chart_errors(synth.target_chart, real.target_chart, camera_to_xyz=to_xyz)
    assert errors.delta_E_2000.max() < 0.02

    assert (
        main(["solve", str(out), "--out", str(tmp_path / "calib"), "--method", "least-squares"])
        == 0
    )
    solved = {
        n: json.loads((tmp_path / "calib" / n / "solution.json").read_text())
        for n in ("direct_sun", "cg_sky")
    }
    cg_solution = solved["cg_sky"]
    assert cg_solution["N"] is not None and cg_solution["M"] is not None
    assert cg_solution["diagnostics"]["synthesized_target"]["illuminant"] == "CIE daylight"
    assert any("SYNTHESIZED" in w for w in cg_solution["diagnostics"]["warnings"])
    Q_real, Q_synth = (np.array(solved[n]["Q"]) for n in ("direct_sun", "cg_sky"))
    assert np.linalg.norm(Q_synth - Q_real) < 0.005 * np.linalg.norm(Q_real)
    assert not np.allclose(Q_synth, np.eye(3), atol=1e-3)  # a real post-correction
    config = tmp_path / "calib" / "cg_sky" / "config.ocio"
    assert config.is_file()
    _ociocheck(config)
    capsys.readouterr()
    assert (
        main(["report", str(tmp_path / "calib" / "cg_sky"), "--out", str(tmp_path / "report")]) == 0
    )
    html = "\n".join(p.read_text() for p in (tmp_path / "report").rglob("*.html"))
    assert "SYNTHESIZED" in html


def _ociocheck(config):
    if shutil.which("ociocheck") is None:
        pytest.skip("ociocheck is not on PATH")
    run = subprocess.run(["ociocheck", "--iconfig", str(config)], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]


def test_replacing_an_environment_keeps_its_black_level(stage_file, tmp_path, capsys):
    out = tmp_path / "replaced.json"
    code, printed, err = _run(
        capsys,
        stage_file,
        "--environment",
        "incandescent",
        "--average-rgb",
        "0.9,1,0.5",
        "--camera",
        NIKON,
        "--out",
        out,
    )
    assert code == 0, err
    before, after = load_measurements(stage_file), load_measurements(out)
    assert [e.name for e in after.environments] == [e.name for e in before.environments]
    env = after.environment("incandescent")
    assert env.synthesized.source == "average-rgb"
    np.testing.assert_array_equal(env.black_level, before.environment("incandescent").black_level)
    np.testing.assert_array_equal(env.w_avg, [0.9, 1.0, 0.5])


def test_aces_input_is_converted_like_the_config_converts_it(stage_file, tmp_path, capsys):
    measurements = load_measurements(stage_file)
    stage = dataclasses.replace(measurements.stage, camera_colorspace="ARRI Wide Gamut 4")
    path = tmp_path / "awg.yaml"
    save_measurements(dataclasses.replace(measurements, stage=stage), path)
    out = tmp_path / "cg.yaml"
    code, printed, err = _run(
        capsys,
        path,
        "--environment",
        "cg",
        "--average-rgb",
        "0.5,0.5,0.5",
        "--hdri-colorspace",
        "ACEScg",
        "--out",
        out,
    )
    assert code == 0, err
    env = load_measurements(out).environment("cg")
    expected = colour.RGB_to_RGB(
        [0.5, 0.5, 0.5], "ACEScg", "ARRI Wide Gamut 4", chromatic_adaptation_transform="CAT02"
    )
    np.testing.assert_allclose(env.w_avg, expected, rtol=1e-12)
    assert env.synthesized.camera == "ARRI Wide Gamut 4 colour space from XYZ"
    assert any("CAT02" in a for a in env.synthesized.assumptions)
    # ACEScg pure red is outside ARRI Wide Gamut 4 (blue -0.005): refused, not clipped.
    code, _, err = _run(
        capsys,
        path,
        "--environment",
        "cg",
        "--average-rgb",
        "1,0,0",
        "--hdri-colorspace",
        "ACEScg",
        "--out",
        tmp_path / "red.yaml",
    )
    assert code == 2 and "outside the camera gamut ARRI Wide Gamut 4" in err
    assert not (tmp_path / "red.yaml").exists()


def test_an_off_locus_light_is_written_with_a_warning(stage_file, tmp_path, capsys):
    out = tmp_path / "green.yaml"
    code, printed, _ = _run(
        capsys,
        stage_file,
        "--environment",
        "green",
        "--average-rgb",
        "0.4,1,0.5",
        "--camera",
        NIKON,
        "--out",
        out,
    )
    assert code == 0
    assert "warning: green:" in printed and "Duv from the Planckian locus" in printed
    assert load_measurements(out).environment("green").synthesized.warnings


BAD = [
    (["--average-rgb", "1,1,1", "--hdri", "sky.exr"], "exactly one of --hdri"),
    ([], "exactly one of --hdri"),
    (["--average-rgb", "1,1"], "--average-rgb: expected R,G,B"),
    (["--average-rgb", "1,nan,1"], "--average-rgb: expected R,G,B"),
    (["--average-rgb", "0,0,0"], "--average-rgb: expected R,G,B"),
    (["--average-rgb", "1,1,1", "--camera", "Nikon 9000"], "unknown camera 'Nikon 9000'"),
    (["--average-rgb", "1,1,1", "--camera", NIKON, "--camera-sensitivities", "s.csv"], "not both"),
    (["--average-rgb", "1,1,1", "--camera", NIKON, "--chart", "PMC"], "has 30 patches"),
    (["--average-rgb", "1,1,1", "--camera", NIKON, "--chart", "Macbeth"], "unknown chart"),
    (
        ["--average-rgb", "1,1,1", "--camera", NIKON, "--hdri-colorspace", "ACEScgg"],
        "unknown colour space 'ACEScgg'",
    ),
    (
        ["--average-rgb", "1,1,1", "--camera", NIKON, "--hdri-colorspace", "ACEScg"],
        "no camera_colorspace",
    ),
    (["--average-rgb", "1,1,1"], "name the camera"),
    (["--hdri", "missing.exr", "--camera", NIKON], "no such HDRI file"),
    (
        ["--average-rgb", "1,1,1", "--camera", NIKON, "--illuminant-method", "magic"],
        "unknown method 'magic'",
    ),
    (
        ["--average-rgb", "1,1,1", "--camera", NIKON, "--illuminant-spectrum", "missing.csv"],
        "file not found",
    ),
    (["--average-rgb", "1,1,1", "--camera-sensitivities", "missing.csv"], "file not found"),
]


@pytest.mark.parametrize(("extra", "message"), BAD)
def test_bad_options_exit_2_with_one_line(stage_file, tmp_path, capsys, extra, message):
    out = tmp_path / "out.yaml"
    code, _, err = _run(capsys, stage_file, "--environment", "cg", *extra, "--out", out)
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_output_rules(stage_file, tmp_path, capsys):
    args = ["--environment", "cg", "--average-rgb", "1,1,1", "--camera", NIKON]
    code, _, err = _run(capsys, stage_file, *args, "--out", stage_file)
    assert code == 2 and "is an input of this command" in err
    existing = tmp_path / "existing.yaml"
    existing.write_text("keep me\n")
    code, _, err = _run(capsys, stage_file, *args, "--out", existing)
    assert code == 2 and "--force" in err and existing.read_text() == "keep me\n"
    assert _run(capsys, stage_file, *args, "--out", existing, "--force")[0] == 0
    code, _, err = _run(capsys, stage_file, *args, "--out", tmp_path / "out.txt")
    assert code == 2 and ".yaml, .yml or .json" in err
    code, _, err = _run(
        capsys, stage_file, "--environment", "bad name", *args[2:], "--out", tmp_path / "o.yaml"
    )
    assert code == 2 and "unsafe name" in err


def test_a_stage_of_several_panel_types_takes_each_types_w_avg_from_solve_hdri(tmp_path, capsys):
    from conftest import panel_stage_measurements

    _, m = panel_stage_measurements(("overcast",))
    stage = tmp_path / "panels.yaml"
    save_measurements(m, stage)
    sky = tmp_path / "sky.exr"
    write_exr(sky, np.ones((90, 180, 3)) * [0.6, 0.7, 0.8])
    out = tmp_path / "cg.yaml"
    args = ["target-chart", str(stage), "--environment", "overcast", "--hdri", str(sky)]
    assert main([*args, "--camera", NIKON, "--out", str(out)]) == 0
    assert "w_avg per panel type: from `solve --hdri`" in capsys.readouterr().out
    env = load_measurements(out).environment("overcast")
    assert env.synthesized is not None and env.panel_w_avg is None
    assert env.panel_black_level.keys() == {"wall"}  # measured on the stage: kept
    calib = tmp_path / "calib"
    assert main(["solve", str(out), "--out", str(calib), "--hdri", f"overcast={sky}"]) == 0
    panels = json.loads((calib / "overcast" / "solution.json").read_text())["panels"]
    total = np.add(panels["wall"]["w_avg"], panels["ceiling"]["w_avg"])
    np.testing.assert_allclose(total, [0.6, 0.7, 0.8], rtol=2e-3)  # a uniform sky: its radiance
