"""Ramps as a camera delivers them: the black it subtracts (a zero step reading slightly
negative), noise, dips and crushed blacks, what is reported, and the shadows after the LUT.

Ground truth is a simulated wall whose channels are too dark in the shadows, as measured real
walls are (13-36% dark at 2% of peak): ``r(d) = d (1 - a exp(-d / 0.05))``, normalised at the
top step. The camera sees ``[SL] r(d)`` plus a black offset, with noise proportional to the
level (0.5-2%) plus a floor. Ramps are spaced evenly in PQ code values, as ramp generators
make them (dense near black). One real ramp, OpenVPCal's published ROE-wall capture, checks
that real data solves without hand cleaning.
"""

from __future__ import annotations

import contextlib
import io
import json
import shutil
import subprocess

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.formats.records import json_value
from ocio_vp.ocio.config import OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.wall.encoding import decode, encode
from ocio_vp.wall.linearity import (
    DETECTION_SIGMAS,
    estimate_noise,
    fit_linearity,
    parse_ramps,
    ramps_to_dict,
    response_model,
)

CHANNELS = ("red", "green", "blue")
DARK = (0.3, 0.15, 0.35)  # how dark each channel is near black (fraction of the level)
BLACK = np.array([-0.0026, -0.0020, -0.0031])  # camera black after its own black subtraction
STEPS = 30


def shadow_wall(d, k: int):
    d = np.asarray(d, dtype=np.float64)
    return d * (1 - DARK[k] * np.exp(-d / 0.05)) / (1 - DARK[k] * np.exp(-1 / 0.05))


def pq_spaced_drive(steps: int = STEPS) -> np.ndarray:
    drive = decode(np.linspace(0.0, float(encode(1.0, "pq")), steps), "pq")
    drive[-1] = 1.0
    return drive


def SL_of(document: dict) -> np.ndarray:
    return np.array([document["primaries"][c] for c in CHANNELS]).T


def camera_ramps(
    SL, drive, *, relative=0.0, floor=0.0, black=BLACK, seed=0, curve=shadow_wall
) -> dict:
    """Camera RGB of each channel's ramp: ``[SL] r(d)`` with noise, plus the camera's black."""
    rng = np.random.default_rng(seed)
    ramps = {}
    for k, c in enumerate(CHANNELS):
        level = curve(drive, k)
        level = level * (1 + rng.normal(0, relative, len(drive))) + rng.normal(0, floor, len(drive))
        level[-1] = curve(1.0, k)  # the top step is the primaries' capture
        ramps[c] = {"drive": drive.tolist(), "camera": (np.outer(level, SL[:, k]) + black).tolist()}
    return ramps


def fitted(ramps: dict, document: dict | None = None) -> dict:
    """The fitted block as solution.json holds it (what pipeline scripts read)."""
    document = document or make_measurements_dict()
    document["ramps"] = ramps
    m = measurements_from_dict(document, source="m.yaml")
    return json_value(fit_linearity(m.ramps, m.SL, source="m.yaml"))


# --------------------------------------------------------------------------------------------


class TestBlack:
    def test_a_negative_zero_step_is_subtracted_and_named(self):
        SL = SL_of(make_measurements_dict())
        drive = pq_spaced_drive()
        block = fitted(camera_ramps(SL, drive))
        for k, c in enumerate(CHANNELS):
            channel = block["channels"][c]
            # Closed form: without noise the black-subtracted response is the wall's own.
            np.testing.assert_allclose(
                channel["measured_response"], shadow_wall(drive, k), atol=1e-12
            )
            assert channel["black"]["source"] == "zero step"
            np.testing.assert_allclose(channel["black"]["camera"], BLACK, rtol=1e-12)
            s = SL[:, k]
            assert channel["black"]["level"] == pytest.approx((BLACK @ s) / (s @ s), rel=1e-9)
            assert channel["black"]["level"] < 0
        assert any(n.startswith("red: black (zero step) camera [-0.0026") for n in block["notes"])

    def test_a_separate_black_frame_does_the_zero_steps_job(self):
        SL = SL_of(make_measurements_dict())
        drive = pq_spaced_drive()
        with_zero = fitted(camera_ramps(SL, drive))
        ramps = camera_ramps(SL, drive)
        for c in CHANNELS:
            ramps[c] = {"drive": ramps[c]["drive"][1:], "camera": ramps[c]["camera"][1:]}
        ramps["black"] = BLACK.tolist()
        with_frame = fitted(ramps)
        for c in CHANNELS:
            assert with_frame["channels"][c]["black"]["source"] == "black frame"
            np.testing.assert_allclose(
                with_frame["channels"][c]["response"],
                with_zero["channels"][c]["response"],
                atol=1e-12,
            )
        assert ramps_to_dict(parse_ramps(ramps))["black"] == BLACK.tolist()


class TestNoise:
    @pytest.mark.parametrize(("relative", "floor"), [(0.01, 1e-4), (0.02, 1e-5), (0.005, 5e-4)])
    def test_the_estimate_finds_the_floor_and_the_relative_part(self, relative, floor):
        # Known noise on a 40-step PQ-spaced ramp (dense near black, so the floor shows):
        # the median estimate over 20 draws is within 30% of each part.
        drive = pq_spaced_drive(40)
        floors, relatives = [], []
        for seed in range(20):
            rng = np.random.default_rng(seed)
            r = drive**1.1 * (1 + rng.normal(0, relative, 40)) + rng.normal(0, floor, 40)
            estimate = estimate_noise(drive, r)
            floors.append(estimate[0])
            relatives.append(estimate[1])
        assert np.median(floors) == pytest.approx(floor, rel=0.3)
        assert np.median(relatives) == pytest.approx(relative, rel=0.3)

    def test_a_given_noise_floor_wins(self):
        SL = SL_of(make_measurements_dict())
        ramps = camera_ramps(SL, pq_spaced_drive())
        ramps["noise_floor"] = 0.002
        block = fitted(ramps)
        green = block["channels"]["green"]
        assert green["noise"]["floor"] == 0.002 and green["noise"]["source"] == "given"
        assert green["noise"]["detection_limit"] == pytest.approx(DETECTION_SIGMAS * 0.002)
        # every step below 0.6% of the top step is dropped, and only those
        measured = green["measured_response"]
        expected = [i for i in range(1, STEPS - 1) if measured[i] < 0.006]
        assert len(expected) > 5 and green["below_floor"] == expected
        assert green["response"][1] >= 0.006


class TestMonotoneFit:
    def test_a_jittery_ramp_is_merged_not_refused(self):
        # Steps 10 and 11 swapped by less than the (given) noise: one knot at their mean.
        SL = SL_of(make_measurements_dict())
        drive = np.linspace(0, 1, 17)
        ramps = camera_ramps(SL, drive, black=np.zeros(3), curve=lambda d, k: d)
        cam = np.array(ramps["red"]["camera"])
        cam[[10, 11]] = cam[[11, 10]] * np.array([[1.0], [1.0]])
        ramps["red"]["camera"] = cam.tolist()
        ramps["noise_floor"] = 0.01  # the swap (6.25% of the top step) is within 4 + 4 sigma
        channel = fitted(ramps)["channels"]["red"]
        assert channel["merged"] == [[10, 11]]
        knots_d, knots_r = np.array(channel["drive"]), np.array(channel["response"])
        assert np.all(np.diff(knots_d) > 0) and np.all(np.diff(knots_r) > 0)
        # closed form: the pool is the mean of the two steps weighted by 1 / sigma^2
        noise, measured = channel["noise"], np.array(channel["measured_response"])[[10, 11]]
        weights = 1 / (noise["floor"] ** 2 + (noise["relative"] * measured) ** 2)
        i = int(np.argmin(np.abs(knots_d - (drive[10] + drive[11]) / 2)))
        assert knots_d[i] == pytest.approx(np.average(drive[[10, 11]], weights=weights), rel=1e-12)
        assert knots_r[i] == pytest.approx(np.average(measured, weights=weights), rel=1e-12)
        assert len(knots_d) == 16  # 17 steps, two of them pooled

    def test_crushed_blacks_are_dropped_and_named_not_fatal(self):
        # The panel shows nothing below drive 0.0005 (crushed), reads -1e-5 there after black.
        SL = SL_of(make_measurements_dict())
        drive = pq_spaced_drive()

        def crushed(d, k):
            return np.where(d < 5e-4, -1e-5, shadow_wall(d, k))

        ramps = camera_ramps(SL, drive, curve=crushed)
        ramps["noise_floor"] = 5e-5
        block = fitted(ramps)
        expected = [i for i in range(1, STEPS) if drive[i] < 5e-4]
        assert expected  # the PQ ramp has steps there
        for c in CHANNELS:
            assert block["channels"][c]["below_floor"] == expected
            assert block["channels"][c]["response"][1] >= DETECTION_SIGMAS * 5e-5
        assert any("below the detection limit" in note for note in block["notes"])

    def test_a_ramp_falling_by_more_than_the_noise_is_refused(self):
        SL = SL_of(make_measurements_dict())
        ramps = camera_ramps(SL, pq_spaced_drive(), relative=0.01, floor=1e-4, seed=3)
        cam = np.array(ramps["blue"]["camera"])
        cam[20] = (cam[19] - BLACK) * 0.8 + BLACK  # 20% below the step before
        ramps["blue"]["camera"] = cam.tolist()
        with pytest.raises(InputError) as error:
            fitted(ramps)
        assert error.value.key == "ramps.blue.camera[20]"
        assert "response not monotone" in error.value.problem
        assert "not noise" in error.value.problem


class TestTopStepAndPrimaries:
    def test_a_22_percent_mismatch_warns(self):
        document = make_measurements_dict()
        SL = SL_of(document)
        ramps = camera_ramps(SL, pq_spaced_drive(), relative=0.005, floor=1e-5)
        ramps["red"]["camera"] = (
            (np.array(ramps["red"]["camera"]) - BLACK) * 1.22 + BLACK
        ).tolist()
        block = fitted(ramps, document)
        assert block["channels"]["red"]["top_step_vs_primary"] == pytest.approx(0.22, abs=1e-4)
        (warning,) = block["warnings"]
        assert warning.startswith("ramps.red: the top step differs from primaries.red by 22%")

    def test_a_far_top_step_is_refused_saying_by_how_much(self):
        SL = SL_of(make_measurements_dict())
        ramps = camera_ramps(SL, pq_spaced_drive())
        ramps["green"]["camera"] = (
            (np.array(ramps["green"]["camera"]) - BLACK) * 0.3 + BLACK
        ).tolist()
        with pytest.raises(InputError, match=r"differs from primaries\.green by 70%"):
            fitted(ramps)


class TestShadowDeviation:
    def test_a_channel_50_percent_dark_below_0_4_percent_of_peak_is_corrected(self):
        # Largest absolute deviation 0.5 * 0.002 / e = 0.037% of the top step: under the 0.2%
        # tolerance, but 50% of the level near black. It must be corrected and said so.
        SL = SL_of(make_measurements_dict())

        def curve(d, k):
            return d * (1 - 0.5 * np.exp(-d / 0.002)) if k == 0 else d

        block = fitted(camera_ramps(SL, pq_spaced_drive(), curve=curve))
        red = block["channels"]["red"]
        assert red["max_deviation"] < 0.002 and red["corrected"]
        assert [block["channels"][c]["corrected"] for c in CHANNELS] == [True, False, False]
        d = red["shadow_deviation"]["drive"]
        assert red["shadow_deviation"]["relative"] == pytest.approx(-0.5 * np.exp(-d / 0.002))
        assert red["shadow_deviation"]["relative"] < -0.4
        text = f"red {100 * abs(red['shadow_deviation']['relative']):.3g}% (+-"
        assert text in block["summary"] and "dark at" in block["summary"]
        assert red["shadow_deviation"]["uncertainty"] < 0.05  # noiseless: the curvature's


# --------------------------------------------------------------------------------------------
# The written config: ramps straight from the camera, solved by the command line.


@pytest.fixture(scope="module")
def realistic(tmp_path_factory):
    """Noisy PQ-spaced ramps (1% of the level + 0.01% of peak), a negative zero step, solved
    for each wall encoding; returns the terminal output and the environment folder."""
    root = tmp_path_factory.mktemp("ramps")
    document = make_measurements_dict(environments=1)
    document["ramps"] = camera_ramps(
        SL_of(document), pq_spaced_drive(), relative=0.01, floor=1e-4, seed=1
    )
    path = root / "m.json"
    path.write_text(json.dumps(document))
    out = {}
    for encoding in ("linear", "gamma2.4", "srgb", "pq"):
        folder = root / encoding
        terminal = io.StringIO()
        with contextlib.redirect_stdout(terminal):
            status = main(["solve", str(path), "--out", str(folder), "--wall-encoding", encoding])
        assert status == 0
        out[encoding] = (terminal.getvalue(), folder / "env_0")
    return out


def decode_independently(signal: np.ndarray, encoding: str, peak: float = 1000.0) -> np.ndarray:
    """The wall's decoding by colour-science (PQ: ``peak`` cd/m2 for drive 1.0)."""
    if encoding == "pq":
        return colour.models.eotf_ST2084(signal) / peak
    if encoding == "gamma2.4":
        return colour.models.eotf_BT1886(np.maximum(signal, 0), L_B=0, L_W=1)
    if encoding == "srgb":
        return colour.models.eotf_sRGB(signal)
    return signal


def linearised(folder, encoding: str, x: np.ndarray, peak: float = 1000.0) -> np.ndarray:
    """Grey content at linear level ``x`` through the written config (OCIO's processor), decoded
    as the wall does, through each channel's fitted response: what the wall emits (n, 3)."""
    solution = json.loads((folder / "solution.json").read_text())
    config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
    cpu = config.getProcessor(REFERENCE, OUT_OF_FRUSTUM).getDefaultCPUProcessor()
    M = np.array(solution["M"])
    content = np.linalg.solve(M, np.repeat(x[:, None], 3, axis=1).T).T  # M content = x
    pixels = np.ascontiguousarray(content, dtype=np.float32)
    cpu.applyRGB(pixels)
    drive = decode_independently(pixels.astype(np.float64), encoding, peak)
    channels = solution["linearity"]["channels"]
    return np.stack(
        [
            response_model(channels[c]["drive"], channels[c]["response"])(
                np.clip(drive[:, k], 0, 1)
            )
            for k, c in enumerate(CHANNELS)
        ],
        axis=1,
    )


class TestWrittenConfig:
    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_solves_without_hand_cleaning_and_names_what_it_did(self, realistic, encoding):
        stdout, folder = realistic[encoding]
        linearity = json.loads((folder / "solution.json").read_text())["linearity"]
        for c in CHANNELS:
            channel = linearity["channels"][c]
            assert channel["black"]["source"] == "zero step" and channel["black"]["level"] < 0
            assert channel["below_floor"]  # the darkest PQ steps are under 0.03% of peak
            assert f"{c}: black (zero step) camera [" in stdout
        assert "below the detection limit" in stdout
        assert linearity["notes"] and all(note in stdout for note in linearity["notes"])
        assert "linearity: red, green, blue deviate from linear" in stdout

    @pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "srgb", "pq"])
    def test_the_shadows_follow_the_measured_ramp(self, realistic, encoding):
        _, folder = realistic[encoding]
        x = np.geomspace(0.001, 1.0, 4001)
        emitted = linearised(folder, encoding, x)
        error = np.max(np.abs(emitted / x[:, None] - 1), axis=1)
        assert np.max(error[x >= 0.02]) < 0.005
        assert np.max(error[(x >= 0.002) & (x < 0.02)]) < 0.03
        # lut.max_error says the same thing (its numpy model vs OCIO's float32 run; for sRGB
        # OCIO's moncurve is IEC 61966-2-1 within 0.025% of the level, see TestSrgb)
        lut = json.loads((folder / "solution.json").read_text())["linearity"]["lut"]
        assert lut["max_error"] < 0.005
        assert np.max(error[x >= 0.002]) == pytest.approx(lut["max_error"], abs=3e-4)
        # and at the measured steps themselves (the knots the monotone fit kept)
        channel = json.loads((folder / "solution.json").read_text())["linearity"]["channels"]
        steps = np.array(channel["red"]["response"][1:-1])
        steps = steps[steps >= 0.002]
        at_steps = linearised(folder, encoding, steps)[:, 0]
        np.testing.assert_allclose(at_steps, steps, rtol=0.005)

    def test_without_the_lut_the_shadows_are_off(self, realistic):
        _, folder = realistic["linear"]
        channels = json.loads((folder / "solution.json").read_text())["linearity"]["channels"]
        model = response_model(channels["blue"]["drive"], channels["blue"]["response"])
        assert model(0.01) / 0.01 < 0.8  # 26% dark at 1% of peak before the LUT

    @pytest.mark.skipif(not shutil.which("ociochecklut"), reason="ociochecklut not on PATH")
    def test_ociochecklut_reads_the_sidecar_as_ocio_does(self, realistic):
        _, folder = realistic["pq"]
        (lut,) = (folder / "luts").glob("*.clf")
        cpu = (
            OCIO.Config.CreateRaw()
            .getProcessor(OCIO.FileTransform(src=str(lut)))
            .getDefaultCPUProcessor()
        )
        for rgb in ([0.05, 0.1, 0.2], [0.3, 0.5, 0.7518], [0.8, 0.9, 1.0]):
            text = subprocess.run(
                ["ociochecklut", str(lut), *map(str, rgb)],
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            got = [float(v) for v in text.split()[-3:]]
            np.testing.assert_allclose(got, cpu.applyRGB(list(map(float, rgb))), atol=1e-6)


class TestTruth:
    def test_low_noise_ramps_linearise_the_simulated_wall(self, tmp_path):
        # 0.1% of the level, 0.001% of peak, 40 steps: the corrected wall (its true curve,
        # not the fit) is linear within 0.5% above 2% of peak and 3% from 0.2%. (With more
        # noise the LUT follows the measured ramp, noise included: docs/linearity.md.)
        document = make_measurements_dict(environments=1)
        document["ramps"] = camera_ramps(
            SL_of(document), pq_spaced_drive(40), relative=0.001, floor=1e-5, seed=5
        )
        path = tmp_path / "m.json"
        path.write_text(json.dumps(document))
        assert (
            main(["solve", str(path), "--out", str(tmp_path / "o"), "--wall-encoding", "pq"]) == 0
        )
        folder = tmp_path / "o" / "env_0"
        solution = json.loads((folder / "solution.json").read_text())
        config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
        cpu = config.getProcessor(REFERENCE, OUT_OF_FRUSTUM).getDefaultCPUProcessor()
        x = np.geomspace(0.002, 1.0, 2001)
        content = np.linalg.solve(np.array(solution["M"]), np.repeat(x[:, None], 3, 1).T).T
        pixels = np.ascontiguousarray(content, dtype=np.float32)
        cpu.applyRGB(pixels)
        drive = colour.models.eotf_ST2084(pixels.astype(np.float64)) / 1000.0
        emitted = np.stack([shadow_wall(drive[:, k], k) for k in range(3)], axis=1)
        error = np.abs(emitted / x[:, None] - 1)
        assert np.max(error[x >= 0.02]) < 0.005
        assert np.max(error[x < 0.02]) < 0.03
        assert (
            np.max(np.abs(np.stack([shadow_wall(x, k) for k in range(3)], 1) / x[:, None] - 1))
            > 0.2
        )


# --------------------------------------------------------------------------------------------
# A real capture.

# The grey ramp of an ROE wall at 1650 cd/m2 (RED camera), from Netflix's OpenVPCal test data:
# tests/test_open_vp_cal/resources/SampleProject2_External_White_NoLens/export/results/
# Wall_1_ROE_calibration_results.json (commit 18a63be), keys EOTF_ramp (camera RGB) and
# EOTF_ramp_signal (the ramp's levels, cd/m2 / 100). Each camera channel is taken as its LED
# channel's response (an approximation: the grey is not split by the primaries here).
ROE_RAMP = [
    [-0.00015323962240169445, -0.0001641548345408713, -0.0001305273084047561],
    [-0.00014425058907363564, -0.00015709180540094772, -0.00012307996318365136],
    [-0.00012852026945135245, -0.0001441627440120404, -0.0001101228772313334],
    [-8.871835598256439e-05, -0.00010870869543092947, -7.447438353362183e-05],
    [-1.9318697619989205e-05, -4.647375196024465e-05, -1.0037940228357911e-05],
    [7.98556914863487e-05, 4.7699784772703424e-05, 7.961244409671053e-05],
    [0.00024389474128838629, 0.00020125499092197666, 0.00022802404904117188],
    [0.0004894801725943884, 0.00044568435987457633, 0.00045138302569588024],
    [0.0008696653336907426, 0.0008309872355312109, 0.0007867160796498259],
    [0.0014510581968352199, 0.001468267641030252, 0.0013131056912243366],
    [0.002157086661706368, 0.0024115506870051226, 0.001993964503829678],
    [0.003250019159168005, 0.0036521560978144407, 0.002987984800711274],
    [0.004924492444843054, 0.0056537240743637085, 0.004417025639365117],
    [0.007354441254089276, 0.008432582641641298, 0.006529107224196196],
    [0.010765823535621166, 0.012308194302022457, 0.009729261510074139],
    [0.015557744229833284, 0.017588296284278233, 0.014518191727499167],
    [0.022018397226929665, 0.024352683996160824, 0.021107894058028858],
    [0.029256947338581085, 0.03177065153916677, 0.028233718127012253],
    [0.040335532277822495, 0.04333172366023064, 0.038797413309415184],
    [0.05505946030219396, 0.058065383384625115, 0.05307117352883021],
    [0.07406674573818843, 0.07703234006961186, 0.07136452694733937],
    [0.09844179451465607, 0.10099593798319499, 0.09493538737297058],
    [0.13141351441542307, 0.13301928341388702, 0.12644290427366892],
    [0.17306972543398538, 0.17406025528907776, 0.16453845302263895],
    [0.21745323638121286, 0.21739613513151804, 0.20655923585096994],
    [0.2837851643562317, 0.2834674119949341, 0.2681870261828105],
    [0.368537575006485, 0.3687026898066203, 0.34957192341486615],
    [0.4770009120305379, 0.4775038758913676, 0.4554580549399058],
    [0.6173824270566305, 0.6175270477930704, 0.5898103912671407],
    [0.798679769039154, 0.8020247220993042, 0.764444092909495],
    [1.028392235438029, 1.03202223777771, 0.9862858255704244],
]
ROE_SIGNAL = [
    0.0, 0.00015745079765460497, 0.0007081855343506124, 0.001870049697154954,
    0.0039352396711109915, 0.007286770559066842, 0.012423000646325595, 0.019988574128201035,
    0.030813308264360875, 0.04596109659412105, 0.06679146770891407, 0.09503715500721834,
    0.13290195294339383, 0.1831843221903783, 0.2494337411918229, 0.33614879237933737,
    0.4490285609314556, 0.59529230323707, 0.7840867668742744, 1.0270063577613935,
    1.338759017533606, 1.7380208250591134, 2.2485358287453496, 2.900535626364466,
    3.7325773541850067, 4.79393126497281, 6.147693077247399, 7.874856119182107,
    10.079660094221294, 12.896645731202364, 16.50000000000105,
]  # fmt: skip


# The grey ramp of a 100-cd/m2 sRGB display, same source: tests/test_open_vp_cal/resources/
# Sample_Project10_SRGB_EOTF/export/results/Wall1_calibration_results.json (commit 18a63be).
SRGB_RAMP = [
    [-0.0001958321954589337, -0.00017131355222469816, -0.0001818425274298837],
    [-0.0001775320852175355, -0.00015315820443599174, -0.00016528395644854754],
    [-7.44651867231975e-05, -4.8622102137111746e-05, -6.714734384634842e-05],
    [9.383030070845659e-05, 0.00011668746446957812, 9.060870312775175e-05],
    [0.00036060733449024457, 0.0003872609716684868, 0.0003278455988038331],
    [0.0007848216337151825, 0.0008596468639249603, 0.0006935574541178843],
    [0.0015377053835739691, 0.0015529441880062222, 0.001438591085995237],
    [0.0028728858257333436, 0.0031648871954530478, 0.003304062799240152],
    [0.00447666272521019, 0.005018582101911306, 0.0053439270704984665],
    [0.006255862303078175, 0.006935941365857919, 0.007375346031039953],
    [0.008795754984021187, 0.009827538393437862, 0.010505415499210358],
    [0.011990095799167952, 0.013512729046245417, 0.014521120736996332],
    [0.015478731443484625, 0.017125384882092476, 0.01818910427391529],
    [0.020396515106161434, 0.022911425679922104, 0.024175407364964485],
    [0.026376869529485703, 0.029584220920999844, 0.03173942615588506],
    [0.033572595566511154, 0.03696966419617335, 0.03963554526368777],
    [0.042465085784594216, 0.046606371800104775, 0.04948031033078829],
    [0.053612579902013145, 0.058250922709703445, 0.061389503379662834],
    [0.0663772001862526, 0.07130035012960434, 0.07604573418696721],
    [0.08163263400395711, 0.087276391685009, 0.09356717516978581],
    [0.09974593669176102, 0.10618958622217178, 0.1145383616288503],
    [0.12125089019536972, 0.1286231279373169, 0.13931110501289368],
    [0.1465643992026647, 0.15523936847845712, 0.16880938907464346],
    [0.1768911431233088, 0.1866573045651118, 0.20396535595258078],
    [0.2114556630452474, 0.22300490736961365, 0.24482696751753488],
    [0.25299469629923504, 0.26619980732599896, 0.2933362325032552],
    [0.3001794119675954, 0.3155246277650197, 0.34867730736732483],
    [0.35628508528073627, 0.37432825565338135, 0.41435547669728595],
    [0.4221084713935852, 0.4433138271172841, 0.4919649064540863],
    [0.4966491957505544, 0.5214906930923462, 0.5799929896990458],
    [0.5849743286768595, 0.6176460385322571, 0.6827954848607382],
    [0.6883522669474283, 0.7292357285817465, 0.8031685551007589],
    [0.8057058850924174, 0.8535791834195455, 0.9463136196136475],
    [0.9418029189109802, 0.9942225416501363, 1.11541748046875],
]
SRGB_SIGNAL = [
    0.0, 5.205761493069468e-05, 0.00020874006133883547, 0.0005018826297021109,
    0.000971739779767154, 0.0016658791643220378, 0.0026400739963229514, 0.003959490383284056,
    0.005700072238582893, 0.007950126137581252, 0.010812128379047378, 0.014404784247584792,
    0.018865374990763392, 0.024352433478558182, 0.03104879553596461, 0.03916508080830536,
    0.04894366492370403, 0.06066321384133771, 0.07464386181827844, 0.09125312662255551,
    0.11091266973517948, 0.13410602563448953, 0.16138744321320098, 0.193392004377437,
    0.23084721043132375, 0.27458625656366925, 0.3255632493398715, 0.3848706624020455,
    0.4537593725932483, 0.5336616736235277, 0.6262177285892802, 0.7333059978014024,
    0.8570782664516443, 1.0000000000000524,
]  # fmt: skip
CAPTURES = {  # name: (camera RGB, levels, wall encoding, peak cd/m2)
    "roe-1650-pq": (ROE_RAMP, ROE_SIGNAL, "pq", 1650.0),
    "display-100-srgb": (SRGB_RAMP, SRGB_SIGNAL, "srgb", 100.0),
}


def capture_document(name: str) -> tuple[dict, np.ndarray, np.ndarray]:
    """A measurements document whose ramps are a real capture (each camera channel as its LED
    channel) and whose primaries are the top step, black subtracted."""
    camera, signal, _, _ = CAPTURES[name]
    camera = np.array(camera)
    drive = np.array(signal) / signal[-1]
    drive[-1] = 1.0
    document = make_measurements_dict(environments=1)
    SL = np.diag(camera[-1] - camera[0])
    document["primaries"] = {c: SL[:, k].tolist() for k, c in enumerate(CHANNELS)}
    document["ramps"] = {
        c: {"drive": drive.tolist(), "camera": np.where(np.eye(3)[k] > 0, camera, 0.0).tolist()}
        for k, c in enumerate(CHANNELS)
    }
    return document, camera, drive


class TestRealCapture:
    @pytest.mark.parametrize("name", list(CAPTURES))
    def test_solves_as_captured_and_the_config_follows_the_ramp(self, name, tmp_path):
        document, camera, drive = capture_document(name)
        _, _, encoding, peak = CAPTURES[name]
        path = tmp_path / "m.json"
        path.write_text(json.dumps(document))
        terminal = io.StringIO()
        nits = ["--peak-nits", str(peak)] if encoding == "pq" else []  # else it is refused
        with contextlib.redirect_stdout(terminal):
            status = main(
                ["solve", str(path), "--out", str(tmp_path / "o"), "--wall-encoding", encoding,
                 *nits]
            )  # fmt: skip
        assert status == 0
        assert "red: black (zero step) camera [-0.000" in terminal.getvalue()
        folder = tmp_path / "o" / "env_0"
        linearity = json.loads((folder / "solution.json").read_text())["linearity"]
        assert linearity["model"] != "linear" and not linearity["warnings"]
        for k, c in enumerate(CHANNELS):
            channel = linearity["channels"][c]
            assert channel["black"]["source"] == "zero step" and channel["black"]["level"] < 0
            expected = (camera[:, k] - camera[0, k]) / (camera[-1, k] - camera[0, k])
            np.testing.assert_allclose(channel["measured_response"], expected, rtol=1e-12)
        # through the written config, the wall's decoding and the fitted response: linear
        x = np.geomspace(0.002, 1.0, 2001)
        error = np.max(np.abs(linearised(folder, encoding, x, peak) / x[:, None] - 1), axis=1)
        assert np.max(error[x >= 0.02]) < 0.005 and np.max(error) < 0.03

    def test_the_roe_wall_solves_as_captured(self):
        camera = np.array(ROE_RAMP)
        drive = np.array(ROE_SIGNAL) / ROE_SIGNAL[-1]
        drive[-1] = 1.0
        document = make_measurements_dict()
        SL = np.diag(camera[-1] - camera[0])
        document["primaries"] = {c: SL[:, k].tolist() for k, c in enumerate(CHANNELS)}
        ramps = {
            c: {"drive": drive.tolist(), "camera": np.where(np.eye(3)[k] > 0, camera, 0.0).tolist()}
            for k, c in enumerate(CHANNELS)
        }
        block = fitted(ramps, document)
        assert block["model"] != "linear" and not block["warnings"]
        for k, c in enumerate(CHANNELS):
            channel = block["channels"][c]
            assert channel["black"]["camera"][k] == camera[0, k] < 0
            # independent: the black-subtracted, normalised camera channel
            expected = (camera[:, k] - camera[0, k]) / (camera[-1, k] - camera[0, k])
            np.testing.assert_allclose(channel["measured_response"], expected, rtol=1e-12)
            i = int(np.argmin(np.abs(drive - 0.02)))
            assert 0.1 < 1 - expected[i] / drive[i] < 0.4  # 15-27% dark at 2% of peak
            assert channel["shadow_deviation"]["relative"] < -0.1
