"""How a post-correction behaves beyond the chart, measured on every solve, and the bound on it.

Footage holds more than the chart's reflective colours: saturated surfaces, emitters and
highlights above white. What a fit does there is measured here from the calibration alone:

- :func:`fold_fraction`: the share of the reflective solid (drive-relative ``u`` in [0, 1]^3,
  :class:`~ocio_vp.model.correction.FitDomain`) where the correction's Jacobian determinant has
  the other sign than its matrix's: two reflective colours that the correction maps to one
  (it folds), so neither is corrected right and no inverse exists there.
- :func:`choose_fade`: the first fade of :data:`FADES` (the root-polynomial's transition to its
  fallback matrix, widest gain first) under which the bounded model folds nowhere in the
  reflective solid; None when none does (the model is then unsafe: ``auto`` does not take it).
- :func:`saturation_probe`: bright saturated inputs (each camera channel dominant, the others
  at 1 %, from 1x to 16x the white patch): the least share of its dominant channel an output
  keeps (a *collapse* below :data:`MIN_RETAINED`) and the most negative output channel relative
  to the dominant one (a *flip* below :data:`MIN_NEGATIVE`).
- :func:`in_frame_led_damage`: the wall's own LEDs seen in frame (its primaries and their
  pairwise mixes at 1/4, 1 and 4 times the white patch's luminance) are emitters whose camera
  RGB the calibration measured: recorded alike on stage and on location, so the right
  correction leaves them alone. The p95 ΔE2000 between Q(x) and x over them is the emitter
  damage a solve can measure without spectra (docs/accuracy.md measures it on emitters).
"""

from __future__ import annotations

import numpy as np

from ocio_vp.formats.diagnostics import (
    MIN_NEGATIVE,
    MIN_RETAINED,
    Extrapolation,
    lowest_channel_words,
)
from ocio_vp.metrics import camera_delta_E_2000
from ocio_vp.model.correction import (
    FitDomain,
    MatrixCorrection,
    PostCorrection,
    RootPolynomialCorrection,
)
from ocio_vp.model.expansion import apply_root_polynomial
from ocio_vp.model.footage_range import EMITTER_LEVELS, wall_emitters

__all__ = [
    "FADES",
    "MIN_NEGATIVE",
    "MIN_RETAINED",
    "Extrapolation",
    "choose_fade",
    "extrapolation",
    "fade_label",
    "fold_fraction",
    "in_frame_led_damage",
    "lowest_channel_words",
    "saturation_probe",
]

#: Fades tried for a root-polynomial Q (start, end gauge), the one keeping most of the
#: polynomial first; the first that folds nowhere in the reflective solid is taken.
FADES = ((1.0, 1.5), (0.75, 1.5), (0.5, 1.5))
#: Points of the reflective solid the fold check samples (a fixed quasi-random set).
FOLD_SAMPLES = 4096


def _halton(n: int, base: int) -> np.ndarray:
    """The first ``n`` points of the van der Corput sequence in ``base`` (deterministic)."""
    out = np.zeros(n)
    for i in range(n):
        f, k, value = 1.0, i + 1, 0.0
        while k:
            f /= base
            value += f * (k % base)
            k //= base
        out[i] = value
    return out


_REFLECTIVE = np.stack([_halton(FOLD_SAMPLES, b) for b in (2, 3, 5)], axis=-1)


def fold_fraction(correction: PostCorrection, domain: FitDomain) -> float:
    """Share of the reflective solid where the correction folds (see the module docstring)."""
    pairs, h = _shifted(domain)
    columns = [
        (correction.apply(plus) - correction.apply(minus)) / (2 * h) for plus, minus in pairs
    ]
    return _folded(columns, correction.matrix)


def _shifted(domain: FitDomain) -> tuple[list[tuple[np.ndarray, np.ndarray]], float]:
    """The reflective solid's sample points as camera RGB, shifted by +/- the derivatives' step
    along each channel (the central differences' pairs), and that step."""
    x = _REFLECTIVE @ np.linalg.inv(domain.to_drive).T
    h = 1e-7 * float(np.max(np.abs(x)))
    return [(x + h * e, x - h * e) for e in np.eye(3)], h


def _folded(columns: list[np.ndarray], matrix: np.ndarray) -> float:
    """The share of points whose Jacobian (its ``columns``) has the other sign than ``matrix``."""
    det = np.linalg.det(np.stack(columns, axis=-1))
    reference = np.sign(np.linalg.det(matrix)) or 1.0
    return float(np.mean(np.sign(det) != reference))


class _Side:
    """One shifted copy of the solid's points and what every fade shares there: the fallback's
    output, the gauge, and the polynomial on the last set of points a fade weighted."""

    def __init__(self, x: np.ndarray, fallback: np.ndarray, domain: FitDomain) -> None:
        self.x, self.linear, self.gauge = x, x @ fallback.T, domain.gauge(x)
        self._points: np.ndarray | None = None
        self._poly = np.empty((0, 3))

    def apply(self, correction: RootPolynomialCorrection) -> np.ndarray:
        """``correction.apply(self.x)``, the same operations on the shared parts."""

        def polynomial(points: np.ndarray) -> np.ndarray:
            if self._points is None or not np.array_equal(points, self._points):
                self._points = points
                self._poly = apply_root_polynomial(correction.coefficients, points)
            return self._poly

        weight = correction.weight_at(self.gauge)
        return correction.blend(self.x, self.linear, weight, polynomial)


def fade_label(fade: tuple[float, float]) -> str:
    """A fade's key in :func:`choose_fade`'s table, e.g. ``"0.75-1.5"``."""
    return f"{fade[0]:g}-{fade[1]:g}"


def choose_fade(
    coefficients: np.ndarray, fallback: np.ndarray, domain: FitDomain
) -> tuple[tuple[float, float] | None, dict[str, float]]:
    """The first of :data:`FADES` whose bounded root-polynomial folds nowhere in the reflective
    solid (None when every one folds), and each tried fade's fold fraction (by
    :func:`fade_label`): :func:`fold_fraction` of each, with the fallback's output, the gauge
    and the polynomial at the solid's points computed once for all the fades."""
    corrections = [RootPolynomialCorrection(coefficients, fallback, domain, f) for f in FADES]
    pairs, h = _shifted(domain)
    matrix = corrections[0].fallback
    sides = [(_Side(plus, matrix, domain), _Side(minus, matrix, domain)) for plus, minus in pairs]
    tried: dict[str, float] = {}
    for fade, correction in zip(FADES, corrections, strict=True):
        columns = [
            (plus.apply(correction) - minus.apply(correction)) / (2 * h) for plus, minus in sides
        ]
        folds = _folded(columns, correction.matrix)
        tried[fade_label(fade)] = folds
        if folds == 0.0:
            return fade, tried
    return None, tried


def saturation_probe(correction: PostCorrection, white: np.ndarray) -> tuple[float, float]:
    """(least share of the dominant channel kept, most negative channel relative to the
    dominant output) over bright saturated inputs: each channel dominant, the others at 1 %,
    at 1, 2, 4, 8 and 16 times the largest channel of ``white`` (the lit white patch)."""
    top = float(np.max(np.abs(white)))
    probes = []
    for k in range(3):
        x = np.full(3, 0.01)
        x[k] = 1.0
        probes += [top * level * x for level in (1.0, 2.0, 4.0, 8.0, 16.0)]
    x = np.asarray(probes)
    y = correction.apply(x)
    dominant = np.argmax(x, axis=1)
    rows = np.arange(len(x))
    kept = y[rows, dominant] / x[rows, dominant]
    relative = y.min(axis=1) / np.maximum(np.abs(y[rows, dominant]), 1e-300)
    relative = np.where(y[rows, dominant] > 0, relative, -np.inf)
    return float(kept.min()), float(relative.min())


def in_frame_led_damage(
    correction: PostCorrection,
    SL: np.ndarray,
    white: np.ndarray,
    camera_to_xyz: np.ndarray,
) -> float:
    """p95 ΔE2000 between Q(x) and x over the wall's own LEDs in frame (module docstring);
    ``white`` is the target white patch (camera RGB), the reference white of the ΔE."""
    leds = wall_emitters(SL, white, camera_to_xyz)
    x = np.vstack([leds * level for level in EMITTER_LEVELS])
    if len(x) == 0:
        return 0.0
    moved = camera_delta_E_2000(x, correction.apply(x), camera_to_xyz=camera_to_xyz, white=white)
    return float(np.percentile(moved, 95))


def extrapolation(
    correction: PostCorrection,
    least_squares: np.ndarray,
    *,
    SL: np.ndarray,
    white: np.ndarray,
    lit_white: np.ndarray,
    camera_to_xyz: np.ndarray,
    domain: FitDomain,
    folds: float | None = None,
) -> Extrapolation:
    """:class:`Extrapolation` of ``correction`` against the least-squares matrix; ``white`` is
    the target white patch (the ΔE's reference), ``lit_white`` the lit one (the probes' scale);
    ``folds`` the fold fraction where the solve already measured it (:attr:`QFit.folds
    <ocio_vp.correction.problem.QFit.folds>`), else it is measured here: 0 for an invertible
    matrix, None where Q's matrix is singular (its Jacobian's sign is rounding there)."""
    if not correction.invertible:
        folds = None
    elif correction.linear:
        folds = 0.0
    elif folds is None:
        folds = fold_fraction(correction, domain)
    kept, negative = saturation_probe(correction, lit_white)
    return Extrapolation(
        led_damage=in_frame_led_damage(correction, SL, white, camera_to_xyz),
        led_damage_least_squares=in_frame_led_damage(
            MatrixCorrection(least_squares), SL, white, camera_to_xyz
        ),
        kept=kept,
        negative=negative,
        folds=folds,
    )
