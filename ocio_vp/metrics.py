"""Chart error metrics: the paper's relative-to-white error (Fig. 11), CIE ΔE2000 and ΔE ITP
of camera RGB through a camera RGB -> XYZ matrix (:func:`camera_to_xyz_matrix`, or the sample
camera's, :func:`sample_camera_to_xyz`); their normalisation is in docs/report.md (*ΔE*).

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). DigiPro '22, Fig. 11.
ITU-R BT.2124-0 (2019). Objective metric for the assessment of the potential visibility of
colour differences in television.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.deprecation import warn_deprecated
from ocio_vp.spectra import CIE_OBSERVER, packaged_json, spectral_shape, wavelengths

__all__ = [
    "COLORCHECKER_NAMES",
    "ITP_WHITE_NITS",
    "ROUNDING",
    "SAMPLE_MATRIX_FILE",
    "WHITE_FLOOR",
    "ChartErrors",
    "as_recorded",
    "camera_delta_E_2000",
    "camera_lab",
    "camera_to_xyz_matrix",
    "chart_errors",
    "delta_E_2000",
    "error_relative_to_white",
    "patch_label",
    "rgb_to_rgb_cat02",
    "sample_camera_to_xyz",
    "training_rgb_xyz",
    "white_scale",
    "zero_below_rounding",
]

#: The 24 patches of the ColorChecker Classic in reading order (X-Rite's names).
COLORCHECKER_NAMES = (
    "dark skin",
    "light skin",
    "blue sky",
    "foliage",
    "blue flower",
    "bluish green",
    "orange",
    "purplish blue",
    "moderate red",
    "purple",
    "yellow green",
    "orange yellow",
    "blue",
    "green",
    "red",
    "yellow",
    "magenta",
    "cyan",
    "white 9.5 (.05 D)",
    "neutral 8 (.23 D)",
    "neutral 6.5 (.44 D)",
    "neutral 5 (.70 D)",
    "neutral 3.5 (1.05 D)",
    "black 2 (1.5 D)",
)


def patch_label(index: int, n: int) -> str:
    """A chart patch as people see it: numbered from 1 in reading order, with its name on a
    ColorChecker 24 (files keep 0-based indices: ``index`` is one).

    >>> patch_label(18, 24), patch_label(0, 140)
    ('patch 19 (white 9.5 (.05 D))', 'patch 1')
    """
    if n == len(COLORCHECKER_NAMES):
        return f"patch {index + 1} ({COLORCHECKER_NAMES[index]})"
    return f"patch {index + 1}"


#: Luminance (cd/m^2) that the target white patch is mapped to for ΔE ITP.
ITP_WHITE_NITS = 100.0


#: A white-patch channel below this fraction of the white's brightest channel is floored to it,
#: so that a near-monochromatic target (sodium: almost no blue) does not divide by ~0.
WHITE_FLOOR = 0.01
#: A colour difference below this is rounding, whose digits differ between machines: files and
#: terminals give it as 0 (:func:`zero_below_rounding`).
ROUNDING = 1e-6


def zero_below_rounding(value: float) -> float:
    """``value`` as a float, or 0.0 where its magnitude is below :data:`ROUNDING`.

    >>> zero_below_rounding(3.2e-8), zero_below_rounding(0.42)
    (0.0, 0.42)
    """
    return 0.0 if abs(value) < ROUNDING else float(value)


def as_recorded(value: float, digits: int = 6) -> float:
    """``value`` as files keep a measured figure: 0 below :data:`ROUNDING`, else rounded to
    ``digits`` significant digits (the digits beyond differ between machines).

    >>> as_recorded(0.9729297276353142), as_recorded(3.2e-8), as_recorded(1234.5678, 4)
    (0.97293, 0.0, 1235.0)
    """
    return float(f"{zero_below_rounding(value):.{digits}g}")


def white_scale(
    target: ArrayLike, white_patch: int = DEFAULT_WHITE_PATCH, weights: ArrayLike | None = None
):
    """(..., 3) per-channel denominators for white-relative errors.

    The target white patch, each channel floored at ``WHITE_FLOOR`` times its brightest channel;
    when the white patch is black (or excluded by ``weights``) the mean absolute target value of
    the fitted patches over all channels, and 1 if the whole chart is black.
    """
    target = np.asarray(target, dtype=np.float64)
    white = np.abs(target[..., white_patch, :])
    peak = white.max(axis=-1, keepdims=True)
    w = np.ones(target.shape[-2]) if weights is None else np.asarray(weights, dtype=np.float64)
    fallback = np.tensordot(w, np.abs(target), axes=([0], [-2])).mean(axis=-1, keepdims=True)
    fallback = fallback / max(float(w.sum()), 1e-300)
    fallback = np.where(fallback > 0, fallback, 1.0)
    usable = (peak > 0) & (w[white_patch] > 0)
    floored = np.maximum(white, WHITE_FLOOR * peak)
    return np.where(usable, floored, np.broadcast_to(fallback, white.shape))


def error_relative_to_white(
    predicted: ArrayLike,
    target: ArrayLike,
    white_patch: int = DEFAULT_WHITE_PATCH,
    weights: ArrayLike | None = None,
) -> np.ndarray:
    """(..., 3) mean absolute error per channel relative to the target white patch (paper, Fig.
    11): ``mean_j |predicted_j - target_j| / target_white``, the white per :func:`white_scale`.

    Parameters
    ----------
    predicted, target
        (..., n, 3) chart values.
    white_patch
        Index of the white patch in ``target``.
    weights
        Optional (n,) weights (0 excludes a patch).

    Examples
    --------
    >>> target = np.ones((24, 3)); predicted = target * 1.02
    >>> error_relative_to_white(predicted, target).round(6).tolist()
    [0.02, 0.02, 0.02]
    """
    predicted = np.asarray(predicted, dtype=np.float64)
    target = np.asarray(target, dtype=np.float64)
    error = np.abs(predicted - target) / white_scale(target, white_patch, weights)[..., None, :]
    w = np.ones(target.shape[-2]) if weights is None else np.asarray(weights, dtype=np.float64)
    return np.tensordot(w, error, axes=([0], [-2])) / w.sum()


def _on_grid(spectra) -> np.ndarray:
    """Values of a colour spectral distribution (or multi-) on the project's grid, float64.

    When every grid wavelength is one of the data's own, the values are taken there (what
    colour's interpolating ``align`` returns at its own nodes, to rounding, without
    interpolating 190 spectra); otherwise colour's ``align``.
    """
    grid = wavelengths()
    own = np.asarray(spectra.wavelengths, dtype=np.float64)
    index = np.searchsorted(own, grid)
    if np.all(index < len(own)) and np.array_equal(own[np.minimum(index, len(own) - 1)], grid):
        return np.asarray(spectra.values, dtype=np.float64)[index]
    return np.asarray(spectra.copy().align(spectral_shape()).values, dtype=np.float64)


def _training_reflectances() -> np.ndarray:
    """(190, W) the RAW to ACES v1 training reflectances on the project's grid.

    Read from colour-science's own CSV file with numpy (the same numbers as colour's slower
    ``read_training_data_rawtoaces_v1``); colour's reader and ``align`` when the file's
    wavelengths are not the grid's.
    """
    import colour
    from colour.characterisation.aces_it import ROOT_RESOURCES_RAWTOACES

    table = np.loadtxt(
        os.path.join(ROOT_RESOURCES_RAWTOACES, "190_Patches.csv"), delimiter=",", skiprows=1
    )
    if np.array_equal(table[:, 0], wavelengths()):
        return table[:, 1:].T
    return _on_grid(colour.characterisation.read_training_data_rawtoaces_v1()).T


@functools.lru_cache(maxsize=8)
def _training_radiance_xyz(illuminant: str) -> tuple[np.ndarray, np.ndarray]:
    """(190, W) radiances of the training reflectances under ``illuminant`` and their (190, 3)
    XYZ, on the project's grid; computed once per illuminant (read-only arrays)."""
    import colour

    reflectances = _training_reflectances()
    light = np.maximum(_on_grid(colour.SDS_ILLUMINANTS[illuminant]), 0.0)
    radiance = reflectances * light
    xyz = radiance @ _on_grid(colour.MSDS_CMFS[CIE_OBSERVER])
    for array in (radiance, xyz):
        array.setflags(write=False)
    return radiance, xyz


def training_rgb_xyz(
    camera: ArrayLike, *, illuminant: str = "D65"
) -> tuple[np.ndarray, np.ndarray]:
    """Camera RGB and CIE XYZ of the RAW to ACES v1 training reflectances under ``illuminant``.

    Parameters
    ----------
    camera
        (W, 3) camera sensitivities on :data:`ocio_vp.spectra.SPECTRAL_SHAPE`.
    illuminant
        A key of ``colour.SDS_ILLUMINANTS``.

    Returns
    -------
    (RGB, XYZ)
        Both (190, 3), unnormalised sums over wavelength.
    """
    radiance, xyz = _training_radiance_xyz(illuminant)
    return radiance @ np.asarray(camera, dtype=np.float64), xyz.copy()


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
        """Deprecated: means (and maxima of ΔE) as plain floats."""
        warn_deprecated("ChartErrors.summary", "the means and maxima of its arrays")
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
    white_patch: int = DEFAULT_WHITE_PATCH,
) -> ChartErrors:
    """Errors of ``predicted`` against ``target`` (both (n, 3) camera RGB).

    ΔE2000: XYZ scaled so the target white patch has Y = 1, Lab relative to its chromaticity.
    ΔE ITP (ITU-R BT.2124): the target white patch at :data:`ITP_WHITE_NITS` cd/m^2, ICtCp
    (BT.2100-2 PQ, via BT.2020 RGB, no chromatic adaptation).

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
    scale = 1.0 / (target[white_patch] @ matrix[1])
    itp_t, itp_p = (
        colour.XYZ_to_ICtCp(rgb @ matrix.T * scale * ITP_WHITE_NITS, method="ITU-R BT.2100-2 PQ")
        for rgb in (target, predicted)
    )
    return ChartErrors(
        relative_to_white=error_relative_to_white(predicted, target, white_patch),
        delta_E_2000=camera_delta_E_2000(
            target, predicted, camera_to_xyz=matrix, white=target[white_patch]
        ),
        delta_E_ITP=np.asarray(colour.delta_E(itp_t, itp_p, method="ITP")),
    )


def camera_delta_E_2000(
    reference: ArrayLike, other: ArrayLike, *, camera_to_xyz: ArrayLike, white: ArrayLike
) -> np.ndarray:
    """(...,) ΔE2000 between two camera RGB renderings (..., 3) of the same colours, with
    colour-science's ``XYZ_to_Lab`` and ``delta_E``: the one camera RGB -> ΔE2000 of the package.

    XYZ through ``camera_to_xyz``, scaled so that ``white`` (camera RGB of the scene's white)
    has Y = 1, Lab relative to its chromaticity. Colours brighter than white, negative or out
    of gamut are measured as they are. :func:`delta_E_2000` is the same figure in numpy alone,
    for the config writer, which does not load colour-science.

    >>> white = np.array([0.9, 1.0, 0.8])
    >>> round(float(camera_delta_E_2000(white, 1.05 * white, camera_to_xyz=np.eye(3), white=white)), 4)
    1.0798
    """
    import colour

    lab = [camera_lab(rgb, camera_to_xyz=camera_to_xyz, white=white) for rgb in (reference, other)]
    return np.asarray(colour.delta_E(lab[0], lab[1], method="CIE 2000"))


def camera_lab(rgb: ArrayLike, *, camera_to_xyz: ArrayLike, white: ArrayLike | int) -> np.ndarray:
    """(..., 3) CIE Lab of camera RGB (..., 3) as :func:`camera_delta_E_2000` measures it.

    ``white`` is the white's camera RGB, or the index of the row of ``rgb`` (n, 3) that is the
    white: its XYZ is then that row of the same product, bit for bit what the rows get."""
    import colour

    matrix = np.asarray(camera_to_xyz, dtype=np.float64)
    xyz = np.asarray(rgb, dtype=np.float64) @ matrix.T
    if isinstance(white, (int, np.integer)):
        scale = 1.0 / xyz[white, 1]
        white_xy = colour.XYZ_to_xy(xyz[white] * scale)
    else:
        white = np.asarray(white, dtype=np.float64)
        scale = 1.0 / float(white @ matrix[1])
        white_xy = colour.XYZ_to_xy(white @ matrix.T * scale)
    return np.asarray(colour.XYZ_to_Lab(xyz * scale, white_xy))


def rgb_to_rgb_cat02(source: str, target: str) -> np.ndarray:
    """(3, 3) colour-science's ``matrix_RGB_to_RGB`` between two ``colour.RGB_COLOURSPACES``
    names with CAT02 adaptation: how content and working spaces reach the camera's gamut."""
    import colour

    spaces = colour.RGB_COLOURSPACES
    matrix = colour.matrix_RGB_to_RGB(
        spaces[source], spaces[target], chromatic_adaptation_transform="CAT02"
    )
    return np.asarray(matrix, dtype=np.float64)


#: The file holding :func:`sample_camera_to_xyz` (inside the package), written by
#: ``python -m benchmarks.make_sample_matrix``.
SAMPLE_MATRIX_FILE = "data/sample_camera_to_xyz.json"


@functools.lru_cache(maxsize=1)
def sample_camera_to_xyz() -> np.ndarray:
    """:func:`camera_to_xyz_matrix` of the sample camera (``ocio_vp.spectra.DEFAULT_CAMERA``,
    under D65), read from :data:`SAMPLE_MATRIX_FILE` so that code writing files (the OCIO
    config's agreement check) needs no colour-science; ``tests/test_metrics.py`` checks it
    against the fit. Read-only."""
    matrix = np.array(packaged_json(SAMPLE_MATRIX_FILE)["camera_to_xyz"], dtype=np.float64)
    matrix.setflags(write=False)
    return matrix


def _lab(xyz: np.ndarray, white: np.ndarray) -> np.ndarray:
    """CIE 1976 L*a*b* of (n, 3) XYZ relative to the XYZ ``white`` (linear below (6/29)^3)."""
    t = xyz / white
    d = 6.0 / 29.0
    f = np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)
    return np.stack(
        [116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], axis=-1
    )


def _ciede2000(lab_1: np.ndarray, lab_2: np.ndarray) -> np.ndarray:
    """CIEDE2000 (Sharma, Wu & Dalal 2005) of (n, 3) Lab pairs, kL = kC = kH = 1."""
    (L1, a1, b1), (L2, a2, b2) = lab_1.T, lab_2.T
    c_bar = (np.hypot(a1, b1) + np.hypot(a2, b2)) / 2
    g = 0.5 * (1 - np.sqrt(c_bar**7 / (c_bar**7 + 25.0**7)))
    a1, a2 = (1 + g) * a1, (1 + g) * a2
    c1, c2 = np.hypot(a1, b1), np.hypot(a2, b2)
    h1 = np.degrees(np.arctan2(b1, a1)) % 360
    h2 = np.degrees(np.arctan2(b2, a2)) % 360
    both = c1 * c2 != 0
    dh = h2 - h1
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(both, dh, 0.0)
    d_hue = 2 * np.sqrt(c1 * c2) * np.sin(np.radians(dh / 2))
    l_bar, c_bar = (L1 + L2) / 2, (c1 + c2) / 2
    h_sum, h_gap = h1 + h2, np.abs(h1 - h2)
    h_bar = np.where(h_gap <= 180, h_sum / 2, np.where(h_sum < 360, h_sum + 360, h_sum - 360) / 2)
    h_bar = np.where(both, h_bar, h_sum)
    t = (
        1
        - 0.17 * np.cos(np.radians(h_bar - 30))
        + 0.24 * np.cos(np.radians(2 * h_bar))
        + 0.32 * np.cos(np.radians(3 * h_bar + 6))
        - 0.20 * np.cos(np.radians(4 * h_bar - 63))
    )
    rotation = 30 * np.exp(-(((h_bar - 275) / 25) ** 2))
    r_c = 2 * np.sqrt(c_bar**7 / (c_bar**7 + 25.0**7))
    s_l = 1 + 0.015 * (l_bar - 50) ** 2 / np.sqrt(20 + (l_bar - 50) ** 2)
    s_c, s_h = 1 + 0.045 * c_bar, 1 + 0.015 * c_bar * t
    r_t = -np.sin(np.radians(2 * rotation)) * r_c
    dl, dc, dhh = (L2 - L1) / s_l, (c2 - c1) / s_c, d_hue / s_h
    return np.sqrt(dl**2 + dc**2 + dhh**2 + r_t * dc * dhh)


def delta_E_2000(
    a: ArrayLike, b: ArrayLike, *, camera_to_xyz: ArrayLike, white: ArrayLike
) -> np.ndarray:
    """(n,) :func:`camera_delta_E_2000` of (n, 3) renderings in numpy alone: the config writer,
    which loads no colour-science, measures its LUT chains with it (``tests/test_metrics.py``
    checks it against colour-science). CIE Lab continues linearly below black.

    >>> white = np.array([0.9, 1.0, 0.8])
    >>> float(delta_E_2000(white[None], white[None], camera_to_xyz=np.eye(3), white=white)[0])
    0.0
    """
    matrix = np.asarray(camera_to_xyz, dtype=np.float64)
    white_xyz = np.asarray(white, dtype=np.float64) @ matrix.T
    white_xyz = white_xyz / white_xyz[1]
    scale = 1.0 / (np.asarray(white, dtype=np.float64) @ matrix[1])
    lab_a = _lab(np.asarray(a, dtype=np.float64).reshape(-1, 3) @ matrix.T * scale, white_xyz)
    lab_b = _lab(np.asarray(b, dtype=np.float64).reshape(-1, 3) @ matrix.T * scale, white_xyz)
    return _ciede2000(lab_a, lab_b)
