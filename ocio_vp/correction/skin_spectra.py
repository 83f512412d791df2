"""Skin samples computed from spectra, where the stage knows them (``solve --led-spectra FILE
--camera-sensitivities FILE|NAME [--location-light ENV=FILE]``).

Each skin reflectance is lit through the LED spectra and camera sensitivities, with gains
fitted to the photographed lit and target charts (the files' units are unknown); a location
light not measured is estimated from the target chart (:func:`estimate_light`). docs/skin.md
("Skin samples", its "From spectra" item) explains it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.correction.skin import SKIN_CHART, SkinSamples, chart_reflectances
from ocio_vp.errors import InputError
from ocio_vp.skin_data import SkinSet, training_skin

__all__ = [
    "LIGHT_BASIS_NM",
    "StageSpectra",
    "estimate_light",
    "spectral_skin_samples",
    "stage_spectra",
]

#: Spacing (and width) of the smooth bumps a location light is estimated with (nm).
LIGHT_BASIS_NM = 25.0
#: Ridge of that estimate, relative to the design's energy: keeps the light smooth.
LIGHT_RIDGE = 1e-4


@dataclass(frozen=True)
class StageSpectra:
    """What a stage knows of its spectra (on the project grid): the panel's ``leds`` (W, 3),
    the camera's ``camera`` (W, 3), measured location ``lights`` (W,) by environment name, and
    where each came from, in words (``sources``)."""

    leds: np.ndarray
    camera: np.ndarray
    lights: dict[str, np.ndarray]
    sources: str


def stage_spectra(
    led_spectra: str | None, camera: str | None, lights: Sequence[str] = ()
) -> StageSpectra | None:
    """The :class:`StageSpectra` of ``solve``'s options: ``led_spectra`` a CSV of three LED
    channels, ``camera`` a CSV of three sensitivities or a camera name
    (:func:`ocio_vp.spectra.camera_names`), ``lights`` ``ENV=FILE.csv`` (one column each).
    None when neither is given; the two come together (an InputError otherwise)."""
    from ocio_vp.formats.spectral_csv import read_spectral_csv
    from ocio_vp.spectra import camera_names, camera_sensitivities, unknown_name

    if led_spectra is None and camera is None:
        if lights:
            raise InputError(
                "needs --led-spectra and --camera-sensitivities", key="--location-light"
            )
        return None
    if led_spectra is None or camera is None:
        missing = "--camera-sensitivities" if camera is None else "--led-spectra"
        given = "--led-spectra" if camera is None else "--camera-sensitivities"
        raise InputError(f"needs {missing} too (skin is computed from both)", key=given)
    leds = read_spectral_csv(led_spectra, columns=3, names=("red", "green", "blue"))
    if Path(camera).suffix.lower() == ".csv" or Path(camera).is_file():
        sensitivities = read_spectral_csv(camera, columns=3, names=("R", "G", "B")).values
    elif camera in camera_names():
        sensitivities = camera_sensitivities(camera)
    else:
        raise InputError(
            unknown_name("camera", camera, camera_names()), key="--camera-sensitivities"
        )
    measured = {}
    for spec in lights:
        name, sep, path = spec.partition("=")
        if not sep or not name or not path:
            raise InputError(f"expected ENV=FILE.csv, got {spec!r}", key="--location-light")
        measured[name] = read_spectral_csv(path, columns=1, names=("light",)).values[:, 0]
    return StageSpectra(
        leds=leds.values,
        camera=sensitivities,
        lights=measured,
        sources=f"the LED spectra of {Path(led_spectra).name} and the camera {Path(camera).name}",
    )


def _gains(measured: np.ndarray, predicted: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Least-squares scale per trailing index: ``measured ≈ g * predicted`` over active rows."""
    m, p = measured[active], predicted[active]
    denominator = np.sum(p * p, axis=0)
    return np.where(
        denominator > 0, np.sum(m * p, axis=0) / np.where(denominator > 0, denominator, 1), 0.0
    )


def estimate_light(camera: np.ndarray, chart: np.ndarray, target: np.ndarray, active) -> np.ndarray:
    """(W,) a smooth non-negative light whose chart (``chart`` (n, W) through ``camera``)
    best matches ``target`` (n, 3), up to a scale per camera channel fitted afterwards."""
    from scipy.optimize import nnls

    from ocio_vp.spectra import wavelengths

    grid = wavelengths()
    centres = np.arange(grid[0], grid[-1] + 1e-9, LIGHT_BASIS_NM)
    basis = np.exp(-0.5 * ((grid[:, None] - centres[None]) / (0.6 * LIGHT_BASIS_NM)) ** 2)
    # design[j, c, m]: patch j through camera channel c under bump m.
    design = np.einsum("jw,wc,wm->jcm", chart[active], camera, basis)
    rows = design.reshape(-1, basis.shape[1])
    scale = np.linalg.norm(rows, axis=0).max()
    lam = np.sqrt(LIGHT_RIDGE) * scale
    A = np.vstack([rows, lam * np.eye(basis.shape[1])])
    b = np.concatenate([target[active].reshape(-1), np.zeros(basis.shape[1])])
    weights, _ = nnls(A, b, maxiter=50 * basis.shape[1])
    return basis @ weights


def spectral_skin_samples(
    SRL: np.ndarray,
    target: np.ndarray,
    active: np.ndarray,
    spectra: StageSpectra,
    environment: str,
    training: SkinSet | None = None,
) -> SkinSamples | None:
    """Skin samples from spectra (module docstring); None on a chart that is not a ColorChecker
    24 (its reference spectra are what the gains are fitted with)."""
    if SRL.shape[0] != 24:
        return None
    training = training or training_skin()
    chart = chart_reflectances()
    C, L = spectra.camera, spectra.leds
    lit_chart = np.einsum("wc,jw,wl->jcl", C, chart, L)
    g = _gains(np.asarray(SRL, dtype=np.float64), lit_chart, active)
    skin = training.reflectances
    light = spectra.lights.get(environment)
    how = "measured"
    if light is None:
        light = estimate_light(C, chart, np.asarray(target, dtype=np.float64), active)
        how = "estimated from the target chart"
    located = (chart * light) @ C
    h = _gains(np.asarray(target, dtype=np.float64), located, active)
    return SkinSamples(
        SRL=g * np.einsum("wc,kw,wl->kcl", C, skin, L),
        target=h * ((skin * light) @ C),
        band=training.bands,
        source=(
            f"{len(skin)} measured skin reflectances through {spectra.sources}, the location "
            f"light {how} (gains fitted to the chart's {SKIN_CHART} spectra)"
        ),
    )
