"""The grid and the cameras (ocio_vp.spectra): the measured sensitivities shipped with ocio_vp."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.spectra import camera_names, camera_sensitivities, wavelengths

DATA = Path(__file__).resolve().parents[1] / "ocio_vp" / "data"
VENDORED = (
    "ARRI D21 (rawtoaces)",
    "RED MX (rawtoaces)",
    "Sony ILCE-7RM2 (rawtoaces)",
    "Sony ILCE-7SM2 (rawtoaces)",
    "Canon EOS 5D Mark II (rawtoaces)",
    "Nikon D810 (rawtoaces)",
    "Canon EOS R5 (rawtoaces)",
    "Fujifilm X-T3 (rawtoaces)",
    "Nikon Z f (rawtoaces)",
    "Panasonic DC-GX9 (rawtoaces)",
)


def _document() -> dict:
    return json.loads((DATA / "camera_sensitivities.json").read_text(encoding="utf-8"))


def test_every_vendored_camera_reads_back_as_written() -> None:
    document = _document()
    assert tuple(document["cameras"]) == VENDORED
    assert set(VENDORED) <= set(camera_names())
    for name, record in document["cameras"].items():
        values = camera_sensitivities(name)
        assert values.shape == (len(wavelengths()), 3)
        np.testing.assert_array_equal(values, np.asarray(record["RGB"], dtype=np.float64))
        assert np.all(np.isfinite(values)) and np.all(values >= 0)
        assert np.all(values.max(axis=0) > 0.1)  # every channel sees light


def test_values_are_the_rawtoaces_files() -> None:
    # Spot values of the source files (rawtoaces-data ARRI_D21_380_780_5.json at 380 nm and its
    # green peak at 540 nm; rawtoaces' 2017 red_mx_380_780_5.json at 380 nm).
    grid = wavelengths()
    arri = camera_sensitivities("ARRI D21 (rawtoaces)")
    np.testing.assert_array_equal(arri[0], [0.000188205, 0.0000859, 0.0000958])
    assert arri[grid == 540.0, 1] == 1.0
    red = camera_sensitivities("RED MX (rawtoaces)")
    assert red[0, 0] == pytest.approx(0.0424, abs=5e-5)


def test_each_camera_names_its_source_and_licence_and_the_notice_ships() -> None:
    notice = (DATA / "CAMERAS_LICENSE.md").read_text(encoding="utf-8")
    assert "Apache License" in notice and "RAW TO ACES LICENSE" in notice
    for name, record in _document()["cameras"].items():
        assert record["source"].startswith("https://github.com/AcademySoftwareFoundation/")
        assert record["licence"] in ("Apache-2.0", "A.M.P.A.S. RAW to ACES licence (2017)")
        assert name.removesuffix(" (rawtoaces)").split()[-1] in notice
    pyproject = (DATA.parents[1] / "pyproject.toml").read_text(encoding="utf-8")
    package_data = pyproject.split("[tool.setuptools.package-data]")[1].split("\n\n")[0]
    assert '"data/*.json"' in package_data and '"data/*.md"' in package_data


def test_the_simulator_takes_them() -> None:
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage

    stage = spectral_stage(camera="Sony ILCE-7SM2 (rawtoaces)")
    m = simulate_measurements(["direct_sun"], stage=stage)
    assert m.environments[0].w_avg[1] == pytest.approx(1.0)


def test_an_unknown_camera_lists_the_shipped_ones() -> None:
    with pytest.raises(InputError, match=r"RED MX \(rawtoaces\)"):
        camera_sensitivities("RED MX")
