"""Measured human skin reflectances, their lightness bands (ITA°), and the cameras held out.

A leaf module (numpy, :mod:`ocio_vp.spectra`). ``ocio_vp/data/skin_training.json`` is the
TRAINING half of NIST's *Reference Data Set of Human Skin Reflectance*, which fits, rules and
constants may use; the HELD-OUT half, ``benchmarks/data/skin_held_out.json``, is outside the
package on purpose (only ``benchmarks/skin_eval.py`` reads it). Weta's physlight cameras are
marked ``tuning`` or ``held-out`` in ``ocio_vp/data/camera_sensitivities_physlight.json``. The
split is fixed in the files (``benchmarks/make_skin_data.py``: within each ITA band, in order of
ITA, subjects alternate); licences and sources: ``ocio_vp/data/SKIN_LICENSE.md``. ITA (Chardon,
Cretois & Hourseau 1991): ``atan((L* - 50) / b*)`` in degrees, CIELAB under D65, CIE 1931 2°.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from importlib import resources

import numpy as np

from ocio_vp.spectra import PHYSLIGHT_CAMERAS, on_grid, packaged_json

__all__ = [
    "ITA_BANDS",
    "SkinSet",
    "band_of",
    "ita_degrees",
    "lab_d65",
    "load_skin_file",
    "physlight_camera_names",
    "physlight_cameras",
    "training_skin",
]

#: (name, lower bound in degrees, exclusive) from light to dark; the last band has no floor
#: (Del Bino & Bernerd 2013's six categories).
ITA_BANDS: tuple[tuple[str, float], ...] = (
    ("very light", 55.0),
    ("light", 41.0),
    ("intermediate", 28.0),
    ("tan", 10.0),
    ("brown", -30.0),
    ("dark", -np.inf),
)

TRAINING_FILE = "data/skin_training.json"


@dataclass(frozen=True)
class SkinSet:
    """Skin reflectances on the grid: ``names`` (n,), ``reflectances`` (n, W), ``bands`` (n,)
    as recorded by the split, ``split`` ('training' or 'held-out')."""

    split: str
    names: tuple[str, ...]
    reflectances: np.ndarray
    bands: tuple[str, ...]

    def ita(self) -> np.ndarray:
        """(n,) ITA° of each sample, computed from its spectrum."""
        return ita_degrees(lab_d65(self.reflectances))


def lab_d65(reflectances) -> np.ndarray:
    """(..., 3) CIELAB of reflectances (..., W) on the grid under D65, CIE 1931 2° observer."""
    import colour

    from ocio_vp.spectra import align, cie_cmfs_sds

    d65 = align(colour.SDS_ILLUMINANTS["D65"])
    weights = cie_cmfs_sds().values * d65[:, None]
    XYZ = np.asarray(reflectances, dtype=np.float64) @ weights / weights[:, 1].sum()
    white = np.ones(weights.shape[0]) @ weights / weights[:, 1].sum()
    return colour.XYZ_to_Lab(XYZ, colour.XYZ_to_xy(white))


def ita_degrees(lab) -> np.ndarray:
    """(...,) Individual Typology Angle in degrees of CIELAB (..., 3): atan((L*-50)/b*)."""
    lab = np.asarray(lab, dtype=np.float64)
    return np.degrees(np.arctan2(lab[..., 0] - 50.0, lab[..., 2]))


def band_of(ita: float) -> str:
    """The name of the ITA band an angle falls in (a bound belongs to the darker band)."""
    for name, floor in ITA_BANDS:
        if ita > floor:
            return name
    return ITA_BANDS[-1][0]


def load_skin_file(text: str) -> SkinSet:
    """A :class:`SkinSet` from a skin JSON document (``ocio-vp/skin-reflectances``)."""
    document = on_grid(json.loads(text), "skin data")
    samples = document["samples"]
    reflectances = np.array([s["reflectance"] for s in samples.values()], dtype=np.float64)
    reflectances.setflags(write=False)
    return SkinSet(
        split=document["split"],
        names=tuple(samples),
        reflectances=reflectances,
        bands=tuple(s["band"] for s in samples.values()),
    )


@functools.lru_cache(maxsize=1)
def training_skin() -> SkinSet:
    """The TRAINING skin (fits, rules and constants may use it; the benchmark judges on the
    held-out half).

    >>> skin = training_skin()
    >>> skin.split, skin.reflectances.shape[1]
    ('training', 81)
    """
    text = resources.files("ocio_vp").joinpath(TRAINING_FILE).read_text(encoding="utf-8")
    return load_skin_file(text)


@functools.lru_cache(maxsize=1)
def _physlight() -> dict:
    return on_grid(packaged_json(PHYSLIGHT_CAMERAS), PHYSLIGHT_CAMERAS)["cameras"]


def physlight_camera_names(split: str) -> tuple[str, ...]:
    """Names of the physlight cameras of one split: 'tuning' or 'held-out'."""
    return tuple(name for name, record in _physlight().items() if record["split"] == split)


def physlight_cameras(split: str) -> dict[str, np.ndarray]:
    """(W, 3) sensitivities of the physlight cameras of one split, by name.

    >>> cameras = physlight_cameras("held-out")
    >>> next(iter(cameras.values())).shape
    (81, 3)
    """
    return {
        name: np.asarray(_physlight()[name]["RGB"], dtype=np.float64)
        for name in physlight_camera_names(split)
    }
