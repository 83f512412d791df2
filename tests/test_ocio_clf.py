"""Sidecar LUT files: names unique to their content (OCIO's process-wide file cache), and CLF
written as Academy CLF v3 whatever OCIO version writes it (read by colour-science's reader)."""

from __future__ import annotations

import json

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import CHANNELS, make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.clf import CLF_V3_NAMESPACE, clf_v3
from ocio_vp.ocio.config import OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.wall.encoding import WallEncoding, apply_lut, lut_table


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """One stage with a non-linear red ramp, solved for a gamma 2.4 wall and a linear one."""
    document = make_measurements_dict(environments=1)
    SL = np.array([document["primaries"][c] for c in CHANNELS]).T
    drive = np.linspace(0.0, 1.0, 17)
    curves = (drive**1.1, drive, drive)
    document["ramps"] = {
        c: {"drive": drive.tolist(), "camera": (np.outer(curves[k], SL[:, k]) + 0.002).tolist()}
        for k, c in enumerate(CHANNELS)
    }
    root = tmp_path_factory.mktemp("sidecars")
    (root / "m.json").write_text(json.dumps(document))
    out = {}
    for encoding in ("gamma2.4", "linear"):
        assert main(["solve", str(root / "m.json"), "--out", str(root / encoding),
                     "--wall-encoding", encoding]) == 0  # fmt: skip
        out[encoding] = root / encoding / "env_0"
    return out


def expected_outer(folder, rgb: np.ndarray, encoding: str) -> np.ndarray:
    """numpy model of the outer wall: M, the encoding (or the linear wall's log shaper), the
    LUT clamped to its [0, 1] domain: the wall signal."""
    solution = load_solution(folder)
    return apply_lut(lut_table(solution.linearity, encoding), rgb @ solution.M.T)


def test_two_calibrations_of_one_stage_in_one_process(solved):
    """Loading the gamma 2.4 config first must not make the linear one use its LUT file."""
    names = {k: sorted(p.name for p in (f / "luts").iterdir()) for k, f in solved.items()}
    assert names["gamma2.4"] != names["linear"]
    rgb = np.array([[4.0, 4.0, 4.0], [0.3, 0.2, 0.1]])
    for encoding in ("gamma2.4", "linear"):  # the order that used to collide
        config = OCIO.Config.CreateFromFile(str(solved[encoding] / "config.ocio"))
        cpu = config.getProcessor(REFERENCE, OUT_OF_FRUSTUM).getDefaultCPUProcessor()
        got = np.array([cpu.applyRGB([float(v) for v in row]) for row in rgb])
        np.testing.assert_allclose(got, expected_outer(solved[encoding], rgb, encoding),
                                   rtol=2e-5, atol=2e-5)  # fmt: skip


def test_sidecar_name_is_its_content_hash(solved):
    import hashlib

    for folder in solved.values():
        (lut,) = (folder / "luts").glob("*.clf")
        digest = hashlib.sha256(lut.read_bytes()).hexdigest()[:12]
        assert lut.name.endswith(f"_{digest}.clf")


def test_sidecar_is_clf_v3_read_by_colour(solved):
    colour_clf_io = pytest.importorskip("colour_clf_io", reason="colour-clf-io not installed")
    for folder in solved.values():
        (lut,) = (folder / "luts").glob("*.clf")
        text = lut.read_text()
        assert f'xmlns="{CLF_V3_NAMESPACE}"' in text and 'compCLFversion="3.0"' in text
        process_list = colour_clf_io.read_clf(lut.read_bytes())
        solution = load_solution(folder)
        encoding = WallEncoding.of(solution.linearity).name
        table = lut_table(solution.linearity, encoding).table
        *shaper, lut = process_list.process_nodes
        assert type(lut).__name__ == "LUT1D" and lut.array.dim == table.shape
        values = np.reshape(lut.array.values, table.shape)
        np.testing.assert_allclose(values, table, rtol=1e-7, atol=1e-9)  # float32 text
        # a linear wall's LUT is fed by a log2 shaper; the others by their own signal
        assert [type(node).__name__ for node in shaper] == (["Log"] if encoding == "linear" else [])


@pytest.mark.parametrize(
    "header",
    [
        '<ProcessList compCLFversion="3" id="x">',
        '<ProcessList compCLFversion="3" xmlns="http://www.smpte-ra.org/ns/2136-1/2024" id="x">',
        '<ProcessList xmlns="urn:AMPAS:CLF:v3.0" compCLFversion="3.0" id="x">',
    ],
)
def test_clf_v3_header(header):
    text = f'<?xml version="1.0"?>\n{header}\n<Matrix/></ProcessList>'
    assert clf_v3(text) == (
        '<?xml version="1.0"?>\n<ProcessList xmlns="urn:AMPAS:CLF:v3.0" compCLFversion="3.0"'
        ' id="x">\n<Matrix/></ProcessList>'
    )


def test_clf_v3_refuses_other_text():
    with pytest.raises(ValueError, match="ProcessList"):
        clf_v3("<LUT/>")
