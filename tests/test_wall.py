"""Panel linearity (issue 5): the ``ramps`` section, the response fit, the LUT sidecar, the wall
encoding, and the written config checked by OCIO's own tools and by OIIO's.

Ground truth is a simulated wall whose red channel follows ``d**1.1`` (the paper, Section 3.2,
found its red channel not linear) while green and blue are linear; the camera sees
``[SL] f(drive) + flare``. Encodings are checked against colour-science's ST 2084 and BT.1886.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import (
    load_measurements,
    measurements_from_dict,
    save_measurements,
)
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.ocio.wall import wall_outputs
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_environment
from ocio_vp.wall.encoding import (
    apply_lut,
    decode,
    lut_drive,
    lut_table,
    with_wall_encoding,
)
from ocio_vp.wall.linearity import (
    LINEARITY_TOLERANCE,
    channel_response,
    fit_linearity,
    inverse_response,
    parse_ramps,
    ramps_to_dict,
    response_model,
)

CHANNELS = ("red", "green", "blue")
FLARE = np.array([0.002, 0.003, 0.0025])
STEPS = 33
TOOLS = all(shutil.which(t) for t in ("ociocheck", "ociochecklut", "oiiotool"))
needs_tools = pytest.mark.skipif(not TOOLS, reason="ociocheck/ociochecklut/oiiotool not on PATH")


def red_curve(d):
    """The simulated wall's red response: slightly sub-linear in the mids (3.5% at d = 0.39)."""
    return np.asarray(d, dtype=np.float64) ** 1.1


def linear(d):
    return np.asarray(d, dtype=np.float64)


WALL = (red_curve, linear, linear)


def SL_of(document: dict) -> np.ndarray:
    return np.array([document["primaries"][c] for c in CHANNELS]).T


def ramps_for(SL: np.ndarray, curves=WALL, *, steps: int = STEPS, flare=FLARE) -> dict:
    drive = np.linspace(0.0, 1.0, steps)
    return {
        c: {
            "drive": drive.tolist(),
            "camera": (np.outer(curves[k](drive), SL[:, k]) + flare).tolist(),
        }
        for k, c in enumerate(CHANNELS)
    }


def document_with_ramps(curves=WALL, **kwargs) -> dict:
    document = make_measurements_dict()
    document["ramps"] = ramps_for(SL_of(document), curves, **kwargs)
    return document


def simulated_wall(drive: np.ndarray, SL: np.ndarray, curves=WALL) -> np.ndarray:
    """Camera RGB of the wall showing linear ``drive`` (..., 3), without flare."""
    light = np.stack([curves[k](np.clip(drive[..., k], 0, None)) for k in range(3)], axis=-1)
    return light @ SL.T


def processor(config: OCIO.Config, src: str, dst: str):
    return config.getProcessor(src, dst).getDefaultCPUProcessor()


def apply(cpu, rgb: np.ndarray) -> np.ndarray:
    pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu.applyRGB(pixels)
    return pixels.astype(np.float64)


# --------------------------------------------------------------------------------------------


class TestParseRamps:
    def test_round_trip_through_a_file(self, tmp_path):
        document = document_with_ramps()
        m = measurements_from_dict(document)
        path = tmp_path / "m.yaml"
        save_measurements(m, path)
        again = load_measurements(path)
        for c in CHANNELS:
            np.testing.assert_array_equal(again.ramps[c].drive, m.ramps[c].drive)
            np.testing.assert_array_equal(again.ramps[c].camera, m.ramps[c].camera)
        assert ramps_to_dict(parse_ramps(document["ramps"])) == document["ramps"]

    @pytest.mark.parametrize(
        ("mutate", "key", "words"),
        [
            (
                lambda r: r["red"]["drive"].__setitem__(3, r["red"]["drive"][2]),
                "ramps.red.drive[3]",
                "increase strictly",
            ),
            (
                lambda r: r["green"].update(drive=[0, 0.5, 1], camera=[[0, 0, 0]] * 3),
                "ramps.green.drive",
                "at least 4",
            ),
            (
                lambda r: r["blue"]["camera"].__setitem__(-1, [0, 0, 0]),
                f"ramps.blue.camera[{STEPS - 1}]",
                "black",
            ),
            (
                lambda r: r["red"]["camera"].pop(),
                "ramps.red.camera",
                "has 32 entries but drive has 33",
            ),
            (
                lambda r: r["red"]["drive"].__setitem__(0, -0.01),
                "ramps.red.drive[0]",
                ">= 0",
            ),
            (lambda r: r.update(noise_floor=0.7), "ramps.noise_floor", "(0, 0.5)"),
            (lambda r: r.update(black=[0.0, 0.1]), "ramps.black", "[r, g, b]"),
            (
                lambda r: r["red"]["camera"][2].__setitem__(0, float("nan")),
                "ramps.red.camera[2][0]",
                "finite",
            ),
            (lambda r: r["red"].update(drives=[]), "ramps.red.drives", "unknown key"),
            (lambda r: r.update(white={}), "ramps.white", "unknown key"),
            (lambda r: r.pop("blue"), "ramps", "'blue'"),
            (
                lambda r: r["red"]["drive"].__setitem__(-1, 0.99),
                f"ramps.red.drive[{STEPS - 1}]",
                "drive 1.0",
            ),
            (
                lambda r: r["red"]["camera"].__setitem__(4, [1, 2]),
                "ramps.red.camera[4]",
                "[r, g, b]",
            ),
        ],
    )
    def test_bad_ramps_name_the_key(self, mutate, key, words):
        document = document_with_ramps()
        mutate(document["ramps"])
        with pytest.raises(InputError) as error:
            measurements_from_dict(document, source="m.yaml")
        assert error.value.source == "m.yaml"
        assert error.value.key == key
        assert words in error.value.problem


class TestChannelResponse:
    def test_projection_is_least_squares_onto_the_primary(self):
        # Closed form: camera = a s + v with v orthogonal to s projects to a exactly, and the
        # projection equals numpy's least-squares solution of s a = C.
        rng = np.random.default_rng(3)
        SL = SL_of(make_measurements_dict())
        s = SL[:, 0]
        drive = np.linspace(0, 1, 9)
        a = drive**1.2
        v = np.cross(s, rng.normal(size=3))  # orthogonal to s
        camera = np.outer(a, s) + np.outer(np.sin(7 * drive) * 0.01, v) + 0.05  # 0.05: flare
        ramp = parse_ramps(
            {c: {"drive": drive.tolist(), "camera": camera.tolist()} for c in CHANNELS}
        )["red"]
        fit = channel_response(ramp, SL, 0)
        r = fit.measured
        lstsq = np.array([np.linalg.lstsq(s[:, None], row, rcond=None)[0][0] for row in camera])
        np.testing.assert_allclose(r, (lstsq - lstsq[0]) / (lstsq[-1] - lstsq[0]), atol=1e-12)
        np.testing.assert_allclose(r, a, atol=1e-12)
        np.testing.assert_allclose(fit.response, a, atol=1e-12)  # noiseless: every step a knot
        assert fit.projection_residual == pytest.approx(
            np.max(np.abs(np.sin(7 * drive)) * 0.01 * np.linalg.norm(v)) / np.linalg.norm(s)
        )

    def test_without_a_zero_step_the_response_starts_at_zero(self):
        SL = SL_of(make_measurements_dict())
        drive = np.linspace(0.125, 1, 8)
        ramps = parse_ramps(
            {
                c: {"drive": drive.tolist(), "camera": np.outer(drive**1.1, SL[:, k]).tolist()}
                for k, c in enumerate(CHANNELS)
            }
        )
        fit = channel_response(ramps["green"], SL, 1)
        assert fit.drive[0] == 0 and fit.response[0] == 0 and len(fit.drive) == 9
        assert fit.black.source.startswith("assumed 0")
        np.testing.assert_allclose(fit.response[1:], drive**1.1, atol=1e-12)
        np.testing.assert_allclose(fit.measured, drive**1.1, atol=1e-12)

    def test_a_step_darker_than_the_one_before_is_not_monotone(self):
        document = document_with_ramps()
        camera = np.array(document["ramps"]["red"]["camera"])
        camera[5] = camera[4] * 0.99
        document["ramps"]["red"]["camera"] = camera.tolist()
        m = measurements_from_dict(document, source="m.yaml")
        with pytest.raises(InputError, match=r"ramps\.red\.camera\[5\]: response not monotone"):
            fit_linearity(m.ramps, m.SL, source="m.yaml")

    def test_top_step_no_brighter_than_zero_step(self):
        document = document_with_ramps()
        document["ramps"]["blue"]["camera"] = [FLARE.tolist()] * STEPS
        m = measurements_from_dict(document, source="m.yaml")
        with pytest.raises(InputError, match=r"ramps\.blue\.camera\[32\]: zero top step"):
            fit_linearity(m.ramps, m.SL, source="m.yaml")


class TestFitLinearity:
    def test_the_non_linear_red_channel_is_the_only_one_corrected(self):
        m = measurements_from_dict(document_with_ramps())
        block = fit_linearity(m.ramps, m.SL)
        drive = np.linspace(0, 1, STEPS)
        # Closed form of the deviation over the ramp steps.
        assert block.channels["red"].max_deviation == pytest.approx(
            np.max(np.abs(drive**1.1 - drive)), abs=1e-12
        )
        assert [block.channels[c].corrected for c in CHANNELS] == [True, False, False]
        assert block.model == "isotonic-pchip-inverse-1d-lut"

    def test_a_wall_linear_within_tolerance_gets_no_lut(self, tmp_path):
        # 0.1% bow on red: below the documented 0.2% tolerance.
        def bow(d):
            return d - 0.004 * d * (1 - d)

        document = document_with_ramps((bow, linear, linear))
        m = measurements_from_dict(document)
        solution = solve_environment(m, m.environments[0])
        block = solution.linearity
        assert block.model == "linear" and block.max_deviation < LINEARITY_TOLERANCE
        assert block.max_deviation == pytest.approx(0.001, rel=1e-3)  # 0.004 / 4 at d = 0.5
        write_solutions([solution], tmp_path)
        written = json.loads((tmp_path / "env_0" / "solution.json").read_text())
        assert written["linearity"]["model"] == "linear"
        assert written["linearity"]["lut"] is None
        assert not (tmp_path / "env_0" / "luts").exists()
        assert "FileTransform" not in (tmp_path / "env_0" / "config.ocio").read_text()

    def test_inverse_is_exact_for_the_pchip_model(self):
        d = np.linspace(0, 1, 9)
        r = d**1.3
        x = np.linspace(0, 1, 1001)
        np.testing.assert_allclose(response_model(d, r)(inverse_response(d, r, x)), x, atol=1e-12)
        outside = np.array([-0.5, 1.5, 7.0])
        np.testing.assert_array_equal(inverse_response(d, r, outside), outside)


class TestLutAccuracy:
    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_red_is_linear_within_0_1_percent_after_the_lut(self, encoding):
        m = measurements_from_dict(document_with_ramps())
        block = fit_linearity(m.ramps, m.SL)
        lut = lut_table(block, encoding)
        assert lut.table.shape[0] <= 4095
        x = np.linspace(0, 1, 100001)
        out = lut_drive(lut, np.repeat(x[:, None], 3, axis=1))
        # The simulated wall's own curve, not the fitted one: 0.1% of the top step.
        assert np.max(np.abs(red_curve(out[:, 0]) - x)) < 1e-3
        assert np.max(np.abs(red_curve(x) - x)) > 0.03  # uncorrected: 3.5%
        np.testing.assert_allclose(
            out[:, 1:], np.repeat(x[:, None], 2, axis=1), rtol=2e-6, atol=1e-9
        )
        # Above drive 1.0 (HDR) the LUT passes drive unchanged up to the signal's own ceiling
        # (but for the interval holding 1.0, which is not a knot: 5e-5 there).
        top = {"linear": 16.0, "pq": 10.0}.get(encoding, 1.0)
        hdr = np.linspace(1, top, 57)
        np.testing.assert_allclose(
            lut_drive(lut, np.repeat(hdr[:, None], 3, 1)), np.repeat(hdr[:, None], 3, 1), rtol=1e-4
        )


# --------------------------------------------------------------------------------------------
# Written configs, checked through OCIO, ociocheck, ociochecklut and oiiotool.


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The CLI run on a measurements file with a non-linear red ramp, for each encoding."""
    root = tmp_path_factory.mktemp("linearity")
    path = root / "m.json"
    path.write_text(json.dumps(document_with_ramps()))
    out = {}
    for encoding in ("linear", "gamma2.4", "srgb", "pq"):
        folder = root / encoding
        args = ["solve", str(path), "--out", str(folder), "--wall-encoding", encoding]
        # the linearity LUT does not depend on Q: auto's pick here (regularised), without
        # auto's comparison of every model
        assert main([*args, "--method", "regularised"]) == 0
        out[encoding] = folder / "env_0"
    return out


def config_of(folder: Path) -> OCIO.Config:
    return OCIO.Config.CreateFromFile(str(folder / "config.ocio"))


def lut_file(folder: Path) -> Path:
    (lut,) = (folder / "luts").glob("*.clf")
    return lut


class TestWrittenConfig:
    def test_the_lut_through_ocio_matches_the_numpy_model(self, written):
        folder = written["linear"]
        solution = load_solution(folder)
        lut = lut_table(solution.linearity, "linear")
        config = config_of(folder)
        cpu = config.getProcessor(
            OCIO.FileTransform(src=lut_file(folder).name)
        ).getDefaultCPUProcessor()
        rgb = np.random.default_rng(1).uniform(-0.2, 20.0, size=(4000, 3))
        rgb[:1000] = np.random.default_rng(2).uniform(0, 1, size=(1000, 3))
        rgb[1000:1100] = np.geomspace(1e-4, 1e-2, 300).reshape(100, 3)
        # OCIO's default optimisation computes the log2 shaper with a fast log (8e-7 in the
        # shaper's [0, 1], 1e-5 of the drive); lossless agrees to 1e-6
        np.testing.assert_allclose(apply(cpu, rgb), apply_lut(lut, rgb), rtol=3e-5, atol=1e-7)

    @pytest.mark.parametrize("encoding", ["linear", "pq"])
    def test_the_sidecar_is_a_shaper_and_a_lut_of_at_most_4095_entries(self, written, encoding):
        import xml.etree.ElementTree as ET

        root = ET.parse(lut_file(written[encoding])).getroot()
        nodes = [
            child.tag.split("}")[-1] for child in root if child.tag.split("}")[-1] != "Description"
        ]
        assert nodes == (["Log", "LUT1D"] if encoding == "linear" else ["LUT1D"])
        (lut,) = [child for child in root if child.tag.endswith("LUT1D")]
        (array,) = [child for child in lut if child.tag.endswith("Array")]
        entries, channels = map(int, array.get("dim").split())
        assert channels == 3 and entries <= 4095
        assert entries == load_solution(written[encoding]).linearity.lut.entries

    def test_rewriting_a_loaded_solution_gives_the_same_sidecar(self, written, tmp_path):
        folder = written["pq"]
        write_solutions([load_solution(folder)], tmp_path)
        again = tmp_path / folder.name
        assert lut_file(again).read_text() == lut_file(folder).read_text()
        assert (
            json.loads((again / "solution.json").read_text())["linearity"]
            == json.loads((folder / "solution.json").read_text())["linearity"]
        )

    @needs_tools
    def test_ociochecklut_matches_the_numpy_model(self, written):
        folder = written["pq"]
        solution = load_solution(folder)
        lut = lut_table(solution.linearity, "pq")
        # the PQ sidecar takes and returns PQ signal
        for rgb in ([0.01, 0.2, 0.3], [0.37, 0.5, 0.999], [0.75, 0.8, 0.9], [-0.1, 0.0, 0.002]):
            text = subprocess.run(
                ["ociochecklut", str(lut_file(folder)), *map(str, rgb)],
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            got = np.array([float(v) for v in text.split()[-3:]])
            expected = apply_lut(lut, decode(np.array(rgb), "pq"))
            np.testing.assert_allclose(got, expected, atol=1e-5)

    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_wall_colorspaces_match_matrix_lut_encoding(self, written, encoding):
        folder = written[encoding]
        solution = load_solution(folder)
        lut = lut_table(solution.linearity, encoding)
        config = config_of(folder)
        c = np.random.default_rng(4).uniform(0.0, 1.0, size=(500, 3)) @ solution.SL.T
        for name, matrix, offset in (
            (OUT_OF_FRUSTUM, solution.M, np.zeros(3)),
            (IN_FRUSTUM, solution.in_frustum_matrix, solution.in_frustum_offset),
        ):
            drive = lut_drive(lut, c @ matrix.T + offset)
            if encoding == "pq":  # independent: colour-science's ST 2084, in cd/m2
                expected = colour.models.eotf_inverse_ST2084(np.maximum(drive, 0) * 1000.0)
            elif encoding == "gamma2.4":  # independent: BT.1886 with a zero black is x^(1/2.4)
                expected = colour.models.eotf_inverse_BT1886(np.maximum(drive, 0), L_B=0, L_W=1)
            elif encoding == "srgb":  # independent: IEC 61966-2-1
                expected = colour.models.eotf_inverse_sRGB(np.maximum(drive, 0))
            else:
                expected = drive
            # OCIO's sRGB is the moncurve (gamma 2.4, offset 0.055): IEC's within 1e-5. A linear
            # wall's drive above 1 goes through OCIO's fast log2 shaper, ~1e-5 *relative*.
            # OCIO's ST 2084 near black (~0.2 cd/m2) is 2.6e-5 from colour-science's (measured).
            atol = {"srgb": 2e-5, "pq": 5e-5}.get(encoding, 1e-5)
            np.testing.assert_allclose(
                apply(processor(config, REFERENCE, name), c), expected, atol=atol, rtol=2e-5
            )
            np.testing.assert_allclose(apply_lut(lut, c @ matrix.T + offset), expected, atol=1e-9)

    @needs_tools
    def test_ociocheck_passes_and_fails_without_the_lut(self, written, tmp_path):
        folder = written["gamma2.4"]
        run = subprocess.run(
            ["ociocheck", "--iconfig", str(folder / "config.ocio")], capture_output=True, text=True
        )
        assert run.returncode == 0, run.stdout + run.stderr
        broken = tmp_path / "broken"
        shutil.copytree(folder, broken)
        lut_file(broken).unlink()
        run = subprocess.run(
            ["ociocheck", "--iconfig", str(broken / "config.ocio")], capture_output=True, text=True
        )
        assert run.returncode != 0
        assert "could not be located" in run.stdout + run.stderr

    @needs_tools
    def test_oiiotool_applies_it_to_an_exr_identically(self, written, tmp_path):
        import OpenImageIO as oiio

        folder = written["linear"]
        solution = load_solution(folder)
        rng = np.random.default_rng(5)
        pixels = (rng.uniform(0, 1.2, size=(16, 24, 3)) @ solution.SL.T).astype(np.float32)
        source, target = tmp_path / "in.exr", tmp_path / "out.exr"
        spec = oiio.ImageSpec(24, 16, 3, oiio.FLOAT)
        image = oiio.ImageOutput.create(str(source))
        assert image.open(str(source), spec) and image.write_image(pixels) and image.close()
        subprocess.run(
            [
                "oiiotool",
                "--colorconfig",
                str(folder / "config.ocio"),
                str(source),
                "--colorconvert",
                REFERENCE,
                OUT_OF_FRUSTUM,
                "-d",
                "float",
                "-o",
                str(target),
            ],
            check=True,
            capture_output=True,
        )
        result = oiio.ImageInput.open(str(target)).read_image("float")
        expected = apply(
            processor(config_of(folder), REFERENCE, OUT_OF_FRUSTUM), pixels.reshape(-1, 3)
        )
        np.testing.assert_allclose(result.reshape(-1, 3), expected, atol=1e-5)
        assert np.max(np.abs(expected - pixels.reshape(-1, 3) @ solution.M.T)) > 1e-3  # LUT is in


class TestEndToEnd:
    """Content c through the written config and the simulated non-linear wall reaches the camera
    as c (out-of-frustum) and as [SL](N c + offset) (in-frustum), as on a linear wall."""

    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_content_reaches_the_camera_unchanged(self, written, encoding):
        folder = written[encoding]
        solution = load_solution(folder)
        SL = solution.SL
        config = config_of(folder)
        drive = np.random.default_rng(6).uniform(0.0, 1.0, size=(2000, 3))
        drive[:5] = [[1, 1, 1], [0.39, 0.39, 0.39], [0.02, 0.5, 0.9], [0, 0, 0], [0.001, 0.3, 1]]
        c = drive @ SL.T  # content the wall can show: M c in [0, 1]

        def decode(signal):
            if encoding == "pq":
                return colour.models.eotf_ST2084(signal) / 1000.0
            if encoding == "gamma2.4":
                return np.maximum(signal, 0) ** 2.4
            if encoding == "srgb":
                return colour.models.eotf_sRGB(signal)
            return signal

        signal = apply(processor(config, REFERENCE, OUT_OF_FRUSTUM), c)
        camera = simulated_wall(decode(signal), SL)
        assert np.max(np.abs(camera - c)) < 1e-3
        assert np.max(np.abs(simulated_wall(drive, SL) - c)) > 0.02  # without the LUT

        signal = apply(processor(config, REFERENCE, IN_FRUSTUM), c)
        inner = c @ solution.in_frustum_matrix.T + solution.in_frustum_offset
        shown = (inner >= 0) & (inner <= 1)
        rows = np.all(shown, axis=1)
        assert rows.sum() > 100
        camera = simulated_wall(decode(signal), SL)
        assert np.max(np.abs(camera[rows] - inner[rows] @ SL.T)) < 1e-3

    def test_hdr_drive_above_one_is_not_clamped(self, written):
        folder = written["pq"]
        solution = load_solution(folder)
        drive = np.array([[3.0, 5.0, 8.0], [1.5, 9.5, 2.0]])
        c = drive @ solution.SL.T
        signal = apply(processor(config_of(folder), REFERENCE, OUT_OF_FRUSTUM), c)
        np.testing.assert_allclose(colour.models.eotf_ST2084(signal) / 1000.0, drive, rtol=1e-4)


class TestCommandLine:
    @pytest.mark.parametrize(
        ("mutate", "message"),
        [
            (
                lambda r: r["red"]["drive"].__setitem__(3, 0.01),
                "ramps.red.drive[3]: drive values must increase strictly",
            ),
            (
                lambda r: r["red"]["camera"].__setitem__(5, [0.0, 0.0, 0.0]),
                "ramps.red.camera[5]: response not monotone",
            ),
            (
                lambda r: r["green"].update(drive=[0, 0.5, 1], camera=[[0, 0, 0]] * 3),
                "ramps.green.drive: has 3 steps; at least 4",
            ),
            (
                lambda r: r["blue"]["camera"].__setitem__(-1, [0, 0, 0]),
                f"ramps.blue.camera[{STEPS - 1}]: the top step is black",
            ),
        ],
    )
    def test_bad_ramps_exit_2_with_one_clear_line(self, tmp_path, capsys, mutate, message):
        document = document_with_ramps()
        mutate(document["ramps"])
        path = tmp_path / "m.json"
        path.write_text(json.dumps(document))
        out = tmp_path / "out"
        assert main(["solve", str(path), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"ocio-vp solve: error: {path}: {message}")
        assert err.count("\n") == 1 and "Traceback" not in err
        assert not out.exists()

    def test_installed_command_exits_2(self, tmp_path):
        document = document_with_ramps(steps=3)
        path = tmp_path / "m.json"
        path.write_text(json.dumps(document))
        run = subprocess.run(
            [sys.executable, "-m", "ocio_vp.cli", "solve", str(path), "--out", str(tmp_path / "o")],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 2
        assert "ramps.red.drive: has 3 steps" in run.stderr

    def test_bad_peak_nits(self, tmp_path, capsys):
        path = tmp_path / "m.json"
        path.write_text(json.dumps(document_with_ramps()))
        assert (
            main(
                [
                    "solve",
                    str(path),
                    "--out",
                    str(tmp_path / "o"),
                    "--wall-encoding",
                    "pq",
                    "--peak-nits",
                    "0",
                ]
            )
            == 2
        )
        assert "--peak-nits" in capsys.readouterr().err

    def test_encoding_without_ramps_has_no_lut(self):
        m = measurements_from_dict(make_measurements_dict())
        solution = with_wall_encoding(solve_environment(m, m.environments[0]), "gamma2.4")
        outputs = wall_outputs(solution)
        assert outputs.files == {} and outputs.search_path is None
        assert outputs.linearity.measured is False
        (chain,) = {len(v) for v in outputs.extra_wall_transforms.values()}
        assert chain == 1
