"""The project's wavelength grid and colour-science spectral data aligned to it (a leaf: the
metrics, the perceptual post-correction and the simulator all put spectra on this one grid).
"""

from __future__ import annotations

import difflib
import functools
import json
from importlib import resources

import numpy as np

from ocio_vp.errors import InputError

__all__ = [
    "CIE_OBSERVER",
    "DEFAULT_CAMERA",
    "DEFAULT_CHART",
    "PHYSLIGHT_CAMERAS",
    "SPECTRAL_SHAPE",
    "VENDORED_CAMERAS",
    "align",
    "camera_names",
    "camera_sensitivities",
    "checker_reflectances",
    "cie_cmfs_sds",
    "on_grid",
    "packaged_json",
    "spectral_shape",
    "unknown_name",
    "wavelengths",
]

#: (start, end, interval) in nm: the grid of colour's camera sensitivity datasets.
SPECTRAL_SHAPE = (380.0, 780.0, 5.0)
DEFAULT_CAMERA = "Nikon 5100 (NPL)"
DEFAULT_CHART = "ColorChecker N Ohta"
CIE_OBSERVER = "CIE 1931 2 Degree Standard Observer"
#: Measured sensitivities shipped with ocio_vp (``ocio_vp/data/camera_sensitivities.json``, from
#: the rawtoaces project's data, and :data:`VENDORED_CAMERA_FILES`; licences in
#: ``ocio_vp/data/CAMERAS_LICENSE.md``), beside colour-science's ``MSDS_CAMERA_SENSITIVITIES``.
VENDORED_CAMERAS = "data/camera_sensitivities.json"
#: Every file of measured cameras shipped with ocio_vp: the rawtoaces file, then Weta's physlight
#: cameras that it does not hold (Apache-2.0, same licence notice).
PHYSLIGHT_CAMERAS = "data/camera_sensitivities_physlight.json"
VENDORED_CAMERA_FILES = (VENDORED_CAMERAS, PHYSLIGHT_CAMERAS)


def spectral_shape():
    """:data:`SPECTRAL_SHAPE` as a ``colour.SpectralShape``."""
    import colour

    return colour.SpectralShape(*SPECTRAL_SHAPE)


def wavelengths() -> np.ndarray:
    """(W,) the grid's wavelengths in nm."""
    start, end, step = SPECTRAL_SHAPE
    return np.arange(start, end + step / 2, step)


def align(sd) -> np.ndarray:
    """Values of a colour ``SpectralDistribution`` on :data:`SPECTRAL_SHAPE`, float64 (W,).

    Interpolated inside its domain; outside it, held constant (colour's default extrapolator).
    Interpolation overshoot below 0 (Sprague, next to a spectral line's zeros) is clipped: light
    and reflectance are never negative.
    """
    return np.maximum(np.asarray(sd.copy().align(spectral_shape()).values, dtype=np.float64), 0.0)


def cie_cmfs_sds():
    """The CIE 1931 2-degree colour matching functions (colour ``MultiSpectralDistributions``)
    on the project's grid."""
    import colour

    return colour.MSDS_CMFS[CIE_OBSERVER].copy().align(spectral_shape())


def checker_reflectances(name: str = DEFAULT_CHART) -> np.ndarray:
    """(n, W) reflectances of ``colour.SDS_COLOURCHECKERS[name]`` in reading order."""
    import colour

    return np.stack([align(sd) for sd in colour.SDS_COLOURCHECKERS[name].values()])


def camera_sensitivities(name: str = DEFAULT_CAMERA) -> np.ndarray:
    """(W, 3) spectral sensitivities of a camera: a key of colour's
    ``MSDS_CAMERA_SENSITIVITIES`` or of :data:`VENDORED_CAMERAS` (:func:`camera_names`).

    >>> camera_sensitivities("ARRI D21 (rawtoaces)").shape
    (81, 3)
    """
    import colour

    if name in colour.MSDS_CAMERA_SENSITIVITIES:
        msds = colour.MSDS_CAMERA_SENSITIVITIES[name]
        return np.asarray(msds.copy().align(spectral_shape()).values, dtype=np.float64)
    vendored = _vendored_cameras()
    if name not in vendored:
        raise InputError(unknown_name("camera", name, camera_names()), key="camera")
    return vendored[name].copy()


def camera_names() -> tuple[str, ...]:
    """Every camera :func:`camera_sensitivities` knows: colour-science's, then the vendored."""
    import colour

    return (*colour.MSDS_CAMERA_SENSITIVITIES, *_vendored_cameras())


def packaged_json(path: str) -> dict:
    """The JSON document at ``path`` inside the package (``data/...``)."""
    return json.loads(resources.files("ocio_vp").joinpath(path).read_text(encoding="utf-8"))


def on_grid(document: dict, what: str) -> dict:
    """``document`` if its ``wavelengths`` are :data:`SPECTRAL_SHAPE`; else RuntimeError naming
    ``what``."""
    grid = document["wavelengths"]
    if (grid["start"], grid["end"], grid["interval"]) != SPECTRAL_SHAPE:
        raise RuntimeError(f"{what} is not on the grid {SPECTRAL_SHAPE}")
    return document


@functools.lru_cache(maxsize=1)
def _vendored_cameras() -> dict[str, np.ndarray]:
    """The cameras of :data:`VENDORED_CAMERA_FILES`, (W, 3) each; the files are on the grid."""
    cameras = {}
    for path in VENDORED_CAMERA_FILES:
        for name, record in on_grid(packaged_json(path), path)["cameras"].items():
            values = np.asarray(record["RGB"], dtype=np.float64)
            values.setflags(write=False)
            cameras[name] = values
    return cameras


def unknown_name(what: str, name: object, valid) -> str:
    """The error text for a name not in ``valid``, with close matches as hints."""
    names = [str(k) for k in valid]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.5)
    hint = f" (close: {', '.join(close)})" if close else ""
    return f"unknown {what} {name!r}{hint}; valid: {', '.join(names)}"
