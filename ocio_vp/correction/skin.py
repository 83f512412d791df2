"""Skin samples for every solve, from the measurements a stage already takes.

Three sources (docs/skin.md explains each): **virtual skin** (:func:`chart_skin_samples`),
measured skin reflectances as combinations of a ColorChecker 24's patch reflectances, whose
camera RGB is then the same combination of the lit and target charts; the chart's own **skin
patches**, named or found by colour (:func:`patch_skin_samples`); and skin computed **from
spectra** (:mod:`ocio_vp.correction.skin_spectra`). Each sample carries its lightness band
(ITA°, :mod:`ocio_vp.skin_data`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ocio_vp.calibration.equations import predict_lit_chart
from ocio_vp.deprecation import deprecated_names
from ocio_vp.metrics import camera_lab, sample_camera_to_xyz
from ocio_vp.skin_data import SkinSet, band_of, ita_degrees, training_skin
from ocio_vp.spectra import checker_reflectances

__all__ = [
    "SKIN_CHART",
    "SkinSamples",
    "chart_reflectances",
    "chart_skin_samples",
    "chart_skin_weights",
    "joined",
    "patch_skin_samples",
    "skin_patch_weights",
    "skin_rows",
    "with_rows",
]

#: The reference spectra of a 24-patch chart (a ColorChecker in reading order): measured charts
#: since 2005 on average (colour-science's data; the chart on set is never exactly either).
SKIN_CHART = "BabelColor Average"

#: Ridge strength of the chart combination, relative to the mean patch energy: small enough to
#: reproduce skin's spectrum, large enough that no coefficient amplifies the chart's noise
#: (chosen on the training skin, docs/skin.md).
COMBINATION_RIDGE = 1e-4


@dataclass(frozen=True)
class SkinSamples:
    """Skin samples for one environment, as the chart is measured.

    ``SRL`` (k, 3, 3): each sample lit by each LED channel from the calibration panel, as
    photographed (like the lit chart); ``target`` (k, 3): the samples in the location;
    ``band`` (k,) their ITA band names; ``weights`` (k, n) the chart combination each sample is
    (None for exact spectra); ``source`` says in words where they come from.
    """

    SRL: np.ndarray
    target: np.ndarray
    band: tuple[str, ...]
    source: str
    weights: np.ndarray | None = None

    @property
    def count(self) -> int:
        return int(self.target.shape[0])

    def lit(self, beta: float, drive: np.ndarray, extra_light: np.ndarray | None) -> np.ndarray:
        """(k, 3) the samples lit by the wall at ``drive`` (eq. 3), plus the chart's extra
        light (fixtures) combined alike where the samples are chart combinations."""
        lit = predict_lit_chart(self.SRL, beta, np.eye(3), drive)
        if extra_light is not None and self.weights is not None:
            lit = lit + self.weights @ extra_light
        return lit


@functools.lru_cache(maxsize=2)
def chart_reflectances(name: str = SKIN_CHART) -> np.ndarray:
    """(24, W) the reference reflectances of a ColorChecker 24 in reading order."""
    values = checker_reflectances(name)
    values.setflags(write=False)
    return values


def joined(first: SkinSamples, second: SkinSamples | None) -> SkinSamples:
    """Both sets of samples as one (``second`` None: ``first``); the chart combination is
    kept only where both have one."""
    if second is None:
        return first
    weights = None
    if first.weights is not None and second.weights is not None:
        weights = np.vstack([first.weights, second.weights])
    return SkinSamples(
        SRL=np.concatenate([first.SRL, second.SRL]),
        target=np.concatenate([first.target, second.target]),
        band=first.band + second.band,
        source=f"{first.source}; and {second.source}",
        weights=weights,
    )


def chart_skin_weights(
    chart: np.ndarray, skin: np.ndarray, active: np.ndarray, ridge: float = COMBINATION_RIDGE
) -> np.ndarray:
    """(k, n) each skin reflectance (k, W) as a ridge-regularised combination of the active
    chart patches' reflectances (n, W); excluded patches get 0.

    ``min_a ||a R - s||² + λ ||a||²`` with ``λ = ridge * trace(R Rᵀ) / m`` (m active patches):
    the Gram matrix plus λ is well conditioned by construction.
    """
    R = np.asarray(chart, dtype=np.float64)[active]
    gram = R @ R.T
    lam = ridge * np.trace(gram) / len(R)
    weights = np.zeros((len(skin), len(chart)))
    weights[:, active] = np.linalg.solve(gram + lam * np.eye(len(R)), R @ np.asarray(skin).T).T
    return weights


def chart_skin_samples(
    SRL: np.ndarray, target: np.ndarray, active: np.ndarray, training: SkinSet | None = None
) -> SkinSamples | None:
    """Virtual skin of a ColorChecker 24 (module docstring); None for another chart."""
    if SRL.shape[0] != 24:
        return None
    training = training or training_skin()
    weights = chart_skin_weights(chart_reflectances(), training.reflectances, active)
    return SkinSamples(
        SRL=np.einsum("kj,jcl->kcl", weights, SRL),
        target=weights @ target,
        band=training.bands,
        source=(
            f"virtual skin: {len(weights)} measured skin reflectances as combinations of the "
            f"chart's patches ({SKIN_CHART} spectra)"
        ),
        weights=weights,
    )


@dataclass(frozen=True)
class SkinRows:
    """Skin samples as extra rows of a weighted fit: lit ``x`` (k, 3), location ``p`` (k, 3)
    and row weights (k,) (``skin_weight`` times the chart's energy, shared so that each sample
    counts by its luminance to the power -2/3: CIE L* is about ``Y^(1/3)``, so the same ΔE in a
    dark face weighs what it does in a light one)."""

    x: np.ndarray
    p: np.ndarray
    weights: np.ndarray


def skin_rows(
    lit: np.ndarray,
    target: np.ndarray,
    chart_target: np.ndarray,
    chart_weights: np.ndarray,
    white_patch: int,
    skin_weight: float,
) -> SkinRows:
    """The skin samples (lit (k, 3), location (k, 3)) as rows to fit beside the chart's."""
    luminance = sample_camera_to_xyz()[1]
    Y = (target @ luminance) / float(chart_target[white_patch] @ luminance)
    scale = np.clip(Y, 1e-3, None) ** (-2.0 / 3.0)
    chart_energy = float(np.sum(chart_weights[:, None] * chart_target**2))
    skin_energy = float(np.sum((scale[:, None] * target) ** 2))
    lam = skin_weight * chart_energy / skin_energy if skin_energy > 0 else 0.0
    return SkinRows(np.asarray(lit, float), np.asarray(target, float), lam * scale**2)


def with_rows(
    X: np.ndarray, P: np.ndarray, w: np.ndarray, rows: SkinRows | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The chart's fit rows ``(X, P, w)`` with the skin rows after them (unchanged for None)."""
    if rows is None:
        return X, P, w
    return np.vstack([X, rows.x]), np.vstack([P, rows.p]), np.concatenate([w, rows.weights])


def skin_patch_weights(
    target: np.ndarray, white_patch: int, active: np.ndarray, named: tuple[int, ...] = ()
) -> tuple[np.ndarray, tuple[str, ...]]:
    """(weights (k, n), bands) selecting the chart's skin patches: ``named`` ones, or those whose
    location colour is a skin colour (hue between 20° and 90° in CIE L*a*b* through the sample
    camera, chroma 8-50, L* 20-90: the ColorChecker's two skin patches and the skin of every
    lightness band under a broadband light)."""
    lab = camera_lab(target, camera_to_xyz=sample_camera_to_xyz(), white=white_patch)
    if named:
        chosen = [j for j in named if active[j]]
    else:
        hue = np.degrees(np.arctan2(lab[:, 2], lab[:, 1]))
        chroma = np.hypot(lab[:, 1], lab[:, 2])
        found = (hue > 20) & (hue < 90) & (chroma > 8) & (chroma < 50)
        found &= (lab[:, 0] > 20) & (lab[:, 0] < 90) & active
        chosen = [int(j) for j in np.flatnonzero(found)]
    weights = np.zeros((len(chosen), len(target)))
    weights[np.arange(len(chosen)), chosen] = 1.0
    bands = tuple(band_of(float(v)) for v in ita_degrees(lab[chosen]))
    return weights, bands


def patch_skin_samples(
    SRL: np.ndarray,
    target: np.ndarray,
    white_patch: int,
    active: np.ndarray,
    named: tuple[int, ...] = (),
) -> SkinSamples | None:
    """The chart's own skin patches as skin samples (:func:`skin_patch_weights`); None when
    there are none."""
    weights, bands = skin_patch_weights(target, white_patch, active, named)
    if len(weights) == 0:
        return None
    chosen = [int(j) for j in np.argmax(weights, axis=1)]
    how = "named in the measurements file" if named else "found by their colour"
    return SkinSamples(
        SRL=np.asarray(SRL, dtype=np.float64)[chosen],
        target=np.asarray(target, dtype=np.float64)[chosen],
        band=bands,
        source=f"the chart's skin patches {', '.join(map(str, chosen))} ({how})",
        weights=weights,
    )


def _skin_delta_e(
    corrected: np.ndarray, target: np.ndarray, white: np.ndarray, camera_to_xyz: np.ndarray
) -> np.ndarray:
    """The old ``skin_delta_e``: ΔE2000 of corrected skin samples against the target."""
    from ocio_vp.metrics import camera_delta_E_2000

    return camera_delta_E_2000(target, corrected, camera_to_xyz=camera_to_xyz, white=white)


#: Names served for one more release (ocio_vp.deprecation).
__getattr__ = deprecated_names(
    __name__,
    {
        "skin_delta_e": (
            "ocio_vp.metrics.camera_delta_E_2000(target, corrected, camera_to_xyz=..., white=...)",
            lambda: _skin_delta_e,
        )
    },
)
