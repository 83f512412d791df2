"""Rebuild the measured skin and camera data files from their public sources (run by hand).

    python -m benchmarks.make_skin_data --nist M38597.csv --physlight PHYSLIGHT_REPO/data/camera

- ``--nist``: NIST's *Reference Data Set of Human Skin Reflectance* (the 250-2500 nm table,
  ``1832_Data_JResNIST_skinrefl v3.txt``; the copy used is ``iadpython/data/M38597.csv`` of
  scottprahl/iadpython). Each subject's ``Average`` column (the mean of its three
  measurements) is interpolated linearly onto the project's grid (380-780 nm, 5 nm; the
  source's 3 nm steps bracket every grid point) and rounded to the source's 4 decimals.
- ``--physlight``: Weta's physlight ``data/camera/*.json`` (already on the grid); values
  unchanged.

The skin split (:mod:`ocio_vp.skin_data`): subjects are banded by ITA (D65, CIE 1931 2°
observer) and, within each band in order of ITA, alternate training / held-out (the second,
fourth, ... go to held-out; a band with one subject gives it to held-out, so every band the
data has is benchmarked). Training goes to ``ocio_vp/data/skin_training.json`` (the solver may
use it), held-out to ``benchmarks/data/skin_held_out.json`` (the benchmark only).
The cameras: bodies the rawtoaces file already holds are left out (their values are the
same); the others, in order of name, alternate tuning / held-out.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
TRAINING = ROOT / "ocio_vp" / "data" / "skin_training.json"
HELD_OUT = ROOT / "benchmarks" / "data" / "skin_held_out.json"
CAMERAS = ROOT / "ocio_vp" / "data" / "camera_sensitivities_physlight.json"

NIST_SOURCE = (
    "NIST Reference Data Set of Human Skin Reflectance (Cooksey, Allen, Tsai, J. Res. NIST 122, "
    "026 (2017), doi:10.6028/jres.122.026; data doi:10.18434/M38597), inner forearm, 100 "
    "subjects; copy: scottprahl/iadpython@dc8c91c0ad5732f62660dad8f536d7fe215815f4 "
    "iadpython/data/M38597.csv"
)
PHYSLIGHT_SOURCE = (
    "https://github.com/wetadigital/physlight/blob/4403821777cfa538c3fce3a46b12e682a24e07ac/"
    "data/camera/"
)


def read_nist(path: Path) -> tuple[np.ndarray, list[str], np.ndarray]:
    """(wavelengths, subject names, (n, L) averages) of the NIST table."""
    with open(path, encoding="latin-1", newline="") as handle:
        rows = list(csv.reader(handle))
    header = next(i for i, row in enumerate(rows) if row and row[0].startswith("Wavelength"))
    labels = rows[header]
    subjects = rows[header - 1]
    columns = [i for i, label in enumerate(labels) if label == "Average"]
    names = [subjects[i - 3].strip() for i in columns]
    body = np.array(
        [
            [float(row[0])] + [float(row[i]) for i in columns]
            for row in rows[header + 1 :]
            if row and row[0]
        ]
    )
    return body[:, 0], names, body[:, 1:].T


def split_skin(nist: Path) -> None:
    """Write the training and held-out skin files from the NIST table (see the docstring)."""
    from ocio_vp.skin_data import band_of, ita_degrees, lab_d65
    from ocio_vp.spectra import wavelengths

    source_nm, names, averages = read_nist(nist)
    on_grid = np.round(np.stack([np.interp(wavelengths(), source_nm, a) for a in averages]), 4)
    ita = ita_degrees(lab_d65(on_grid))
    bands = [band_of(v) for v in ita]
    held_out = np.zeros(len(names), dtype=bool)
    for band in set(bands):
        members = sorted((i for i, b in enumerate(bands) if b == band), key=lambda i: ita[i])
        if len(members) == 1:
            held_out[members[0]] = True
        for position, i in enumerate(members):
            held_out[i] = held_out[i] or position % 2 == 1
    for path, keep, split in ((TRAINING, ~held_out, "training"), (HELD_OUT, held_out, "held-out")):
        samples = {
            f"NIST {names[i]}": {"band": bands[i], "reflectance": on_grid[i].tolist()}
            for i in np.flatnonzero(keep)
        }
        document = {
            "format": "ocio-vp/skin-reflectances",
            "version": 1,
            "split": split,
            "description": "Measured human skin reflectance factors (0-1) on the project grid; "
            "see ocio_vp/data/SKIN_LICENSE.md",
            "source": NIST_SOURCE,
            "wavelengths": _shape(),
            "samples": samples,
        }
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")


def _shape() -> dict[str, float]:
    from ocio_vp.spectra import SPECTRAL_SHAPE

    return dict(zip(("start", "end", "interval"), SPECTRAL_SHAPE, strict=True))


def gather_cameras(physlight: Path) -> None:
    """Write the physlight cameras the rawtoaces file lacks, split tuning / held-out."""
    from ocio_vp.spectra import wavelengths

    existing = json.loads((ROOT / "ocio_vp" / "data" / "camera_sensitivities.json").read_text())
    known = {name.split(" (")[0].lower() for name in existing["cameras"]}
    cameras = {}
    for file in sorted(physlight.glob("*_380_780_5.json")):
        record = json.loads(file.read_text())
        head = record["header"]
        name = f"{head['manufacturer']} {head['model'].replace('_', ' ')}"
        if name.lower() in known:  # the same values as the rawtoaces file's (checked)
            continue
        main_data = record["spectral_data"]["data"]["main"]
        cameras[f"{name} (physlight)"] = {
            "manufacturer": head["manufacturer"],
            "model": head["model"],
            "source": f"{PHYSLIGHT_SOURCE}{file.name}",
            "licence": head["license"],
            "document_creator": head["document_creator"],
            "document_creation_date": head["document_creation_date"],
            "units": record["spectral_data"]["units"],
            "split": None,
            "RGB": [main_data[f"{nm:g}"] for nm in wavelengths()],
        }
    for position, record in enumerate(cameras.values()):
        record["split"] = "held-out" if position % 2 == 1 else "tuning"
    document = {
        "format": "ocio-vp/camera-sensitivities",
        "version": 1,
        "description": "Measured camera spectral sensitivities from Weta's physlight "
        "(Apache-2.0), values unchanged, gathered into one file (see "
        "CAMERAS_LICENSE.md); 'split' says which the benchmark holds out",
        "wavelengths": _shape(),
        "channels": ["R", "G", "B"],
        "cameras": cameras,
    }
    CAMERAS.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nist", type=Path, required=True)
    parser.add_argument("--physlight", type=Path, required=True)
    args = parser.parse_args(argv)
    split_skin(args.nist)
    gather_cameras(args.physlight)


if __name__ == "__main__":
    main()
