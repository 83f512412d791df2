"""Chart error metrics: the paper's relative-to-white error, CIE ΔE2000 and ΔE ITP.

- :func:`error_relative_to_white` (re-exported from :mod:`ocio_vp.diagnostics`): mean absolute
  error per channel relative to the target white patch, the metric of the paper's Fig. 11.
- :func:`camera_to_xyz_matrix`: a 3x3 camera RGB -> CIE XYZ matrix fitted (least squares,
  colour's ``matrix_colour_correction``, Cheung 2004 with 3 terms) on colour-science's offline
  RAW to ACES v1 training reflectances (190 samples) under an illuminant (default D65), XYZ
  from the CIE 1931 2-degree observer.
- :func:`chart_errors`: ΔE2000 and ΔE ITP per patch through that matrix, with colour's own
  ``delta_E`` implementations.

Normalisation (both ΔE need one):

- **ΔE2000**: XYZ are scaled so the *target* white patch has Y = 1, and CIE Lab uses that
  patch's chromaticity as the reference white (so the target white is L* ~ 100, a* = b* = 0:
  the eye adapted to the scene's white).
- **ΔE ITP** (ITU-R BT.2124) needs absolute luminance: XYZ are scaled so the target white patch
  is :data:`ITP_WHITE_NITS` = 100 cd/m^2 (diffuse white on an SDR/HDR reference display), then
  ICtCp (ITU-R BT.2100-2 PQ, via BT.2020 RGB, no chromatic adaptation). 1 ΔE ITP is about one
  just-noticeable difference.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, Fig. 11.
ITU-R BT.2124-0 (2019). Objective metric for the assessment of the potential visibility of
colour differences in television.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.diagnostics import error_relative_to_white

__all__ = [
    "ITP_WHITE_NITS",
    "ChartErrors",
    "camera_to_xyz_matrix",
    "chart_errors",
    "error_relative_to_white",
    "training_rgb_xyz",
]

#: Luminance (cd/m^2) that the target white patch is mapped to for ΔE ITP.
ITP_WHITE_NITS = 100.0
_CMFS = "CIE 1931 2 Degree Standard Observer"


def training_rgb_xyz(
    camera: ArrayLike, *, illuminant: str = "D65"
) -> tuple[np.ndarray, np.ndarray]:
    """Camera RGB and CIE XYZ of the RAW to ACES v1 training reflectances under ``illuminant``.

    Parameters
    ----------
    camera
        (W, 3) camera sensitivities on :data:`ocio_vp.spectral_data.SPECTRAL_SHAPE`.
    illuminant
        A key of ``colour.SDS_ILLUMINANTS``.

    Returns
    -------
    (RGB, XYZ)
        Both (190, 3), unnormalised sums over wavelength.
    """
    import colour

    from ocio_vp.spectral_data import _shape, align

    shape = _shape()
    reflectances = np.asarray(
        colour.characterisation.read_training_data_rawtoaces_v1().copy().align(shape).values,
        dtype=np.float64,
    ).T  # (samples, W)
    light = align(colour.SDS_ILLUMINANTS[illuminant])
    cmfs = np.asarray(colour.MSDS_CMFS[_CMFS].copy().align(shape).values, dtype=np.float64)
    radiance = reflectances * light
    return radiance @ np.asarray(camera, dtype=np.float64), radiance @ cmfs


def camera_to_xyz_matrix(camera: ArrayLike, *, illuminant: str = "D65") -> np.ndarray:
    """(3, 3) matrix taking camera RGB to CIE XYZ, fitted on the training reflectances.

    Least squares over the 190 RAW to ACES v1 training samples (colour's Cheung 2004 matrix,
    3 terms). The overall scale is irrelevant: :func:`chart_errors` normalises to the target
    white.
    """
    from colour.characterisation import matrix_colour_correction

    rgb, xyz = training_rgb_xyz(camera, illuminant=illuminant)
    return np.asarray(matrix_colour_correction(rgb, xyz, method="Cheung 2004", terms=3))


@dataclass(frozen=True)
class ChartErrors:
    """Errors of a predicted chart against the target: per channel, and per patch ΔE."""

    relative_to_white: np.ndarray  # (3,) paper Fig. 11
    delta_E_2000: np.ndarray  # (n,)
    delta_E_ITP: np.ndarray  # (n,)

    @property
    def summary(self) -> dict[str, float]:
        """Means (and maxima of ΔE) as plain floats, for tables and JSON."""
        return {
            "relative_to_white_mean": float(np.mean(self.relative_to_white)),
            "delta_E_2000_mean": float(np.mean(self.delta_E_2000)),
            "delta_E_2000_max": float(np.max(self.delta_E_2000)),
            "delta_E_ITP_mean": float(np.mean(self.delta_E_ITP)),
            "delta_E_ITP_max": float(np.max(self.delta_E_ITP)),
        }


def chart_errors(
    predicted: ArrayLike,
    target: ArrayLike,
    *,
    camera_to_xyz: ArrayLike,
    white_patch: int = 18,
) -> ChartErrors:
    """Errors of ``predicted`` against ``target`` (both (n, 3) camera RGB).

    See the module docstring for the normalisation of ΔE2000 (target white Y = 1 and the Lab
    reference white) and ΔE ITP (target white = 100 cd/m^2).

    Examples
    --------
    >>> chart = np.linspace(0.05, 0.9, 72).reshape(24, 3)
    >>> e = chart_errors(chart * 1.01, chart, camera_to_xyz=np.eye(3))
    >>> bool(np.allclose(e.relative_to_white, 0.01 * chart.mean(axis=0) / chart[18]))
    True
    >>> bool(e.delta_E_2000.max() < 1.0)
    True
    """
    import colour

    predicted = np.asarray(predicted, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    matrix = np.asarray(camera_to_xyz, dtype=np.float64)
    xyz_target = target @ matrix.T
    xyz_predicted = predicted @ matrix.T
    scale = 1.0 / xyz_target[white_patch, 1]
    xyz_target, xyz_predicted = xyz_target * scale, xyz_predicted * scale
    white_xy = colour.XYZ_to_xy(xyz_target[white_patch])
    lab_t = colour.XYZ_to_Lab(xyz_target, white_xy)
    lab_p = colour.XYZ_to_Lab(xyz_predicted, white_xy)
    itp_t = colour.XYZ_to_ICtCp(xyz_target * ITP_WHITE_NITS, method="ITU-R BT.2100-2 PQ")
    itp_p = colour.XYZ_to_ICtCp(xyz_predicted * ITP_WHITE_NITS, method="ITU-R BT.2100-2 PQ")
    return ChartErrors(
        relative_to_white=error_relative_to_white(predicted, target, white_patch),
        delta_E_2000=np.asarray(colour.delta_E(lab_t, lab_p, method="CIE 2000")),
        delta_E_ITP=np.asarray(colour.delta_E(itp_t, itp_p, method="ITP")),
    )
