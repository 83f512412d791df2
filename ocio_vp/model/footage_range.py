"""The camera range footage really spans, as named sets of camera RGB, and how far a host's
rendering of a post-correction is from the exact model over it.

A post-correction is fitted on a chart, but every host that carries it (the OCIO config, the
Resolve CLF, DCTL and cube, ``ocio-vp apply``) sees whatever the camera records. The sets
(:data:`SETS`), camera RGB relative to the scene's white: ``reflectances``, surfaces lit by the
stage at :data:`EXPOSURES` times, with noise; ``near_black``, the same at :data:`NEAR_BLACK`
times and black, with noise (many channels negative); ``highlights``, the lit white and the
surfaces up to :data:`HDR` times; ``emitters``, self-luminous colours at :data:`EMITTER_LEVELS`
times the white's luminance (narrow-band LEDs, the wall's primaries and their pairwise mixes).

Noise is Gaussian per channel, ``sigma^2 = (READ_NOISE w)^2 + SHOT_NOISE^2 w |x|`` with ``w``
the white's largest channel. :func:`agreement` measures ΔE2000 between a host and the exact
model on every set (:func:`ocio_vp.metrics.delta_E_2000`). The simulator builds the sets from
spectra (:func:`ocio_vp.simulator.truth.stage_footage_range`), the config writer from the
calibration alone (:func:`calibration_footage_range`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:  # formats imports model: the JSON types for annotations only
    from ocio_vp.formats.jsontypes import JsonObject


__all__ = [
    "AGREEMENT_P99",
    "AGREEMENT_WORST",
    "EMITTER_LEVELS",
    "EXPOSURES",
    "HDR",
    "NEAR_BLACK",
    "READ_NOISE",
    "SETS",
    "SHOT_NOISE",
    "Agreement",
    "FootageRange",
    "agreement",
    "calibration_footage_range",
    "footage_range",
    "wall_emitters",
]

#: The sets, in the order tables list them.
SETS = ("reflectances", "near_black", "highlights", "emitters")
#: Exposure of the lit surfaces, relative to the chart's (log-uniform between the two).
EXPOSURES = (1.0 / 16.0, 4.0)
#: Exposure of the near-black surfaces (log-uniform between the two).
NEAR_BLACK = (2.0**-10, 2.0**-6)
#: Highlights: the lit white up to this many times, the surfaces from 4 times up to it.
HDR = 16.0
#: Self-luminous colours in frame (narrow-band emitters, the wall's own LEDs): their luminance
#: relative to the white's (a perfect white diffuser under the real light). Every check of
#: emitters uses these levels (simulator, extrapolation, footage range).
EMITTER_LEVELS = (0.25, 1.0, 4.0)
#: Sensor noise relative to the white's largest channel: read noise (sigma at black) and the
#: shot-noise coefficient (``sigma^2 += SHOT_NOISE^2 w |x|``).
READ_NOISE = 1e-3
SHOT_NOISE = 3e-3
#: Black pixels (noise only) in the near-black set.
BLACK_PIXELS = 200


@dataclass(frozen=True)
class FootageRange:
    """Named (n, 3) sets of camera RGB (:data:`SETS`), and what ΔE2000 needs: the camera ->
    XYZ matrix and the scene white (camera RGB)."""

    sets: Mapping[str, np.ndarray]
    camera_to_xyz: np.ndarray
    white: np.ndarray

    def delta_E(self, a: ArrayLike, b: ArrayLike) -> np.ndarray:
        """(n,) ΔE2000 between two renderings (camera RGB) of the same pixels."""
        from ocio_vp.metrics import delta_E_2000

        return delta_E_2000(a, b, camera_to_xyz=self.camera_to_xyz, white=self.white)

    def all(self) -> np.ndarray:
        """Every set, stacked."""
        return np.vstack([self.sets[name] for name in self.sets])


def _noisy(x: np.ndarray, top: float, rng: np.random.Generator) -> np.ndarray:
    sigma = np.sqrt((READ_NOISE * top) ** 2 + SHOT_NOISE**2 * top * np.abs(x))
    return x + sigma * rng.standard_normal(x.shape)


def _exposed(x: np.ndarray, low: float, high: float, rng: np.random.Generator) -> np.ndarray:
    return x * np.exp2(rng.uniform(np.log2(low), np.log2(high), (len(x), 1)))


def footage_range(
    *,
    lit: ArrayLike,
    lit_white: ArrayLike,
    white: ArrayLike,
    emitters: ArrayLike,
    camera_to_xyz: ArrayLike,
    seed: int = 0,
) -> FootageRange:
    """The sets of the module docstring from their ingredients (all camera RGB).

    ``lit`` (n, 3): surfaces lit by the stage at the chart's exposure; ``lit_white``: the white
    patch lit by the stage; ``white``: the scene's white (ΔE's reference); ``emitters`` (m, 3):
    self-luminous colours at the white's luminance. Deterministic for a ``seed``.
    """
    rng = np.random.default_rng(seed)
    lit = np.asarray(lit, dtype=np.float64).reshape(-1, 3)
    lit_white = np.asarray(lit_white, dtype=np.float64).reshape(3)
    emitters = np.asarray(emitters, dtype=np.float64).reshape(-1, 3)
    top = float(np.max(np.abs(lit_white)))
    black = np.zeros((BLACK_PIXELS, 3))
    sets = {
        "reflectances": _noisy(_exposed(lit, *EXPOSURES, rng), top, rng),
        "near_black": _noisy(np.vstack([_exposed(lit, *NEAR_BLACK, rng), black]), top, rng),
        "highlights": np.vstack(
            [
                lit_white * np.exp2(rng.uniform(0.0, np.log2(HDR), (BLACK_PIXELS, 1))),
                _exposed(lit, 4.0, HDR, rng),
            ]
        ),
        "emitters": np.vstack([emitters * level for level in EMITTER_LEVELS]),
    }
    for values in sets.values():
        values.setflags(write=False)
    return FootageRange(
        sets, np.asarray(camera_to_xyz, dtype=np.float64), np.asarray(white, dtype=np.float64)
    )


def wall_emitters(SL: ArrayLike, white: ArrayLike, camera_to_xyz: ArrayLike) -> np.ndarray:
    """The wall's primaries and their pairwise mixes (camera RGB, [SL]'s columns) at the
    luminance (Y through ``camera_to_xyz``) of ``white``; those of no positive luminance are
    left out."""
    primaries = np.ascontiguousarray(np.asarray(SL, dtype=np.float64).T)
    colours = np.vstack([primaries, primaries + np.roll(primaries, -1, axis=0)])  # r+g, g+b, b+r
    y = np.asarray(camera_to_xyz, dtype=np.float64)[1]
    luminance = colours @ y
    keep = luminance > 0
    return colours[keep] / luminance[keep, None] * float(np.asarray(white) @ y)


def calibration_footage_range(
    *,
    lit_chart: ArrayLike,
    white_patch: int,
    target_white: ArrayLike,
    SL: ArrayLike,
    camera_to_xyz: ArrayLike,
    seed: int = 0,
) -> FootageRange:
    """The sets from a calibration alone (no spectra): the lit chart's patches as the surfaces,
    its white patch as the lit white, the wall's primaries and mixes as the emitters
    (:func:`wall_emitters`), the target white as the scene's."""
    lit_chart = np.asarray(lit_chart, dtype=np.float64)
    return footage_range(
        lit=lit_chart,
        lit_white=lit_chart[white_patch],
        white=target_white,
        emitters=wall_emitters(SL, target_white, camera_to_xyz),
        camera_to_xyz=camera_to_xyz,
        seed=seed,
    )


#: The agreement with the exact model the hosts are held to (ΔE2000, p99 and worst): the
#: config's LUT chains when they are baked, and the exports' notes when they are read back.
AGREEMENT_P99 = 0.5
AGREEMENT_WORST = 2.0


@dataclass(frozen=True)
class Agreement:
    """ΔE2000 of a host against the exact model: p99 and worst per set and over all sets,
    and the input of the worst pixel."""

    p99: Mapping[str, float]
    worst: Mapping[str, float]
    worst_input: tuple[float, float, float]

    @property
    def overall(self) -> tuple[float, float]:
        """(p99, worst) over every set."""
        return self.p99["all"], self.worst["all"]

    def within(self, p99: float, worst: float) -> bool:
        return self.overall[0] <= p99 and self.overall[1] <= worst

    def to_dict(self) -> JsonObject:
        return {
            "p99": dict(self.p99),
            "worst": dict(self.worst),
            "worst_input": list(self.worst_input),
        }


def agreement(
    footage: FootageRange,
    exact: Callable[[np.ndarray], np.ndarray],
    host: Callable[[np.ndarray], np.ndarray],
) -> Agreement:
    """ΔE2000 between ``host`` and ``exact`` (each (n, 3) -> (n, 3)) on every set."""
    p99, worst = {}, {}
    errors, inputs = [], []
    for name, x in footage.sets.items():
        if len(x) == 0:
            continue
        de = footage.delta_E(host(x), exact(x))
        de = np.where(np.isfinite(de), de, np.inf)
        p99[name], worst[name] = float(np.percentile(de, 99)), float(de.max())
        errors.append(de)
        inputs.append(x)
    de, x = np.concatenate(errors), np.vstack(inputs)
    p99["all"], worst["all"] = float(np.percentile(de, 99)), float(de.max())
    at = x[int(np.argmax(de))]
    return Agreement(p99, worst, (float(at[0]), float(at[1]), float(at[2])))
