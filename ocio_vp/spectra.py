"""The project's wavelength grid and colour-science spectral data aligned to it.

A leaf module (it imports nothing of ocio_vp but :mod:`ocio_vp.errors`): the metrics, the
perceptual post-correction and the simulator all put spectra on this one grid.
colour-science is imported inside the functions: ``ocio-vp --help`` must stay fast.
"""

from __future__ import annotations

import difflib

import numpy as np

from ocio_vp.errors import InputError

__all__ = [
    "DEFAULT_CAMERA",
    "SPECTRAL_SHAPE",
    "align",
    "camera_sensitivities",
    "spectral_shape",
    "unknown_name",
    "wavelengths",
]

#: (start, end, interval) in nm: the grid of colour's camera sensitivity datasets.
SPECTRAL_SHAPE = (380.0, 780.0, 5.0)
DEFAULT_CAMERA = "Nikon 5100 (NPL)"


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


def camera_sensitivities(name: str = DEFAULT_CAMERA) -> np.ndarray:
    """(W, 3) spectral sensitivities of a camera in ``colour.MSDS_CAMERA_SENSITIVITIES``."""
    import colour

    try:
        msds = colour.MSDS_CAMERA_SENSITIVITIES[name]
    except KeyError:
        raise InputError(
            unknown_name("camera", name, colour.MSDS_CAMERA_SENSITIVITIES), key="camera"
        ) from None
    return np.asarray(msds.copy().align(spectral_shape()).values, dtype=np.float64)


def unknown_name(what: str, name: object, valid) -> str:
    """The error text for a name not in ``valid``, with close matches as hints."""
    names = [str(k) for k in valid]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.5)
    hint = f" (close: {', '.join(close)})" if close else ""
    return f"unknown {what} {name!r}{hint}; valid: {', '.join(names)}"
