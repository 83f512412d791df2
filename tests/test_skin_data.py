"""The measured skin and its split (ocio_vp.skin_data), and the physlight cameras."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

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
