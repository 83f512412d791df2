"""Ground truth beyond the reflective colours of a scene (:mod:`ocio_vp.simulator.truth`
judges those): narrow-band emitters (practicals, neon, screens, LED props), which light
themselves alike on stage and on location, so the right post-correction leaves them alone
(:func:`emitter_errors`); and optimal colours, the edge of the reflective gamut
(:func:`optimal_reflectances`), judged as held-out reflectances are. docs/accuracy.md (*Beyond
the chart*) describes both.

References
----------
MacAdam, D. L. (1935). Maximum visual efficiency of colored materials. JOSA 25(11), 361-367.
https://doi.org/10.1364/JOSA.25.000361 (the optimal colours are block reflectances).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np

from ocio_vp.metrics import camera_delta_E_2000
from ocio_vp.model.footage_range import EMITTER_LEVELS
from ocio_vp.simulator.stage import SpectralStage, camera_rgb, environment_spectrum
from ocio_vp.spectra import wavelengths

__all__ = [
    "EMITTER_FWHM",
    "EMITTER_LEVELS",
    "EMITTER_PEAKS",
    "OPTIMAL_EDGES",
    "emitter_errors",
    "emitter_spectra",
    "emitters_in_scene",
    "luminance",
    "optimal_reflectances",
]

#: Peak wavelengths (nm) of the narrow-band emitters.
EMITTER_PEAKS = tuple(float(p) for p in range(420, 681, 10))
#: Their full width at half maximum (nm): a typical coloured LED.
EMITTER_FWHM = 20.0
#: Band edges (nm) of the optimal colours: every band between two of them is one band-pass
#: reflectance; every band between two inner edges (not 380 or 780) is also one band-stop.
OPTIMAL_EDGES = (380.0, *(float(e) for e in range(400, 701, 20)), 780.0)


@functools.lru_cache(maxsize=1)
def _y_bar() -> np.ndarray:
    from ocio_vp.synthesis.camera import cie_cmfs

    y = cie_cmfs()[:, 1]
    y.setflags(write=False)
    return y


def luminance(spectra: np.ndarray) -> np.ndarray:
    """(...,) CIE 1931 Y of (..., W) spectra on the grid, up to one constant factor
    (``sum_lambda y_bar(lambda) spectrum(lambda)``): only ratios of it are used."""
    return np.asarray(spectra, dtype=np.float64) @ _y_bar()


def emitter_spectra(
    peaks: Sequence[float] = EMITTER_PEAKS, fwhm: float = EMITTER_FWHM
) -> np.ndarray:
    """(k, W) unit-peak Gaussians ``exp(-4 ln 2 (lambda - peak)^2 / fwhm^2)``, one per peak.

    >>> s = emitter_spectra([550.0])
    >>> float(s.max()), s.shape
    (1.0, (1, 81))
    """
    grid = wavelengths()
    centres = np.asarray(peaks, dtype=np.float64)[:, None]
    return np.exp(-4.0 * np.log(2.0) * (grid[None, :] - centres) ** 2 / float(fwhm) ** 2)


def emitters_in_scene(
    stage: SpectralStage,
    environment,
    *,
    peaks: Sequence[float] = EMITTER_PEAKS,
    fwhm: float = EMITTER_FWHM,
    levels: Sequence[float] = EMITTER_LEVELS,
) -> np.ndarray:
    """(len(levels) * len(peaks), W) the emitters as spectral radiance in ``environment``'s
    scene: each of :func:`emitter_spectra` scaled to ``level`` times the luminance of a perfect
    white diffuser under the environment's light (as the simulator scales it,
    :func:`~ocio_vp.simulator.stage.environment_spectrum`); level-major order."""
    white_y = float(luminance(environment_spectrum(stage, environment)))
    unit = emitter_spectra(peaks, fwhm)
    unit = unit * (white_y / luminance(unit))[:, None]
    return np.vstack([level * unit for level in levels])


def emitter_errors(
    stage: SpectralStage,
    environment,
    correct: Callable[[np.ndarray], np.ndarray],
    *,
    camera_to_xyz: np.ndarray,
    emitters: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(ΔE2000 between ``correct(x)`` and ``x``, the corrected camera RGB) for every emitter
    ``x`` (default :func:`emitters_in_scene`), through ``camera_to_xyz`` with the scene's
    white (a perfect diffuser under the real light) at Y = 1 as the reference white, as
    :func:`~ocio_vp.simulator.truth.held_out_errors` judges reflectances."""
    spectra = emitters_in_scene(stage, environment) if emitters is None else emitters
    x = camera_rgb(stage, spectra)
    white = camera_rgb(stage, environment_spectrum(stage, environment))
    corrected = np.asarray(correct(x), dtype=np.float64)
    # the scene's white at Y = 1, as chart_errors normalises
    moved = camera_delta_E_2000(x, corrected, camera_to_xyz=camera_to_xyz, white=white)
    return moved, corrected


def optimal_reflectances(edges: Sequence[float] = OPTIMAL_EDGES) -> np.ndarray:
    """(k, W) block reflectances: 1 on ``[a, b)`` for every pair of edges ``a < b`` but the
    whole range (band-pass), then 1 outside ``[a, b)`` for every pair of inner edges
    (band-stop, the band-pass's complement).

    >>> r = optimal_reflectances((380.0, 500.0, 600.0, 780.0))
    >>> r.shape, sorted(set(r.ravel().tolist()))
    ((6, 81), [0.0, 1.0])
    """
    grid = wavelengths()
    edges = sorted(float(e) for e in edges)
    lo, hi = grid[0], grid[-1] + 1.0
    passes, stops = [], []
    for i, a in enumerate(edges):
        for b in edges[i + 1 :]:
            band = ((grid >= a) & (grid < (hi if b >= grid[-1] else b))).astype(np.float64)
            whole = a <= lo and b >= grid[-1]
            if not whole:
                passes.append(band)
            if a > lo and b < grid[-1]:
                stops.append(1.0 - band)
    return np.asarray(passes + stops)
