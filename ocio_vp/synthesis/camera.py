"""The camera that would photograph a synthesized chart: spectral sensitivities or a colour space.

Either model is a (W, 3) *observer* on :data:`ocio_vp.spectra.SPECTRAL_SHAPE`: camera RGB of a
radiance ``E(lambda)`` is ``observer.T @ E``. With spectral sensitivities (colour-science's
``MSDS_CAMERA_SENSITIVITIES`` or a ``wavelength,R,G,B`` CSV) that is exact. Without them the
camera is approximated through its stated colour space: ``RGB = A XYZ`` with ``A`` the space's
XYZ-to-RGB matrix (``colour.RGB_COLOURSPACES``), i.e. the observer ``cmfs @ A.T``. That is the
Luther-Ives approximation every camera gamut makes; ``benchmarks/bench_target_chart.py``
measures its error on the simulator's cameras.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp import spectra
from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.metrics import camera_to_xyz_matrix
from ocio_vp.simulator.options import read_spectra_csv
from ocio_vp.spectra import camera_sensitivities, unknown_name

__all__ = [
    "CameraModel",
    "camera_from_colourspace",
    "camera_from_csv",
    "camera_from_dataset",
    "camera_from_matrix",
    "cie_cmfs",
]

#: Names served for one more release (ocio_vp.deprecation): moved to ocio_vp.spectra.
__getattr__ = deprecated_names(
    __name__,
    {
        "CIE_OBSERVER": ("ocio_vp.spectra.CIE_OBSERVER", "ocio_vp.spectra:CIE_OBSERVER"),
        "cie_cmfs_sds": ("ocio_vp.spectra.cie_cmfs_sds", "ocio_vp.spectra:cie_cmfs_sds"),
    },
)


def cie_cmfs() -> np.ndarray:
    """(W, 3) the CIE 1931 2-degree colour matching functions on the project's grid."""
    return np.asarray(spectra.cie_cmfs_sds().values, dtype=np.float64)


@dataclass(frozen=True)
class CameraModel:
    """A camera as a linear observer: ``render(radiance) = radiance @ observer``.

    ``to_xyz`` (3, 3) takes its RGB to CIE XYZ (exact for a colour-space model, a least-squares
    fit for sensitivities); ``spectral`` says whether ``observer`` is measured sensitivities.
    """

    description: str
    observer: np.ndarray
    to_xyz: np.ndarray
    spectral: bool

    def render(self, radiance: ArrayLike) -> np.ndarray:
        """(..., 3) camera RGB of (..., W) spectral radiance."""
        return np.asarray(radiance, dtype=np.float64) @ self.observer


def _from_sensitivities(sensitivities: np.ndarray, description: str) -> CameraModel:
    return CameraModel(
        description=description,
        observer=sensitivities,
        to_xyz=camera_to_xyz_matrix(sensitivities),
        spectral=True,
    )


def camera_from_dataset(name: str) -> CameraModel:
    """The sensitivities of a named camera (:func:`ocio_vp.spectra.camera_names`; ``--camera``)."""
    return _from_sensitivities(camera_sensitivities(name), f"{name} spectral sensitivities")


def camera_from_csv(path: str | Path) -> CameraModel:
    """Sensitivities from a ``wavelength,R,G,B`` CSV (nm; optional header), as rawtoaces ships.

    Raises
    ------
    InputError
        Unreadable file, bad rows, negative values, or a channel that is zero on 380-780 nm.
    """
    sensitivities = read_spectra_csv(path, columns=3)
    if np.any(sensitivities.max(axis=0) <= 0):
        raise InputError("a channel is zero over 380-780 nm", source=str(path))
    return _from_sensitivities(sensitivities, f"{Path(path).name} spectral sensitivities")


def camera_from_matrix(xyz_to_camera: ArrayLike, description: str) -> CameraModel:
    """A camera approximated by a 3x3 XYZ-to-camera-RGB matrix (a camera gamut)."""
    matrix = np.asarray(xyz_to_camera, dtype=np.float64)
    return CameraModel(
        description=description,
        observer=cie_cmfs() @ matrix.T,
        to_xyz=np.linalg.inv(matrix),
        spectral=False,
    )


def camera_from_colourspace(name: str) -> CameraModel:
    """The camera through its stated gamut, a ``colour.RGB_COLOURSPACES`` name (no adaptation)."""
    import colour

    if name not in colour.RGB_COLOURSPACES:
        raise InputError(unknown_name("colour space", name, colour.RGB_COLOURSPACES), key="camera")
    space = colour.RGB_COLOURSPACES[name]
    return camera_from_matrix(space.matrix_XYZ_to_RGB, f"{space.name} colour space from XYZ")
