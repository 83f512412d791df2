"""A plausible illuminant spectrum from one RGB colour (the environment's diffuse integral w_avg).

An RGB colour does not determine a spectrum: the most plausible one is made to reproduce it
exactly. A *base* spectrum comes from the colour's CCT and Duv (colour-science, Ohno 2013) by
one of :data:`ILLUMINANT_METHODS` (``daylight-planckian``, the default chosen by
``benchmarks/bench_target_chart.py``: CIE daylight at 5000 K and above, Planckian below);
it is then multiplied by the smooth factor ``c0 + c1 t + c2 t^2`` (``t = (lambda - 580 nm) /
200 nm``) whose coefficients make the camera see exactly w_avg. Colours off the locus (``|Duv|
>`` :data:`NATURAL_DUV`) or outside :data:`NATURAL_CCT` get ``smooth`` under ``auto``
(docs/target_chart.md).

References
----------
Ohno, Y. (2014). Practical use and calculation of CCT and Duv. LEUKOS 10(1), 47-55.
https://doi.org/10.1080/15502724.2014.839020
CIE 13.3-1995, Method of measuring and specifying colour rendering properties of light sources.
Jakob, W., Hanika, J. (2019). A low-dimensional function space for efficient spectral
upsampling. Computer Graphics Forum 38(2). https://doi.org/10.1111/cgf.13621
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError
from ocio_vp.spectra import align, cie_cmfs_sds, spectral_shape, wavelengths
from ocio_vp.synthesis.camera import CameraModel

__all__ = [
    "DAYLIGHT_FROM_CCT",
    "ILLUMINANT_METHODS",
    "NATURAL_CCT",
    "NATURAL_DUV",
    "IlluminantEstimate",
    "cct_duv",
    "estimate_illuminant",
    "given_illuminant",
    "match_colour",
]

#: |Duv| above this is not a natural light (ANSI C78.377's tolerance for white lights is ~0.006).
NATURAL_DUV = 0.006
#: CCT range (K) of natural light: candle/sunset to blue sky. Sodium lamps fall below.
NATURAL_CCT = (1800.0, 25000.0)
#: CIE 13.3 reference illuminants: Planckian below 5000 K, CIE daylight at and above.
DAYLIGHT_FROM_CCT = 5000.0
_MATCH_CONDITION_LIMIT = 1e8


def cct_duv(xyz: ArrayLike) -> tuple[float, float]:
    """Correlated colour temperature (K) and Duv of a CIE XYZ colour (Ohno 2013, colour-science).

    Examples
    --------
    CIE D65 (x, y = 0.3127, 0.3290) is about 6504 K, +0.0032 above the Planckian locus:

    >>> import colour
    >>> cct, duv = cct_duv(colour.xy_to_XYZ([0.3127, 0.3290]))
    >>> round(cct), round(duv, 4)
    (6504, 0.0032)
    """
    import colour

    xyz = np.asarray(xyz, dtype=np.float64)
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)) or xyz.sum() <= 0:
        raise InputError(f"expected a visible XYZ colour, got {np.round(xyz, 6).tolist()}")
    uv = colour.xy_to_UCS_uv(colour.XYZ_to_xy(xyz))
    cct, duv = colour.uv_to_CCT(uv, method="Ohno 2013")
    return float(cct), float(duv)


def _daylight(cct: float) -> np.ndarray:
    import colour

    return align(colour.sd_CIE_illuminant_D_series(colour.temperature.CCT_to_xy_CIE_D(cct)))


def _planckian(cct: float) -> np.ndarray:
    import colour

    return align(colour.sd_blackbody(cct, spectral_shape()))


def _recovered(xyz: np.ndarray, method: str) -> np.ndarray:
    import colour

    # The recovery methods make reflectances (<= 1) under an illuminant: ask for the colour's
    # chromaticity at a middle luminance under equal energy; the exact match rescales it.
    target = 0.4 * xyz / xyz[1]
    shape = spectral_shape()
    sd = colour.XYZ_to_sd(
        target, method=method, cmfs=cie_cmfs_sds(), illuminant=colour.sd_ones(shape)
    )
    return align(sd)


def _base_daylight_planckian(xyz: np.ndarray, cct: float) -> tuple[np.ndarray, str]:
    if cct >= DAYLIGHT_FROM_CCT:
        return _daylight(min(cct, NATURAL_CCT[1])), "CIE daylight"
    return _planckian(cct), "Planckian"


#: Base-spectrum methods: ``(XYZ, CCT) -> ((W,) spectrum, label)``.
ILLUMINANT_METHODS: dict[str, Callable[[np.ndarray, float], tuple[np.ndarray, str]]] = {
    "daylight-planckian": _base_daylight_planckian,
    "planckian": lambda xyz, cct: (_planckian(cct), "Planckian"),
    "smooth": lambda xyz, cct: (_recovered(xyz, "Jakob 2019"), "smooth (Jakob 2019)"),
    "flat": lambda xyz, cct: (np.ones(len(wavelengths())), "equal energy"),
}


def match_colour(base: ArrayLike, observer: ArrayLike, rgb: ArrayLike) -> np.ndarray:
    """``base (c0 + c1 t + c2 t^2)`` with the observer's response to it exactly ``rgb``.

    ``t = (lambda - 580) / 200``; the three coefficients solve ``observer.T @ B c = rgb`` where
    the columns of B are ``base t^k``. The result may be negative where the colour is far from
    the base's: callers check.

    Examples
    --------
    >>> observer = np.random.default_rng(0).random((81, 3))
    >>> spectrum = match_colour(np.ones(81), observer, [1.0, 2.0, 3.0])
    >>> np.round(observer.T @ spectrum, 9).tolist()
    [1.0, 2.0, 3.0]
    """
    base = np.asarray(base, dtype=np.float64)
    observer = np.asarray(observer, dtype=np.float64)
    t = (wavelengths() - 580.0) / 200.0
    basis = base[:, None] * t[:, None] ** np.arange(3)[None, :]
    system = observer.T @ basis
    if np.linalg.cond(system) > _MATCH_CONDITION_LIMIT:
        raise InputError("this camera cannot tell the spectrum's colour (singular response)")
    return basis @ np.linalg.solve(system, np.asarray(rgb, dtype=np.float64))


@dataclass(frozen=True)
class IlluminantEstimate:
    """A light's estimated spectrum (W,), matched to the colour; ``natural`` per CCT/Duv."""

    spectrum: np.ndarray
    label: str
    cct: float
    duv: float
    natural: bool
    warnings: tuple[str, ...] = ()


def _off_locus_reason(cct: float, duv: float) -> str | None:
    if abs(duv) > NATURAL_DUV:
        side = "green" if duv > 0 else "magenta"
        return (
            f"its colour is {duv:+.4f} Duv from the Planckian locus ({side} of it, CCT "
            f"{cct:.0f} K), beyond +-{NATURAL_DUV}: not daylight or incandescent light"
        )
    if not NATURAL_CCT[0] <= cct <= NATURAL_CCT[1]:
        return f"its CCT {cct:.0f} K is outside natural light's {NATURAL_CCT[0]:.0f}-{NATURAL_CCT[1]:.0f} K"
    return None


def estimate_illuminant(
    w_avg: ArrayLike, camera: CameraModel, *, method: str = "auto"
) -> IlluminantEstimate:
    """Estimate the light whose camera RGB is ``w_avg`` (see the module docstring).

    ``method="auto"``: ``daylight-planckian`` for natural colours, ``smooth`` otherwise, with a
    warning giving the reason; a base whose match goes negative also falls back to ``smooth``.

    Raises
    ------
    InputError
        Unknown method, a colour no non-negative spectrum of the kind matches, or black.
    """
    w_avg = np.asarray(w_avg, dtype=np.float64)
    if method != "auto" and method not in ILLUMINANT_METHODS:
        valid = ", ".join(["auto", *ILLUMINANT_METHODS])
        raise InputError(f"unknown illuminant method {method!r}; valid: {valid}", key="method")
    cct, duv = cct_duv(camera.to_xyz @ w_avg)
    reason = _off_locus_reason(cct, duv)
    warnings = []
    chosen = method
    if method == "auto":
        chosen = "daylight-planckian" if reason is None else "smooth"
        if reason:
            warnings.append(
                f"{reason}; RGB alone cannot tell its spectrum (LED, fluorescent or sodium "
                "light?), so a smooth spectrum of exactly that colour was assumed"
            )
    spectrum, label = _matched(chosen, camera, w_avg, cct)
    if np.min(spectrum) < 0 and method == "auto" and chosen != "smooth":
        warnings.append(f"{label} cannot match this colour without negative light; smooth used")
        spectrum, label = _matched("smooth", camera, w_avg, cct)
    if np.min(spectrum) < 0:
        raise InputError(
            f"no non-negative {label} spectrum has this colour (CCT {cct:.0f} K, Duv {duv:+.4f}); "
            "give the light's spectrum with --illuminant-spectrum"
        )
    return IlluminantEstimate(spectrum, label, cct, duv, reason is None, tuple(warnings))


def _matched(method: str, camera: CameraModel, w_avg: np.ndarray, cct: float):
    xyz = camera.to_xyz @ w_avg
    base, label = ILLUMINANT_METHODS[method](xyz, cct)
    return match_colour(base, camera.observer, w_avg), label


def given_illuminant(
    spectrum: ArrayLike, w_avg: ArrayLike, camera: CameraModel
) -> IlluminantEstimate:
    """A known light spectrum (W,), scaled so the camera's green sees w_avg's green.

    The shape is kept (it is the point of giving it); a colour that disagrees with w_avg's by
    more than 2% in red/green or blue/green is reported as a warning.
    """
    spectrum = np.asarray(spectrum, dtype=np.float64).reshape(-1)
    w_avg = np.asarray(w_avg, dtype=np.float64)
    rgb = camera.render(spectrum)
    if not rgb[1] > 0:
        raise InputError("the camera sees no light in this spectrum", key="--illuminant-spectrum")
    scaled = spectrum * w_avg[1] / rgb[1]
    cct, duv = cct_duv(camera.to_xyz @ w_avg)
    ratios = (camera.render(scaled) / np.where(w_avg > 0, w_avg, np.inf))[[0, 2]]
    warnings: tuple[str, ...] = ()
    if np.any(np.abs(ratios - 1.0) > 0.02):
        warnings = (
            "the given spectrum's colour differs from w_avg's (camera R/G, B/G off by "
            f"{np.round(100 * (ratios - 1.0), 1).tolist()}%); the spectrum's shape was kept",
        )
    return IlluminantEstimate(
        scaled, "given spectrum", cct, duv, _off_locus_reason(cct, duv) is None, warnings
    )
