"""Spectral CSV files (LED spectra, camera sensitivities, location light): read onto the grid,
and every unusable file refused on one line naming the file, the column and the problem."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.correction.skin_spectra import stage_spectra
from ocio_vp.errors import InputError
from ocio_vp.formats.spectral_csv import read_spectral_csv
from ocio_vp.spectra import wavelengths

NAMES = ("red", "green", "blue")


def _write(path, nm, values, header="nm,red,green,blue"):
    rows = [header] if header else []
    rows += [",".join(f"{v:.9g}" for v in (w, *row)) for w, row in zip(nm, values, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _gaussians(nm):
    return np.stack([np.exp(-0.5 * ((nm - p) / 12.0) ** 2) for p in (630, 525, 460)], axis=1)


def test_a_coarser_file_is_resampled_linearly_onto_the_grid(tmp_path):
    nm = np.arange(390.0, 731.0, 10.0)
    values = _gaussians(nm)
    table = read_spectral_csv(_write(tmp_path / "leds.csv", nm, values), columns=3, names=NAMES)
    grid = wavelengths()
    assert table.columns == NAMES and table.values.shape == (len(grid), 3)
    expected = np.stack([np.interp(grid, nm, values[:, k], left=0, right=0) for k in range(3)], 1)
    np.testing.assert_allclose(table.values, expected, rtol=1e-9, atol=1e-12)
    assert np.all(table.values[grid > 730] == 0) and np.all(table.values[grid < 390] == 0)


def test_a_file_without_header_takes_the_given_names(tmp_path):
    nm = wavelengths()
    table = read_spectral_csv(
        _write(tmp_path / "l.csv", nm, _gaussians(nm), header=""), columns=3, names=NAMES
    )
    assert table.columns == NAMES


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ("negative", r"l\.csv: column 'green': negative value -0\.1 at 450 nm"),
        ("range", r"l\.csv: column 'wavelength': covers 420-780 nm, need at least 400-700 nm"),
        ("sparse", r"l\.csv: column 'wavelength': too few samples: 10 between 400 and 700 nm"),
        ("columns", r"l\.csv: has 2 channel column\(s\), expected 3"),
        ("text", r"l\.csv: column 'blue', row 3: expected a finite number, got 'n/a'"),
        ("zero", r"l\.csv: column 'red': all zero"),
        ("order", r"l\.csv: column 'wavelength': expected increasing wavelengths"),
        ("units", r"l\.csv: column 'wavelength': 0\.38-0\.78 is not a range of wavelengths"),
    ],
)
def test_an_unusable_file_is_refused_on_one_line(tmp_path, change, message):
    nm = wavelengths().copy()
    values = _gaussians(nm)
    header = "nm,red,green,blue"
    if change == "negative":
        values[np.flatnonzero(nm == 450)[0], 1] = -0.1
    elif change == "range":
        nm, values = nm[8:], values[8:]
    elif change == "sparse":
        nm, values = nm[::6], values[::6]
    elif change == "columns":
        values, header = values[:, :2], "nm,red,green"
    elif change == "zero":
        values[:, 0] = 0
    elif change == "order":
        nm[[3, 4]] = nm[[4, 3]]
    elif change == "units":
        nm = nm / 1000
    path = _write(tmp_path / "l.csv", nm, values, header)
    if change == "text":
        lines = path.read_text().splitlines()
        lines[3] = lines[3].rsplit(",", 1)[0] + ",n/a"
        path.write_text("\n".join(lines))
    with pytest.raises(InputError, match=message) as error:
        read_spectral_csv(path, columns=3, names=NAMES)
    assert "\n" not in str(error.value)


def test_stage_spectra_needs_both_files_and_a_known_camera(tmp_path):
    nm = wavelengths()
    leds = _write(tmp_path / "leds.csv", nm, _gaussians(nm))
    assert stage_spectra(None, None) is None
    with pytest.raises(InputError, match="--led-spectra: needs --camera-sensitivities"):
        stage_spectra(str(leds), None)
    with pytest.raises(InputError, match="--camera-sensitivities: unknown camera 'Nikon 51'"):
        stage_spectra(str(leds), "Nikon 51")
    with pytest.raises(InputError, match=r"--location-light: expected ENV=FILE\.csv"):
        stage_spectra(str(leds), "Nikon 5100 (NPL)", ["daylight"])
    spectra = stage_spectra(str(leds), "Nikon 5100 (NPL)")
    assert spectra.leds.shape == spectra.camera.shape == (len(nm), 3) and spectra.lights == {}
