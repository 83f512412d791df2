"""Rebuild ``ocio_vp/data/sample_camera_to_xyz.json`` and ``ocio_vp/data/rec709_to_xyz.json`` (run
by hand when the fit, the sample camera or colour-science changes)::

    python -m benchmarks.make_sample_matrix

The file holds :func:`ocio_vp.metrics.camera_to_xyz_matrix` of the sample camera
(``ocio_vp.spectra.DEFAULT_CAMERA``, under D65): code that writes files (the OCIO config's
agreement check) reads it instead of fitting, so it needs no colour-science.
``tests/test_metrics.py`` checks the file against the fit. The second file holds
colour-science's ITU-R BT.709 RGB-to-XYZ matrix, every bit of it, for the configs' view of
camera RGB as Rec.709 (:func:`ocio_vp.ocio.viewing.rec709_to_xyz`): the helper process that
writes configs then needs no colour-science either; ``tests/test_ocio_viewing.py`` checks it
against colour-science.
"""

from __future__ import annotations

import json
from pathlib import Path

from ocio_vp.metrics import SAMPLE_MATRIX_FILE, camera_to_xyz_matrix
from ocio_vp.ocio.viewing import REC709_MATRIX_FILE
from ocio_vp.spectra import DEFAULT_CAMERA, camera_sensitivities

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    matrix = camera_to_xyz_matrix(camera_sensitivities(DEFAULT_CAMERA), illuminant="D65")
    document = {
        "camera": DEFAULT_CAMERA,
        "illuminant": "D65",
        "written_by": "python -m benchmarks.make_sample_matrix",
        # 12 significant digits: the fit's own digits, not the last bits of its arithmetic
        "camera_to_xyz": [[float(f"{v:.12g}") for v in row] for row in matrix],
    }
    path = ROOT / "ocio_vp" / SAMPLE_MATRIX_FILE
    path.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {path}")
    _write_rec709()


def _write_rec709() -> None:
    import colour

    matrix = colour.RGB_COLOURSPACES["ITU-R BT.709"].matrix_RGB_to_XYZ
    document = {
        "colourspace": "ITU-R BT.709",
        "source": f"colour-science {colour.__version__}: matrix_RGB_to_XYZ",
        "written_by": "python -m benchmarks.make_sample_matrix",
        # every digit: the configs carry colour-science's matrix itself (JSON floats round-trip)
        "rgb_to_xyz": [[float(v) for v in row] for row in matrix],
    }
    path = ROOT / "ocio_vp" / REC709_MATRIX_FILE
    path.write_text(json.dumps(document, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
