"""The data of a post-correction (Q) solve (eq. 5 of the paper) and its result.

:class:`QProblem` and :class:`QFit` live apart from :mod:`ocio_vp.correction.registry`
(which re-exports them) so that the methods can import them without an import cycle.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ocio_vp.calibration.equations import predict_lit_chart
from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.correction.skin import SkinRows, SkinSamples, skin_rows
from ocio_vp.model.correction import FitDomain, fit_domain

if TYPE_CHECKING:
    from ocio_vp.model.correction import PostCorrection

__all__ = ["Folds", "QFit", "QProblem", "fit_least_squares"]


@dataclass(frozen=True)
class QProblem:
    """The data of eq. 5 for one environment.

    ``SRL`` is (n, 3, 3) as photographed (not divided by beta); ``target`` the (n, 3) p_j;
    ``weights`` (n,) is 1 for patches to fit and 0 for excluded ones (e.g. clipped).
    """

    SL: np.ndarray
    SRL: np.ndarray
    beta: float
    M: np.ndarray
    w_avg: np.ndarray
    target: np.ndarray
    white_patch: int = DEFAULT_WHITE_PATCH
    weights: np.ndarray | None = None
    #: (n, 3) light on the chart beyond eq. 3's (practical fixtures, a changed wall drive:
    #: :mod:`ocio_vp.fixtures.lighting`); None for the wall alone.
    extra_light: np.ndarray | None = None
    #: Reflectance of the white patch (sets the drive of a perfect white diffuser, the top of
    #: the reflective domain: :func:`ocio_vp.model.correction.fit_domain`).
    white_reflectance: float = 0.9
    #: Skin as this stage and the location see it (:mod:`ocio_vp.correction.skin`); None where
    #: the chart gives none.
    skin: SkinSamples | None = None
    #: (3,) the camera's reading of the dark in-frustum panels (``black_level``), what the
    #: in-frustum offset cancels; None where not measured.
    black_level: np.ndarray | None = None

    # The derived arrays below are computed once per problem (a frozen dataclass keeps no
    # state but these caches) and read-only, since every solve step shares them.
    @cached_property
    def drive(self) -> np.ndarray:
        """(3,) ``M w_avg`` as the wall emits it: a negative channel clipped to 0."""
        return _read_only(np.clip(np.asarray(self.M, dtype=np.float64) @ self.w_avg, 0.0, None))

    @cached_property
    def skin_predicted(self) -> np.ndarray | None:
        """(k, 3) the skin samples lit as :attr:`predicted` lights the chart (None: no skin)."""
        if self.skin is None:
            return None
        return _read_only(self.skin.lit(self.beta, self.drive, self.extra_light))

    def skin_rows(self, skin_weight: float) -> SkinRows | None:
        """The skin samples as rows to fit beside the chart's
        (:func:`ocio_vp.correction.skin.skin_rows`); None without samples or weight."""
        lit = self.skin_predicted
        if not skin_weight or lit is None or self.skin is None or self.skin.count == 0:
            return None
        target = np.asarray(self.target, dtype=np.float64)
        return skin_rows(
            lit, self.skin.target, target, self.fit_weights, self.white_patch, skin_weight
        )

    @cached_property
    def predicted(self) -> np.ndarray:
        """(n, 3) the lit chart, eq. 3 plus ``extra_light``: the x_j that Q maps to p_j.

        Eq. 3 with the drive the wall can emit: a negative channel of ``M w_avg`` (a light
        outside the LEDs' gamut, e.g. sodium) is clipped to 0, as the wall clips it, so Q is
        not fitted to colours the camera never sees (docs/accuracy.md).
        """
        lit = predict_lit_chart(self.SRL, self.beta, np.eye(3), self.drive)
        return _read_only(lit if self.extra_light is None else lit + self.extra_light)

    @cached_property
    def domain(self) -> FitDomain:
        """Where the post-correction is fitted (:func:`ocio_vp.model.correction.fit_domain`):
        the lit chart as the wall really lights it, the calibrated M, the fitted patches. One
        object per problem: a measurement made over it (:class:`Folds`) knows it by identity."""
        return fit_domain(
            self.predicted,
            M=self.M,
            white_patch=self.white_patch,
            white_reflectance=self.white_reflectance,
            weights=self.fit_weights,
        )

    @property
    def fit_weights(self) -> np.ndarray:
        n = self.target.shape[0]
        return np.ones(n) if self.weights is None else np.asarray(self.weights, dtype=np.float64)


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class Folds:
    """The fold fraction (:func:`ocio_vp.correction.extrapolation.fold_fraction`) a method
    measured for its ``correction`` over ``domain``, so that the solve's diagnostics read it
    instead of measuring it again; :meth:`of` gives it only for those very objects."""

    correction: PostCorrection
    domain: FitDomain
    fraction: float

    def of(self, correction: PostCorrection, domain: FitDomain) -> float | None:
        """The fraction if it was measured for ``correction`` over ``domain``, else None."""
        return self.fraction if correction is self.correction and domain is self.domain else None


@dataclass(frozen=True)
class QFit:
    """A solved post-correction and what the method says about it.

    ``correction`` is the post-correction itself (:mod:`ocio_vp.model.correction`); ``Q`` its
    3x3 (the matrix, or a non-linear model's fallback). ``M`` is set only by methods that also
    change the lighting. ``model`` names what was fitted (``auto`` names the model it chose),
    ``reason`` why, ``cross_validated_error`` (3,) the method's own leave-one-patch-out error
    (white-relative), ``target_rank`` the chart's rank as a rank-aware method saw it.
    ``details`` holds the method's own figures for people (written to solution.json's
    ``diagnostics.method_notes``); no module reads a model from them.
    """

    correction: PostCorrection
    model: str
    description: str = ""
    M: np.ndarray | None = None
    reason: str | None = None
    cross_validated_error: np.ndarray | None = None
    target_rank: int | None = None
    warnings: tuple[str, ...] = ()
    details: Mapping[str, Any] = field(default_factory=dict)
    #: (n, 3) the leave-one-patch-out predictions behind ``cross_validated_error``, where the
    #: method made them (``auto`` compares candidates with them).
    loo_predictions: np.ndarray | None = None
    #: With skin first: the default's fit that this one was judged against (the solve reports
    #: the two side by side).
    default: QFit | None = None
    #: The fold fraction the method measured for ``correction`` (None: not measured).
    folds: Folds | None = None

    @property
    def Q(self) -> np.ndarray:
        """(3, 3) the correction's matrix (its fallback for a non-linear model)."""
        return self.correction.matrix

    @property
    def notes(self) -> dict[str, object]:
        """Everything the method reported (its own figures: numbers, arrays, text), which
        solution.json writes as ``diagnostics.method_notes`` (converted to JSON there)."""
        notes: dict[str, object] = {"model": self.model, "description": self.description}
        if self.reason is not None:
            notes["reason"] = self.reason
        if self.target_rank is not None:
            notes["target_rank"] = self.target_rank
        if self.cross_validated_error is not None:
            notes["cross_validated_error"] = self.cross_validated_error
        if self.warnings:
            notes["warnings"] = list(self.warnings)
        return notes | dict(self.details)


# Eq. 5's kernel lives with the problem: the linear family, perceptual (its start) and joint all
# use it, and linear judges models with perceptual's ΔE, so neither may import the other for it.
def fit_least_squares(X: np.ndarray, P: np.ndarray, w: np.ndarray, white: int = 0) -> np.ndarray:
    """argmin_Q sum_j w_j ||Q x_j - p_j||^2 (eq. 5), via an SVD least-squares solve."""
    sw = np.sqrt(w)[:, None]
    QT, *_ = np.linalg.lstsq(X * sw, P * sw, rcond=None)  # rows: x_j^T Q^T = p_j^T
    return QT.T
