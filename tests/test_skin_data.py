"""The measured skin and its split (ocio_vp.skin_data), the physlight cameras, and the skin
benchmark's machinery (benchmarks.skin_eval): its ΔE against colour-science's, its ratios, and
where its held-out data lives."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks import replace_section
from benchmarks.skin_eval import (
    REFERENCE,
    TUNING_LED_SETS,
    Variant,
    evaluate,
    held_out_skin,
    summarise,
)
from ocio_vp.skin_data import (
    ITA_BANDS,
    band_of,
    ita_degrees,
    lab_d65,
    load_skin_file,
    physlight_camera_names,
    physlight_cameras,
    training_skin,
)
from ocio_vp.spectra import camera_names, camera_sensitivities, wavelengths

ROOT = Path(__file__).resolve().parents[1]
HELD_OUT = ROOT / "benchmarks" / "data" / "skin_held_out.json"
CAMERA = "Nikon 5100 (NPL)"


@pytest.fixture(scope="module")
def halves():
    return training_skin(), load_skin_file(HELD_OUT.read_text(encoding="utf-8"))


def _by_name(halves) -> dict[str, np.ndarray]:
    return {n: r for half in halves for n, r in zip(half.names, half.reflectances, strict=True)}


class TestData:
    def test_both_halves_load_on_the_grid_as_reflectances(self, halves) -> None:
        training, held_out = halves
        assert (training.split, held_out.split) == ("training", "held-out")
        for half in halves:
            assert half.reflectances.shape == (len(half.names), len(wavelengths()))
            assert np.all(np.isfinite(half.reflectances))
            assert np.all((half.reflectances > 0) & (half.reflectances < 1))

    def test_values_are_the_nist_averages_interpolated_onto_the_grid(self, halves) -> None:
        # NIST 1832_Data_JResNIST_skinrefl v3 (iadpython M38597.csv), "Average" columns:
        # subject 1: 0.1926 at 379 nm, 0.1958 at 382 nm, 0.3159 at 550 nm, 0.6027 at 778 nm,
        # 0.6042 at 781 nm; subject 50: 0.3649 at 550 nm; subject 100: 0.3610 at 550 nm.
        grid = wavelengths()
        spectra = _by_name(halves)
        s1 = spectra["NIST Subject 1"]
        assert s1[grid == 380.0][0] == pytest.approx(0.1926 + (0.1958 - 0.1926) / 3, abs=5e-5)
        assert s1[grid == 550.0][0] == 0.3159
        assert s1[grid == 780.0][0] == pytest.approx(0.6027 + 2 * (0.6042 - 0.6027) / 3, abs=5e-5)
        assert spectra["NIST Subject 50"][grid == 550.0][0] == 0.3649
        assert spectra["NIST Subject 100"][grid == 550.0][0] == 0.3610


class TestSplit:
    def test_the_halves_are_disjoint_and_together_all_100_subjects(self, halves) -> None:
        training, held_out = halves
        assert not set(training.names) & set(held_out.names)
        assert set(training.names) | set(held_out.names) == {
            f"NIST Subject {i}" for i in range(1, 101)
        }
        distance = np.abs(training.reflectances[:, None] - held_out.reflectances[None]).max(-1)
        assert distance.min() > 0  # no spectrum is in both halves under another name

    def test_recorded_bands_are_the_bands_of_the_spectra(self, halves) -> None:
        for half in halves:
            assert tuple(band_of(v) for v in half.ita()) == half.bands

    def test_split_is_stratified_over_lightness(self, halves) -> None:
        training, held_out = halves
        for band, _ in ITA_BANDS:
            n_train, n_held = training.bands.count(band), held_out.bands.count(band)
            if n_train + n_held == 1:
                assert n_held == 1  # a band's only subject is benchmarked
            else:
                assert abs(n_train - n_held) <= 1, band
        # Within a band, alternating in order of ITA: the halves' medians are close.
        for band in ("very light", "light", "intermediate"):
            medians = [np.median(h.ita()[np.array(h.bands) == band]) for h in halves]
            assert abs(medians[0] - medians[1]) < 3.0, band


class TestITA:
    def test_closed_form(self) -> None:
        # ITA = atan((L* - 50) / b*): 45° at L* 60, b* 10; 0° at L* 50; negative when darker.
        lab = np.array([[60.0, 5.0, 10.0], [50.0, 3.0, 20.0], [40.0, 8.0, 10.0]])
        np.testing.assert_allclose(ita_degrees(lab), [45.0, 0.0, -45.0], atol=1e-12)

    def test_lab_agrees_with_colour_science_colorimetry(self, halves) -> None:
        import colour

        shape = colour.SpectralShape(380, 780, 5)
        cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].copy().align(shape)
        d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
        white = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
        reflectances = halves[1].reflectances[:5]
        expected = []
        for values in reflectances:
            sd = colour.SpectralDistribution(dict(zip(wavelengths(), values, strict=True)))
            XYZ = colour.sd_to_XYZ(sd, cmfs, d65, method="Integration") / 100
            expected.append(colour.XYZ_to_Lab(XYZ, white))
        np.testing.assert_allclose(lab_d65(reflectances), expected, atol=0.02)

    @pytest.mark.parametrize(
        ("ita", "band"),
        [
            (70, "very light"),
            (55, "light"),
            (41.0001, "light"),
            (41, "intermediate"),
            (28, "tan"),
            (10, "brown"),
            (-30, "dark"),
            (-80, "dark"),
        ],
    )
    def test_bands_and_their_bounds(self, ita, band) -> None:
        assert band_of(ita) == band


class TestPhyslightCameras:
    def test_tuning_and_held_out_are_disjoint_and_known_by_name(self) -> None:
        tuning, held = physlight_camera_names("tuning"), physlight_camera_names("held-out")
        assert len(tuning) == len(held) == 16 and not set(tuning) & set(held)
        assert set(tuning) | set(held) <= set(camera_names())
        for name, values in physlight_cameras("held-out").items():
            np.testing.assert_array_equal(camera_sensitivities(name), values)
            assert np.all(values >= 0) and np.all(values.max(axis=0) > 0.1)

    def test_no_body_of_the_rawtoaces_file_again(self) -> None:
        raw = json.loads((ROOT / "ocio_vp" / "data" / "camera_sensitivities.json").read_text())
        bodies = {n.removesuffix(" (rawtoaces)") for n in raw["cameras"]}
        physlight = physlight_camera_names("tuning") + physlight_camera_names("held-out")
        assert not bodies & {n.removesuffix(" (physlight)") for n in physlight}

    def test_values_source_and_licence_are_physlight_s(self) -> None:
        # wetadigital/physlight data/camera/Sony_ILCE-9_380_780_5.json: 380 nm and 550 nm rows.
        values = camera_sensitivities("Sony ILCE-9 (physlight)")
        grid = wavelengths()
        np.testing.assert_allclose(
            values[grid == 380.0][0],
            [0.0001358554358391867, 0.00021197070005921737, 0.00024997895040082183],
            rtol=1e-15,
        )
        np.testing.assert_allclose(
            values[grid == 550.0][0],
            [0.04820013622211943, 0.901221971451837, 0.07325412333669672],
            rtol=1e-15,
        )
        document = json.loads(
            (ROOT / "ocio_vp" / "data" / "camera_sensitivities_physlight.json").read_text()
        )
        notice = (ROOT / "ocio_vp" / "data" / "CAMERAS_LICENSE.md").read_text(encoding="utf-8")
        assert "wetadigital/physlight" in notice
        for record in document["cameras"].values():
            assert record["licence"] == "Apache-2.0"
            assert record["source"].startswith("https://github.com/wetadigital/physlight/blob/")


# ---------------------------------------------------------------------------------------------
# The benchmark (benchmarks/skin_eval.py)


@pytest.fixture(scope="module")
def small():
    """Least squares and white-preserving, one camera, one LED set, two environments, no noise."""
    return evaluate(
        variant_list=[Variant(REFERENCE, REFERENCE), Variant("wp", "white-preserving")],
        environments=["d65", "incandescent"],
        cameras=[CAMERA],
        led_sets=TUNING_LED_SETS[:1],
        noise=0.0,
    )


def test_skin_delta_e_is_colour_sciences_ciede2000_of_the_stage(small) -> None:
    """Recompute one solve's skin ΔE2000 from the spectra with colour-science directly."""
    import colour

    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import (
        camera_rgb,
        environment_spectrum,
        simulate_measurements,
        spectral_stage,
    )
    from ocio_vp.skin_data import training_skin

    stage = spectral_stage(camera=CAMERA, leds=TUNING_LED_SETS[0])
    measurements = simulate_measurements(["d65", "incandescent"], stage=stage)
    env = measurements.environment("incandescent")
    solution = solve_environment(measurements, env, method="least-squares")
    skin = training_skin().reflectances
    light = environment_spectrum(stage, "incandescent")
    emitted = stage.leds @ np.clip(solution.M @ solution.w_avg, 0, None)
    corrected = camera_rgb(stage, skin * emitted) @ solution.Q.T
    target = camera_rgb(stage, skin * light)
    # Camera RGB -> XYZ: the least-squares fit of the camera to the CIE 1931 observer
    # (ocio_vp.metrics.camera_to_xyz_matrix), the scene white at Y = 1.
    from ocio_vp.metrics import camera_to_xyz_matrix

    matrix = camera_to_xyz_matrix(stage.camera)
    white = camera_rgb(stage, light) @ matrix.T
    scale = 1 / white[1]
    xy = colour.XYZ_to_xy(white * scale)
    expected = colour.delta_E(
        colour.XYZ_to_Lab(target @ matrix.T * scale, xy),
        colour.XYZ_to_Lab(corrected @ matrix.T * scale, xy),
        method="CIE 2000",
    )
    row = next(r for r in small.rows if r.variant == REFERENCE and r.environment == "incandescent")
    np.testing.assert_allclose(row.skin, expected, rtol=1e-9, atol=1e-9)
    assert row.bands == training_skin().bands


def test_ratios_are_to_least_squares_on_the_same_solves(small) -> None:
    ls, wp = summarise(small, REFERENCE), summarise(small, "wp")
    assert ls.skin_ratio == 1.0 and ls.cells_lost == 0 and ls.cells == 2
    rows = {(r.variant, r.environment): r for r in small.rows}
    for env in ("d65", "incandescent"):
        expected = rows[("wp", env)].skin_mean / rows[(REFERENCE, env)].skin_mean
        assert wp.by_environment_ratio[env] == pytest.approx(expected, rel=1e-12)
    mine = np.mean([rows[("wp", e)].skin_mean for e in ("d65", "incandescent")])
    theirs = np.mean([rows[(REFERENCE, e)].skin_mean for e in ("d65", "incandescent")])
    assert wp.skin_ratio == pytest.approx(mine / theirs, rel=1e-12)
    assert wp.cells_lost == sum(
        rows[("wp", e)].skin_mean > 1.02 * rows[(REFERENCE, e)].skin_mean
        for e in ("d65", "incandescent")
    )
    # Per band: the pooled samples of that band, both methods.
    band = "light"
    mask = np.array(rows[("wp", "d65")].bands) == band
    pooled = [
        np.concatenate([rows[(v, e)].skin[mask] for e in ("d65", "incandescent")])
        for v in ("wp", REFERENCE)
    ]
    assert wp.by_band_ratio[band] == pytest.approx(pooled[0].mean() / pooled[1].mean(), rel=1e-12)


def test_the_held_out_skin_is_outside_the_package() -> None:
    assert held_out_skin().split == "held-out"
    assert not list((ROOT / "ocio_vp").rglob("skin_held_out*"))
    for path in (ROOT / "ocio_vp").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "from benchmarks" not in text and "import benchmarks" not in text, path


def test_replace_section_replaces_only_its_own_section() -> None:
    document = "# Accuracy\n\nintro\n\n## A\nold a\n\n### a1\nx\n\n## B\nb\n"
    assert (
        replace_section(document, "## A\nnew a\n")
        == "# Accuracy\n\nintro\n\n## A\nnew a\n\n## B\nb\n"
    )
    assert replace_section(document, "## C\nc\n") == document + "\n## C\nc\n"
    assert replace_section("", "## C\nc") == "## C\nc\n"
    last = replace_section(document, "## B\nnew b\n")
    assert last.endswith("## B\nnew b\n") and "old a" in last


def test_the_skin_section_states_each_target_with_its_measured_figure(small) -> None:
    import dataclasses

    from benchmarks.bench_skin import HEADING, report
    from benchmarks.skin_eval import Evaluation

    # white-preserving stands in for the default: the section must judge whatever it measured.
    rows = [dataclasses.replace(r, variant="auto") if r.variant == "wp" else r for r in small.rows]
    evaluation = Evaluation(
        rows=rows,
        split="training",
        cameras=small.cameras,
        led_sets=small.led_sets,
        environments=small.environments,
    )
    text = report(evaluation, quick=True)
    auto = summarise(evaluation, "auto")
    worst_env, worst = max(auto.by_environment_ratio.items(), key=lambda kv: kv[1])
    target = next(line for line in text.splitlines() if line.startswith("- Default (`auto`)"))
    assert f"worst {worst:.2f}x ({worst_env})" in target
    assert target.endswith("**met**.") == (worst <= 1.0)
    assert text.startswith(HEADING + "\n")
    ls_row = next(
        line for line in text.splitlines() if line.startswith("| `least-squares` (ΔE2000)")
    )
    assert f"| {summarise(evaluation, REFERENCE).skin:.2f} |" in ls_row
