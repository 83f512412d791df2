"""The post-correction Q as a typed object: what it is, where it was fitted, how it applies.

Every consumer (the config, ``ocio-vp apply``, the exports, the report, the simulator) is built
from one :data:`PostCorrection`. Its kinds (``matrix``, ``rank-deficient``, ``root-polynomial``,
``protected``) and the ``post_correction`` block of solution.json are in docs/solution.md; the
fit's domain (the chart's hull) and the fade outside it in docs/stability.md.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, eq. 5.
https://doi.org/10.1145/3543664.3543681

Finlayson, G. D., Mackiewicz, M., Hurlbert, A. (2015). Color Correction Using Root-Polynomial
Regression. IEEE Transactions on Image Processing 24(5), 1460-1470.
https://doi.org/10.1109/TIP.2015.2405336
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property, partial
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.deprecation import warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.model.expansion import (
    ROOT_POLYNOMIAL_TERMS,
    apply_root_polynomial,
    root_polynomial_terms,
)

if TYPE_CHECKING:  # formats imports model: the JSON types for annotations only
    from ocio_vp.formats.jsontypes import JsonObject, JsonValue

__all__ = [
    "DEFAULT_BRIGHT",
    "DEFAULT_DARK",
    "DEFAULT_FADE",
    "DEFAULT_NEGATIVE",
    "DRIVE_FLOOR",
    "HULL_MIN_RADIUS",
    "MAX_CONDITION_INVERSE",
    "PROTECTION",
    "FitDomain",
    "MatrixCorrection",
    "PostCorrection",
    "ProtectedCorrection",
    "ProtectionPoint",
    "RootPolynomialCorrection",
    "condition_number",
    "correction_from_dict",
    "correction_to_dict",
    "fit_domain",
    "matrix_invertible",
    "newton_inverse",
    "protection_words",
    "smoothstep",
    "truncated_pseudo_inverse",
    "unprotected",
]

#: A root-polynomial Q starts fading to its fallback matrix at the first gauge and has faded
#: out at the second (1 = the chart's hull).
DEFAULT_FADE = (1.0, 1.5)


def protection_words(bright: tuple[float, float], negative: tuple[float, float]) -> str:
    """Where an emitter protection hands over to the identity, in words."""
    return (
        f"the identity above {bright[1]:g}x white in any LED channel (fading from "
        f"{bright[0]:g}x) and beyond {negative[1]:.0%} negative drive (fading "
        f"from {negative[0]:.0%})"
    )


@dataclass(frozen=True)
class ProtectionPoint:
    """A point of ``solve --protect-emitters``: ``bright``, the brightness (largest
    drive-relative channel, 1 = a perfect white diffuser) where the fade to the identity starts
    and ends; ``negative``, the negative drive (most negative drive channel over the largest)
    where it starts and ends."""

    bright: tuple[float, float]
    negative: tuple[float, float]

    def setting(self) -> str:
        """The point in words, as :meth:`ProtectedCorrection.protection` words any point."""
        return protection_words(self.bright, self.negative)


#: ``--protect-emitters``' default point, chosen on the benchmark's tuning stages by the rule
#: in docs/accuracy.md. What it trades is measured there ("The trade-off of
#: --protect-emitters", written by ``python -m benchmarks.bench_accuracy``), not here.
PROTECTION = ProtectionPoint(bright=(1.1, 2.0), negative=(0.2, 0.5))
#: ``--protect-emitters``: the brightness fade (:attr:`ProtectionPoint.bright`).
DEFAULT_BRIGHT = PROTECTION.bright
#: ``--protect-emitters``: the negative-drive fade (:attr:`ProtectionPoint.negative`).
DEFAULT_NEGATIVE = PROTECTION.negative
#: ``--protect-emitters``: below this brightness (of a perfect white diffuser) negative drive
#: is measured against it rather than against the colour's own drive: near black, negative
#: channels are sensor noise, not light the wall cannot make.
DEFAULT_DARK = 2.0**-5
#: A lighting drive channel below this fraction of the largest counts as this fraction (a light
#: the wall cannot emit in that channel: reflectances there are noise and crosstalk).
DRIVE_FLOOR = 0.05
#: The hull always holds a disc of this radius (chromaticity units) around white, so that a
#: chart whose colours lie on a line (sodium light) still has a domain around white.
HULL_MIN_RADIUS = 0.02
#: Q with a condition number above this has no inverse (``rank-deficient``), and N = M Q^-1 is
#: not solved (:data:`ocio_vp.calibration.MAX_CONDITION_Q_FOR_N` is this number): Q^-1 would
#: amplify a 0.1% error in the chart measurements into more than 100% of the in-frustum drive
#: (as the paper found for low-pressure sodium, where Q has rank 1).
MAX_CONDITION_INVERSE = 1e3


def condition_number(matrix: ArrayLike) -> float:
    """2-norm condition number; ``inf`` for a singular (or non-finite) matrix."""
    matrix = np.asarray(matrix, dtype=np.float64)
    if not np.all(np.isfinite(matrix)):
        return float("inf")
    singular_values = np.linalg.svd(matrix, compute_uv=False)
    if singular_values[-1] <= singular_values[0] * np.finfo(np.float64).eps:
        return float("inf")
    return float(singular_values[0] / singular_values[-1])


def matrix_invertible(Q: ArrayLike) -> bool:
    """Whether a 3x3 Q may be inverted: the one rule every consumer asks (cond(Q) at most
    :data:`MAX_CONDITION_INVERSE`; a singular or non-finite Q never)."""
    return condition_number(Q) <= MAX_CONDITION_INVERSE


def truncated_pseudo_inverse(Q: ArrayLike) -> tuple[np.ndarray, int]:
    """Q's pseudo-inverse with the singular values below ``sigma_max /``
    :data:`MAX_CONDITION_INVERSE` dropped, and the rank kept: a bounded stand-in for the
    inverse of a Q that :func:`matrix_invertible` refuses (gain at most
    ``MAX_CONDITION_INVERSE / sigma_max``)."""
    U, sigma, Vt = np.linalg.svd(np.asarray(Q, dtype=np.float64))
    keep = sigma >= sigma[0] / MAX_CONDITION_INVERSE
    return (Vt.T[:, keep] / sigma[keep]) @ U[:, keep].T, int(keep.sum())


def smoothstep(t: ArrayLike) -> np.ndarray:
    """``3t^2 - 2t^3`` on [0, 1], clamped outside: 0 -> 0, 1 -> 1, zero slope at both ends.

    >>> smoothstep([-1.0, 0.0, 0.5, 1.0, 2.0]).tolist()
    [0.0, 0.0, 0.5, 1.0, 1.0]
    """
    t = np.clip(np.asarray(t, dtype=np.float64), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _fade_out(t: np.ndarray) -> np.ndarray:
    return 1.0 - smoothstep(t)


def _blend(
    base: np.ndarray, weight: np.ndarray, model: Callable[[np.ndarray], np.ndarray], x: np.ndarray
) -> np.ndarray:
    """``base + weight (model(x) - base)``, calling ``model`` only where ``weight > 0``."""
    out = base.copy()
    inside = weight > 0
    if np.any(inside):
        out[inside] += weight[inside][:, None] * (model(x[inside]) - base[inside])
    return out


def _array(value: JsonValue) -> np.ndarray:
    """A JSON list of numbers as float64 (TypeError/ValueError when it is not one)."""
    return np.asarray(value, dtype=np.float64)


def _number(value: JsonValue) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"expected a number, got {value!r:.40}")
    return float(value)


def _two(value: JsonValue) -> tuple[float, float]:
    low, high = _array(value).reshape(2)
    return float(low), float(high)


def _matrix(value: ArrayLike, key: str) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (3, 3) or not np.all(np.isfinite(array)):
        raise InputError(f"expected a finite 3x3 matrix, got shape {array.shape}", key=key)
    return array


def _pair(value: ArrayLike, key: str) -> tuple[float, float]:
    low, high = (float(v) for v in np.asarray(value, dtype=np.float64).reshape(2))
    if not (np.isfinite(low) and np.isfinite(high) and 0.0 <= low < high):
        raise InputError(f"expected [start, end] with 0 <= start < end, got {value!r}", key=key)
    return low, high


# ---------------------------------------------------------------------------------------------
# The domain


@dataclass(frozen=True)
class FitDomain:
    """Where the post-correction was fitted: reflective colours as the stage lights them.

    ``to_drive`` (3, 3) is ``U = D^-1 M``, camera RGB to drive relative to a perfect white
    diffuser; ``hull`` (k, 2) the counter-clockwise vertices of the chart's fitted patches in
    the chromaticity plane ``(u_r, u_b) / sum(u)``; ``centre`` (2,) white's chromaticity
    (docs/solution.md, "The domain"; built by :func:`fit_domain`).
    """

    to_drive: np.ndarray
    hull: np.ndarray
    centre: np.ndarray

    def __post_init__(self) -> None:
        hull = np.asarray(self.hull, dtype=np.float64)
        centre = np.asarray(self.centre, dtype=np.float64).reshape(2)
        if hull.ndim != 2 or hull.shape[1] != 2 or len(hull) < 3 or not np.all(np.isfinite(hull)):
            raise InputError("expected at least 3 finite [r, b] vertices", key="domain.hull")
        object.__setattr__(self, "to_drive", _matrix(self.to_drive, "domain.to_drive"))
        object.__setattr__(self, "hull", hull)
        object.__setattr__(self, "centre", centre)
        normals, reach = _edges(hull, centre)
        if not np.all(reach > 0):
            raise InputError("the hull must contain its centre", key="domain.hull")
        object.__setattr__(self, "_normals", normals / reach[:, None])

    @property
    def edge_normals(self) -> np.ndarray:
        """(k, 2) each hull edge's outward normal divided by the edge's distance from the
        centre: the gauge is ``max_i n_i . (c - centre)``."""
        return self._normals  # type: ignore[attr-defined]

    def drive(self, rgb: ArrayLike) -> np.ndarray:
        """(..., 3) ``u = U x``: drive relative to a perfect white diffuser, per LED channel."""
        return np.asarray(rgb, dtype=np.float64) @ self.to_drive.T

    def gauge(self, rgb: ArrayLike) -> np.ndarray:
        """(...,) how far ``rgb``'s chromaticity lies from white, in units of the hull: <= 1
        inside, 1 on its edge, 2 at twice its size; ``inf`` where ``sum(u) <= 0``.

        Homogeneous of degree 0 (``gauge(k x) = gauge(x)`` for ``k > 0``).
        """
        u = self.drive(rgb)
        total = u.sum(axis=-1)
        valid = total > 0
        c = u[..., [0, 2]] / np.where(valid, total, 1.0)[..., None]
        rho = np.max((c - self.centre) @ self._normals.T, axis=-1)  # type: ignore[attr-defined]
        return np.where(valid, rho, np.inf)

    def brightness(self, rgb: ArrayLike) -> np.ndarray:
        """(...,) the largest drive-relative channel ``max_k u_k`` (1: a perfect white)."""
        return np.max(self.drive(rgb), axis=-1)

    def negativity(
        self, rgb: ArrayLike, drive_matrix: np.ndarray, floor: float = 0.0
    ) -> np.ndarray:
        """(...,) ``-min_k (M x)_k / max(max_k (M x)_k, floor)``: the negative light a colour
        needs, relative to its largest drive or ``floor`` (in the same drive units), whichever
        is larger (``inf`` when neither is positive)."""
        d = np.asarray(rgb, dtype=np.float64) @ np.asarray(drive_matrix).T
        top = np.maximum(d.max(axis=-1), floor)
        return np.where(top > 0, -d.min(axis=-1) / np.where(top > 0, top, 1.0), np.inf)

    def to_dict(self) -> JsonObject:
        return {
            "to_drive": self.to_drive.tolist(),
            "hull": self.hull.tolist(),
            "centre": self.centre.tolist(),
        }

    @classmethod
    def from_dict(cls, data: JsonValue) -> FitDomain:
        try:
            if not isinstance(data, Mapping):
                raise TypeError("expected a mapping")
            return cls(_array(data["to_drive"]), _array(data["hull"]), _array(data["centre"]))
        except (KeyError, TypeError, ValueError) as error:
            raise InputError(f"malformed domain ({error})", key="post_correction.domain") from None


def _edges(hull: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward normals of the polygon's edges and each edge's distance along it from centre."""
    following = np.roll(hull, -1, axis=0)
    edge = following - hull
    normals = np.stack([edge[:, 1], -edge[:, 0]], axis=-1)  # outward for counter-clockwise
    return normals, np.einsum("ij,ij->i", normals, hull - centre)


def _convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise hull vertices (Andrew's monotone chain; collinear points dropped)."""
    pts = sorted(set(map(tuple, np.round(points, 15))))
    if len(pts) < 3:
        return np.asarray(pts, dtype=np.float64)

    def half(sequence):
        chain: list[tuple[float, float]] = []
        for p in sequence:
            while len(chain) >= 2:
                (ax, ay), (bx, by) = chain[-2], chain[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 1e-15:
                    break
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(reversed(pts))
    return np.asarray(lower[:-1] + upper[:-1], dtype=np.float64)


def fit_domain(
    lit_chart: ArrayLike,
    *,
    M: ArrayLike,
    white_patch: int,
    white_reflectance: float,
    weights: ArrayLike | None = None,
) -> FitDomain:
    """The :class:`FitDomain` of a chart as the stage lights it (``lit_chart``: eq. 3, (n, 3)).

    The drive of a perfect white is the lit white patch's drive over its reflectance; the hull
    holds the fitted patches (``weights > 0``) and a disc of :data:`HULL_MIN_RADIUS` around
    white (12 points), so white is always strictly inside.

    Examples
    --------
    >>> SL = np.array([[0.9, 0.1, 0.0], [0.2, 0.8, 0.1], [0.0, 0.1, 0.9]])
    >>> rho = np.random.default_rng(0).uniform(0.05, 0.9, (24, 3))
    >>> rho[18] = 0.9
    >>> domain = fit_domain(rho @ SL.T, M=np.linalg.inv(SL), white_patch=18,
    ...                     white_reflectance=0.9)
    >>> np.round(domain.drive((0.9 * SL.sum(axis=1))), 12).tolist()
    [0.9, 0.9, 0.9]
    >>> bool(domain.gauge(rho[:5] @ SL.T).max() <= 1 + 1e-12)
    True
    """
    X = np.asarray(lit_chart, dtype=np.float64)
    M = np.asarray(M, dtype=np.float64)
    w = np.ones(len(X)) if weights is None else np.asarray(weights, dtype=np.float64)
    white = np.clip(M @ X[white_patch], 0.0, None) / float(white_reflectance)
    if not white.max() > 0:
        raise InputError("the lit white patch has no positive drive", key="lit_chart")
    white = np.maximum(white, DRIVE_FLOOR * white.max())
    to_drive = M / white[:, None]
    u = X[w > 0] @ to_drive.T
    total = u.sum(axis=-1)
    chroma = u[total > 0][:, [0, 2]] / total[total > 0, None]
    centre_u = X[white_patch] @ to_drive.T
    centre = centre_u[[0, 2]] / centre_u.sum()
    angles = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    disc = centre + HULL_MIN_RADIUS * np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    return FitDomain(to_drive, _convex_hull(np.vstack([chroma, disc])), centre)


# ---------------------------------------------------------------------------------------------
# The kinds


@dataclass(frozen=True)
class MatrixCorrection:
    """``Q x``: every linear method (the paper's eq. 5 among them)."""

    Q: np.ndarray
    domain: FitDomain | None = None

    linear: ClassVar[bool] = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "Q", _matrix(self.Q, "Q"))

    @property
    def kind(self) -> str:
        return "matrix" if self.invertible else "rank-deficient"

    @property
    def matrix(self) -> np.ndarray:
        return self.Q

    @property
    def invertible(self) -> bool:
        return matrix_invertible(self.Q)

    @property
    def homogeneous(self) -> bool:
        """Deprecated: whether ``apply`` commutes with scaling (Q(kx) = k Q(x))."""
        warn_deprecated("MatrixCorrection.homogeneous", "its inverse's own handling of scale")
        return True

    def apply(self, rgb: ArrayLike) -> np.ndarray:
        """(..., 3) ``Q rgb``."""
        return np.asarray(rgb, dtype=np.float64) @ self.Q.T

    def inverse(self, rgb: ArrayLike) -> np.ndarray:
        """(..., 3) ``Q^-1 rgb``; an InputError for a ``rank-deficient`` Q."""
        if not self.invertible:
            raise InputError("Q is rank-deficient: it has no inverse", key="post_correction")
        return np.asarray(rgb, dtype=np.float64) @ np.linalg.inv(self.Q).T

    def describe(self) -> str:
        rank = "" if self.invertible else ", rank-deficient: no inverse"
        return f"3x3 matrix{rank}"

    def parameters(self) -> JsonObject:
        return {"Q": self.Q.tolist()}


@dataclass(frozen=True)
class RootPolynomialCorrection:
    """``C e(x)`` inside the fit's domain, fading to the ``fallback`` matrix outside it.

    ``weight(x) = 1 - smoothstep((gauge(x) - 1) / (fade - 1))``; ``Q(x) = A x + weight (C e(x)
    - A x)`` with ``A`` the fallback. Homogeneous of degree 1 (the gauge is of degree 0), so
    exposure-invariant like a matrix. ``domain=None`` (a solution.json written before the domain
    existed) is the unbounded polynomial, as those files were applied.
    """

    coefficients: np.ndarray
    fallback: np.ndarray
    domain: FitDomain | None = None
    fade: tuple[float, float] = DEFAULT_FADE

    kind: ClassVar[str] = "root-polynomial"
    linear: ClassVar[bool] = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "fade", _pair(self.fade, "post_correction.parameters.fade"))
        C = np.asarray(self.coefficients, dtype=np.float64)
        if C.ndim != 2 or C.shape[0] != 3 or C.shape[1] not in ROOT_POLYNOMIAL_TERMS.values():
            raise InputError(
                f"root-polynomial coefficients must be (3, terms), got shape {C.shape}",
                key="post_correction.parameters.coefficients",
            )
        if not np.all(np.isfinite(C)):
            raise InputError("non-finite coefficients", key="post_correction.parameters")
        object.__setattr__(self, "coefficients", C)
        object.__setattr__(self, "fallback", _matrix(self.fallback, "fallback"))

    @property
    def degree(self) -> int:
        return next(d for d, n in ROOT_POLYNOMIAL_TERMS.items() if n == self.coefficients.shape[1])

    @property
    def matrix(self) -> np.ndarray:
        return self.fallback

    @property
    def invertible(self) -> bool:
        return matrix_invertible(self.fallback)

    @property
    def homogeneous(self) -> bool:
        """Deprecated: whether ``apply`` commutes with scaling (Q(kx) = k Q(x))."""
        warn_deprecated(
            "RootPolynomialCorrection.homogeneous", "its inverse's own handling of scale"
        )
        return True

    def weight(self, rgb: ArrayLike) -> np.ndarray:
        """(...,) 1 where the polynomial applies, 0 where the fallback does."""
        if self.domain is None:
            return np.ones(np.shape(rgb)[:-1])
        return self.weight_at(self.domain.gauge(rgb))

    def weight_at(self, gauge: np.ndarray) -> np.ndarray:
        """(...,) the weight at a :meth:`FitDomain.gauge` of the domain (this fade's)."""
        start, end = self.fade
        return _fade_out((gauge - start) / (end - start))

    def apply(self, rgb: ArrayLike) -> np.ndarray:
        """(..., 3) the correction of ``rgb`` (float64)."""
        x = np.asarray(rgb, dtype=np.float64)
        if self.domain is None:
            return apply_root_polynomial(self.coefficients, x)
        polynomial = partial(apply_root_polynomial, self.coefficients)
        return _blend(x @ self.fallback.T, self.weight(x), polynomial, x)

    def blend(
        self,
        x: np.ndarray,
        linear: np.ndarray,
        weight: np.ndarray,
        polynomial: Callable[[np.ndarray], np.ndarray],
    ) -> np.ndarray:
        """(..., 3) :meth:`apply` of ``x`` from its parts: the fallback's output ``linear``,
        :meth:`weight` and ``polynomial`` (``C e(.)`` of the points where the weight is
        positive), for callers that evaluate several fades at the same points."""
        return _blend(linear, weight, polynomial, x)

    def inverse(self, rgb: ArrayLike) -> np.ndarray:
        return newton_inverse(self.apply, rgb, self.fallback, homogeneous=True)

    def describe(self) -> str:
        bound = (
            "unbounded (a file from before the domain)"
            if self.domain is None
            else f"inside the chart's domain, fading to the 3x3 fallback from {self.fade[0]:g}x to "
            f"{self.fade[1]:g}x its size"
        )
        return f"root-polynomial degree {self.degree}, {bound}"

    def parameters(self) -> JsonObject:
        return {
            "degree": self.degree,
            "terms": root_polynomial_terms(self.degree),
            "coefficients": self.coefficients.tolist(),
            "fallback": self.fallback.tolist(),
            "fade": list(self.fade),
        }


@dataclass(frozen=True)
class ProtectedCorrection:
    """``inner`` where a reflective surface lit by the stage can be, the identity elsewhere.

    ``weight = fade(brightness; bright) * fade(negativity; negative)``: brightness is the
    largest drive-relative channel (:meth:`FitDomain.brightness`, 1 = a perfect white),
    negativity the negative light the colour needs (:meth:`FitDomain.negativity`), relative to
    its largest drive or, below ``dark`` times a perfect white's, to that (files written before
    ``dark`` existed read as 0: no floor); each fades out between its (start, end). ``Q(x) = x + weight (inner(x) - x)``. Brightness depends on
    exposure: the domain is the calibration's, so footage exposed brighter than the chart's
    plates should be scaled to it first (docs/stability.md).
    """

    inner: MatrixCorrection | RootPolynomialCorrection
    domain: FitDomain
    drive_matrix: np.ndarray
    bright: tuple[float, float] = DEFAULT_BRIGHT
    negative: tuple[float, float] = DEFAULT_NEGATIVE
    dark: float = 0.0

    kind: ClassVar[str] = "protected"
    linear: ClassVar[bool] = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "drive_matrix", _matrix(self.drive_matrix, "drive_matrix"))
        object.__setattr__(self, "bright", _pair(self.bright, "post_correction.bright"))
        object.__setattr__(self, "negative", _pair(self.negative, "post_correction.negative"))
        if self.bright[0] <= 0:
            raise InputError("the brightness fade must start above 0", key="post_correction")
        if not (np.isfinite(self.dark) and 0.0 <= self.dark < self.bright[0]):
            raise InputError(
                "dark must be at least 0 and below the brightness fade", key="post_correction.dark"
            )
        object.__setattr__(self, "dark", float(self.dark))

    @cached_property
    def floor(self) -> float:
        """``dark`` in drive units: the least drive negative light is measured against."""
        return self.dark * _white_drive(self.domain, self.drive_matrix)

    @property
    def matrix(self) -> np.ndarray:
        return self.inner.matrix

    @property
    def invertible(self) -> bool:
        return self.inner.invertible

    @property
    def homogeneous(self) -> bool:
        """Deprecated: whether ``apply`` commutes with scaling (Q(kx) = k Q(x))."""
        warn_deprecated("ProtectedCorrection.homogeneous", "its inverse's own handling of scale")
        return False

    def weight(self, rgb: ArrayLike) -> np.ndarray:
        """(...,) 1 where ``inner`` applies, 0 where the identity does."""
        v = self.domain.brightness(rgb)
        low, high = self.bright
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.log2(np.maximum(v, 1e-300) / low) / np.log2(high / low)
        g_bright = np.where(v > 0, _fade_out(t), 1.0)  # no positive drive: dark, not bright
        n = self.domain.negativity(rgb, self.drive_matrix, self.floor)
        start, end = self.negative
        g_negative = np.where(np.isfinite(n), _fade_out((n - start) / (end - start)), 0.0)
        return g_bright * g_negative

    def apply(self, rgb: ArrayLike) -> np.ndarray:
        x = np.asarray(rgb, dtype=np.float64)
        return _blend(x, self.weight(x), self.inner.apply, x)

    def inverse(self, rgb: ArrayLike) -> np.ndarray:
        return newton_inverse(self.apply, rgb, self.inner.matrix, homogeneous=False)

    def describe(self) -> str:
        return f"{self.inner.describe()}; emitters protected: {self.protection()}"

    def protection(self) -> str:
        """Where the identity takes over, in words."""
        return protection_words(self.bright, self.negative)

    def parameters(self) -> JsonObject:
        return {
            "inner": correction_to_dict(self.inner),
            "drive_matrix": self.drive_matrix.tolist(),
            "bright": list(self.bright),
            "negative": list(self.negative),
            "dark": self.dark,
        }


def _white_drive(domain: FitDomain, drive_matrix: np.ndarray) -> float:
    """The largest channel of the drive (``drive_matrix`` units) of a perfect white diffuser:
    the colour whose drive relative to white (:meth:`FitDomain.drive`) is 1 in every channel."""
    try:
        white = np.linalg.solve(domain.to_drive, np.ones(3))
    except np.linalg.LinAlgError:
        return 0.0
    return float(max(np.max(drive_matrix @ white), 0.0))


#: Every kind of post-correction.
PostCorrection = MatrixCorrection | RootPolynomialCorrection | ProtectedCorrection


def unprotected(correction: PostCorrection) -> MatrixCorrection | RootPolynomialCorrection:
    """The model a correction applies where nothing fades it out: a protected one's inner
    model, any other one itself."""
    return correction.inner if isinstance(correction, ProtectedCorrection) else correction


# ---------------------------------------------------------------------------------------------
# The inverse


def newton_inverse(
    function: Callable[[np.ndarray], np.ndarray],
    rgb: ArrayLike,
    start_matrix: np.ndarray,
    *,
    homogeneous: bool,
    tolerance: float = 1e-12,
    max_iterations: int = 50,
    start: ArrayLike | None = None,
    jacobian: Callable[[np.ndarray], np.ndarray] | None = None,
    halvings: int = 16,
) -> np.ndarray:
    """x with ``function(x) = rgb`` for (..., 3) ``rgb``: damped Newton with a finite-difference
    Jacobian (or ``jacobian``: (n, 3) -> (n, 3, 3)), started from ``start_matrix^-1 rgb`` (or
    from ``start``, the same shape as ``rgb``: a close guess, e.g. a neighbour's solution); every
    colour at once; a step is halved at most ``halvings`` times until it lowers the residual.

    A ``homogeneous`` function is solved on each colour's direction (divided by its largest
    absolute channel, then scaled back) and maps black to black. A colour whose iteration does
    not reach ``tolerance`` (relative to its size; the function folds there) keeps its best
    iterate, which is always finite.
    """
    y = np.asarray(rgb, dtype=np.float64)
    flat = y.reshape(-1, 3)
    scale = np.max(np.abs(flat), axis=1) if homogeneous else np.ones(len(flat))
    live = np.all(np.isfinite(flat), axis=1) & (scale > 0)
    target = np.zeros_like(flat)
    target[live] = flat[live] / scale[live, None]
    size = np.maximum(np.max(np.abs(target), axis=1), 1e-300)
    if start is None:
        x = target @ np.linalg.inv(start_matrix).T
    else:
        x = np.asarray(start, dtype=np.float64).reshape(-1, 3) / np.where(live, scale, 1.0)[:, None]
        x = np.where(np.all(np.isfinite(x), axis=1)[:, None], x, 0.0)
    residual = function(x) - target
    norm = np.max(np.abs(residual), axis=1) / size
    active = live.copy()
    for _ in range(max_iterations):
        todo = np.flatnonzero(active & (norm > tolerance))
        if len(todo) == 0:
            break
        step = _newton_step(function, x[todo], residual[todo], start_matrix, jacobian)
        for alpha in 2.0 ** -np.arange(0, halvings):
            trial = x[todo] + alpha * step
            r = function(trial) - target[todo]
            n = np.max(np.abs(r), axis=1) / size[todo]
            better = np.isfinite(n) & (n < norm[todo])
            done = todo[better]
            x[done], residual[done], norm[done] = trial[better], r[better], n[better]
            todo, step = todo[~better], step[~better]
            if len(todo) == 0:
                break
        active[todo] = False  # no step lowers the residual: keep the best iterate
    out = x * scale[:, None] if homogeneous else x
    out[~live] = 0.0
    return out.reshape(y.shape)


def _newton_step(function, x: np.ndarray, residual: np.ndarray, fallback: np.ndarray, jacobian):
    """``-J^-1 r`` with ``jacobian``'s J or a central-difference one; the fallback matrix where
    J is singular or not finite."""
    if jacobian is not None:
        J = jacobian(x)
    else:
        h = 1e-6 * np.maximum(np.max(np.abs(x), axis=1, keepdims=True), 1e-12)
        J = np.empty((len(x), 3, 3))
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            J[:, :, k] = (function(x + h * e) - function(x - h * e)) / (2 * h)
    finite = np.all(np.isfinite(J), axis=(1, 2))
    det = np.linalg.det(np.where(finite[:, None, None], J, fallback))
    bad = ~finite | (np.abs(det) < 1e-12 * abs(np.linalg.det(fallback)))
    J[bad] = fallback
    return -np.linalg.solve(J, residual[..., None])[..., 0]


# ---------------------------------------------------------------------------------------------
# solution.json


def correction_to_dict(correction: PostCorrection) -> JsonObject:
    """The ``post_correction`` block: ``kind``, ``parameters`` and ``domain``."""
    domain = getattr(correction, "domain", None)
    return {
        "kind": correction.kind,
        "parameters": correction.parameters(),
        "domain": None if domain is None else domain.to_dict(),
    }


def correction_from_dict(data: JsonValue) -> PostCorrection:
    """A :data:`PostCorrection` from its ``post_correction`` block (InputError when malformed)."""
    if not isinstance(data, Mapping):
        raise InputError("expected a mapping", key="post_correction")
    kind, parameters = data.get("kind"), data.get("parameters")
    if not isinstance(parameters, Mapping):
        raise InputError("expected a parameters mapping", key="post_correction.parameters")
    domain = None if data.get("domain") is None else FitDomain.from_dict(data["domain"])
    try:
        if kind in ("matrix", "rank-deficient"):
            return MatrixCorrection(_array(parameters["Q"]), domain)
        if kind == "root-polynomial":
            return RootPolynomialCorrection(
                _array(parameters["coefficients"]),
                _array(parameters["fallback"]),
                domain,
                _two(parameters.get("fade", list(DEFAULT_FADE))),
            )
        if kind == "protected":
            if domain is None:
                raise InputError("a protected correction needs its domain", key="post_correction")
            block = parameters["inner"]
            if not isinstance(block, Mapping):
                raise TypeError("inner: expected a mapping")
            inner = correction_from_dict({**block, "domain": data.get("domain")})
            if isinstance(inner, ProtectedCorrection):
                raise InputError(
                    "a protected correction cannot protect another",
                    key="post_correction.parameters.inner",
                )
            return ProtectedCorrection(
                inner,
                domain,
                _array(parameters["drive_matrix"]),
                _two(parameters["bright"]),
                _two(parameters["negative"]),
                _number(parameters.get("dark", 0.0)),  # files before it: no dark floor
            )
    except InputError as error:
        key = error.key or ""
        if not key.startswith("post_correction"):
            key = f"post_correction.parameters.{key}".rstrip(".")
        raise InputError(error.problem, key=key) from None
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(f"malformed {kind} parameters ({error})", key="post_correction") from None
    raise InputError(
        f"unknown kind {kind!r}; expected matrix, rank-deficient, root-polynomial or protected",
        key="post_correction.kind",
    )
