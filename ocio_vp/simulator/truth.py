"""Ground truth on colours the chart does not contain: held-out reflectances, noisy measurements.

A calibration is fitted on 24 chart patches and applied to actors, costumes and sets; this module
judges it the way it is used (:func:`held_out_errors`, :func:`noisy_measurements`).
:func:`held_out_reflectances` are sets that are *not* the chart, all from colour-science's offline
data: the 190 RAW to ACES v1 training reflectances, the 99 CIE 2017 colour evaluation samples (the
TM-30 set), and a ``skin`` set (the four skin tones of colour's ``PMC`` chart and CIE 1995 test
colour sample 13, "human complexion"). A sample within :data:`CHART_DUPLICATE_TOLERANCE` of a
chart patch is dropped: it is on the chart.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ocio_vp.formats.measurements import Measurements
from ocio_vp.formats.solution import Solution
from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
from ocio_vp.model.footage_range import FootageRange, footage_range
from ocio_vp.simulator.data import DEFAULT_CHART, chart_reflectances
from ocio_vp.simulator.stage import SpectralStage, camera_rgb, environment_spectrum
from ocio_vp.spectra import align, spectral_shape

__all__ = [
    "CHART_DUPLICATE_TOLERANCE",
    "HeldOutErrors",
    "camera_matrix",
    "held_out_colours",
    "held_out_errors",
    "held_out_reflectances",
    "narrow_band_emitters",
    "noisy_measurements",
    "solution_held_out_errors",
    "stage_footage_range",
]

#: A held-out sample whose reflectance is within this (max over wavelengths) of a chart patch's
#: counts as a chart patch and is dropped (the RAW to ACES set contains ColorChecker-like patches).
CHART_DUPLICATE_TOLERANCE = 0.02

_SKIN_PMC = ("Caucasian", "Oriental", "South Asian", "African")


@functools.lru_cache(maxsize=4)
def held_out_reflectances(chart: str = DEFAULT_CHART) -> dict[str, np.ndarray]:
    """Reflectance sets not on ``chart``: ``{"rawtoaces": (k, W), "cie2017": ..., "skin": ...}``.

    Read-only arrays on the simulator's grid; see the module docstring for the sources.
    """
    import colour
    from colour.quality.cfi2017 import load_TCS_CIE2017

    shape = spectral_shape()
    training = colour.characterisation.read_training_data_rawtoaces_v1().copy().align(shape)
    ces = load_TCS_CIE2017(shape)
    pmc = colour.SDS_COLOURCHECKERS["PMC"]
    skin = [align(pmc[name]) for name in _SKIN_PMC]
    skin.append(align(colour.quality.SDS_TCS["CIE 1995"]["TCS13"]))
    sets = {
        "rawtoaces": np.asarray(training.values, dtype=np.float64).T,
        "cie2017": np.asarray(ces.values, dtype=np.float64).T,
        "skin": np.stack(skin),
    }
    patches = chart_reflectances(chart)
    out = {}
    for name, values in sets.items():
        distance = np.abs(values[:, None, :] - patches[None]).max(axis=2).min(axis=1)
        kept = np.clip(values[distance > CHART_DUPLICATE_TOLERANCE], 0.0, None)
        kept.setflags(write=False)
        out[name] = kept
    return out


def noisy_measurements(
    measurements: Measurements, noise: float, rng: np.random.Generator
) -> Measurements:
    """``measurements`` with every photographed value times ``1 + noise * gauss`` (independent).

    Primaries [SL], the lit chart [SRL]_j, every target chart, w_avg, black level and every
    fixture channel's lit chart; on a stage of several panel types, every type's primaries and
    lit chart and each environment's per-type w_avg and black level.
    """

    def jitter(a):
        if a is None:
            return None
        a = np.asarray(a, dtype=np.float64)
        return a * (1.0 + noise * rng.standard_normal(a.shape))

    environments = tuple(
        dataclasses.replace(
            e,
            target_chart=jitter(e.target_chart),
            w_avg=jitter(e.w_avg),
            black_level=jitter(e.black_level),
        )
        for e in measurements.environments
    )
    fixtures = tuple(
        dataclasses.replace(f, lit_chart=jitter(f.lit_chart)) for f in measurements.fixtures
    )
    noisy = dataclasses.replace(
        measurements,
        SL=jitter(measurements.SL),
        SRL=jitter(measurements.SRL),
        environments=environments,
        fixtures=fixtures,
    )
    return _noisy_panels(noisy, jitter) if measurements.panels else noisy


def _noisy_panels(measurements: Measurements, jitter) -> Measurements:
    """Every panel type's primaries and lit chart, and each environment's per-type w_avg and
    black level, jittered too (after the rest, so files without panels draw the same noise);
    the top-level arrays stay the first in-frustum type's."""
    panels = tuple(
        dataclasses.replace(p, SL=jitter(p.SL), SRL=jitter(p.SRL)) for p in measurements.panels
    )

    def each(values):
        return None if values is None else {k: jitter(v) for k, v in values.items()}

    environments = tuple(
        dataclasses.replace(
            e, panel_w_avg=each(e.panel_w_avg), panel_black_level=each(e.panel_black_level)
        )
        for e in measurements.environments
    )
    first = next(p for p in panels if p.in_frustum)
    return dataclasses.replace(
        measurements, SL=first.SL, SRL=first.SRL, panels=panels, environments=environments
    )


@dataclass(frozen=True)
class HeldOutErrors:
    """Per-sample ΔE2000 and ΔE ITP of a solve on one reflectance set (both (k,))."""

    delta_E_2000: np.ndarray
    delta_E_ITP: np.ndarray


def camera_matrix(stage: SpectralStage) -> np.ndarray:
    """(3, 3) the stage camera's RGB -> XYZ matrix (:func:`ocio_vp.metrics.camera_to_xyz_matrix`),
    the one every ground-truth ΔE here goes through (cached per camera)."""
    return _camera_matrix_cached(stage.camera.tobytes(), stage.camera.shape)


@functools.lru_cache(maxsize=8)
def _camera_matrix_cached(camera: bytes, shape: tuple[int, ...]) -> np.ndarray:
    return camera_to_xyz_matrix(np.frombuffer(camera, dtype=np.float64).reshape(shape))


def held_out_colours(
    stage: SpectralStage,
    environment,
    *,
    M: np.ndarray,
    w_avg: np.ndarray,
    reflectances: np.ndarray,
    extra_emission: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(lit, target), each (k + 1, 3) camera RGB: ``reflectances`` (k, W) and a perfect white
    diffuser (the last row) lit by what the wall emits (``clip(M w_avg, 0)`` through the stage's
    true LEDs, plus ``extra_emission``) and under ``environment``'s real light. The colours
    :func:`held_out_errors` judges; to judge many corrections of one solve, compute them once."""
    spectrum = environment_spectrum(stage, environment)
    white = camera_rgb(stage, spectrum)
    target = np.vstack([camera_rgb(stage, reflectances * spectrum), white])
    drive = np.clip(np.asarray(M, dtype=np.float64) @ np.asarray(w_avg, dtype=np.float64), 0, None)
    emitted = stage.leds @ drive
    if extra_emission is not None:
        emitted = emitted + np.asarray(extra_emission, dtype=np.float64)
    lit = np.vstack([camera_rgb(stage, reflectances * emitted), camera_rgb(stage, emitted)])
    return lit, target


def held_out_errors(
    stage: SpectralStage,
    environment,
    *,
    M: np.ndarray,
    w_avg: np.ndarray,
    Q: np.ndarray,
    reflectances: np.ndarray,
    extra_emission: np.ndarray | None = None,
    correct: Callable[[np.ndarray], np.ndarray] | None = None,
) -> HeldOutErrors:
    """How a solve renders ``reflectances`` (k, W) on the stage, against the real light.

    The wall emits ``clip(M w_avg, 0)`` through the stage's true LEDs; the camera sees the
    samples lit by it, Q corrects them; the reference is the samples under ``environment``
    (a name or spectrum, as :func:`~ocio_vp.simulator.stage.environment_spectrum`). ΔE uses the
    stage camera's own RGB -> XYZ matrix and a perfect white diffuser under the real light as
    the reference white. ``extra_emission`` (W,) is light added by practical fixtures (their
    spectra times their drives, :mod:`ocio_vp.simulator.fixtures`). ``correct`` replaces
    ``Q`` by a non-linear post-correction (a :data:`~ocio_vp.model.PostCorrection`'s
    ``apply``). :func:`held_out_colours` gives the colours compared.
    """
    lit, target = held_out_colours(
        stage,
        environment,
        M=M,
        w_avg=w_avg,
        reflectances=reflectances,
        extra_emission=extra_emission,
    )
    corrected = lit @ np.asarray(Q, dtype=np.float64).T if correct is None else correct(lit)
    errors = chart_errors(
        corrected, target, camera_to_xyz=camera_matrix(stage), white_patch=len(target) - 1
    )
    return HeldOutErrors(errors.delta_E_2000[:-1], errors.delta_E_ITP[:-1])


def solution_held_out_errors(
    stage: SpectralStage, environment, solution: Solution, reflectances: np.ndarray
) -> HeldOutErrors:
    """:func:`held_out_errors` of a solve: its M and w_avg light the samples, its
    post-correction corrects them."""
    return held_out_errors(
        stage,
        environment,
        M=solution.M,
        w_avg=solution.w_avg,
        Q=solution.Q,
        reflectances=reflectances,
        correct=solution.correction.apply,
    )


def narrow_band_emitters(stage: SpectralStage, environment) -> np.ndarray:
    """(k, 3) camera RGB of the narrow-band emitters of :mod:`ocio_vp.simulator.extremes`
    (:func:`~ocio_vp.simulator.extremes.emitters_in_scene`) at the luminance (CIE Y) of a
    perfect white diffuser under ``environment``, and of the wall's LEDs (each, and each pair)
    at the same luminance."""
    from ocio_vp.simulator.extremes import emitters_in_scene, luminance

    leds = stage.leds.T
    leds = np.vstack([leds, leds[[0, 1]].sum(0), leds[[1, 2]].sum(0), leds[[0, 2]].sum(0)])
    white = float(luminance(environment_spectrum(stage, environment)))
    leds = leds * (white / luminance(leds))[:, None]
    return camera_rgb(
        stage, np.vstack([emitters_in_scene(stage, environment, levels=(1.0,)), leds])
    )


def stage_footage_range(stage: SpectralStage, environment, solution, seed: int = 0) -> FootageRange:
    """The camera range of :mod:`ocio_vp.model.footage_range` on this stage: the held-out
    reflectances and the chart lit by what the wall emits for ``solution`` (``clip(M w_avg)``
    through the stage's LEDs), the white diffuser under the real light as the scene white,
    :func:`narrow_band_emitters`, and the stage camera's own RGB -> XYZ matrix."""
    sets = held_out_reflectances(stage.chart_name)
    reflectances = np.vstack([sets["rawtoaces"], sets["cie2017"], sets["skin"], stage.reflectances])
    lit, target = held_out_colours(
        stage, environment, M=solution.M, w_avg=solution.w_avg, reflectances=reflectances
    )
    return footage_range(
        lit=lit[:-1],
        lit_white=lit[-1],
        white=target[-1],
        emitters=narrow_band_emitters(stage, environment),
        camera_to_xyz=camera_matrix(stage),
        seed=seed,
    )
