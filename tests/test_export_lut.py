"""Exports of a config that carries the panel-linearity LUT sidecar (``luts/*.clf``).

The sidecar must travel with every exported config (``ociocheck`` parses every LUT and fails
on a missing file), be inside the ``.ocioz``, and the wall CLFs must carry the LUT1D: checked
with ``ociochecklut`` against the original config's processor at the solve's location."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict
from test_export_unreal import run_tool

from ocio_vp.exports import export_solutions
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM, REFERENCE
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements

CHANNELS = ("red", "green", "blue")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    data = make_measurements_dict(environments=1)
    SL = np.array([data["primaries"][c] for c in CHANNELS]).T
    drive = np.linspace(0.0, 1.0, 17)
    curves = (drive**1.1, drive, drive)  # a red channel that is not linear (paper, Sec. 3.2)
    data["ramps"] = {
        c: {"drive": drive.tolist(), "camera": (np.outer(curves[k], SL[:, k]) + 0.002).tolist()}
        for k, c in enumerate(CHANNELS)
    }
    root = tmp_path_factory.mktemp("lut")
    write_solutions(solve_measurements(measurements_from_dict(data, source="t")), root / "s")
    folder = root / "s" / "env_0"
    if not (folder / "luts").is_dir():
        pytest.skip("this build writes no linearity LUT sidecar")
    export_solutions([folder], targets=["unreal", "nuke", "resolve"], cube_size=17)
    return folder


def test_sidecar_travels_with_every_config(exported, tmp_path):
    luts = sorted(p.name for p in (exported / "luts").iterdir())
    assert luts
    for target in ("unreal", "nuke"):
        config = exported / "exports" / target / "config"
        assert sorted(p.name for p in (config / "luts").iterdir()) == luts
        result = run_tool("ociocheck", "--iconfig", str(config / "config.ocio"))
        assert result.returncode == 0, result.stdout + result.stderr
    with zipfile.ZipFile(exported / "exports" / "unreal" / "env_0.ocioz") as archive:
        archive.extractall(tmp_path)
    assert sorted(p.name for p in (tmp_path / "luts").iterdir()) == luts
    result = run_tool("ociocheck", "--iconfig", str(tmp_path / "config.ocio"))
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize(("stem", "space"), [("wall_out_of_frustum", OUT_OF_FRUSTUM),
                                             ("wall_in_frustum", IN_FRUSTUM)])  # fmt: skip
def test_wall_clf_carries_the_lut(exported, stem, space):
    clf = exported / "exports" / "resolve" / f"{stem}.clf"
    assert "LUT1D" in clf.read_text()
    config = OCIO.Config.CreateFromFile(str(exported / "config.ocio"))
    cpu = config.getProcessor(REFERENCE, space).getDefaultCPUProcessor()
    for rgb in ([0.1, 0.05, 0.02], [0.3, 0.2, 0.1], [0.05, 0.1, 0.2]):
        want = np.array(cpu.applyRGB([float(v) for v in rgb]))
        result = run_tool("ociochecklut", str(clf), *(repr(float(v)) for v in rgb))
        assert result.returncode == 0, result.stderr
        got = np.array([float(v) for v in result.stdout.split()[-3:]])
        np.testing.assert_allclose(got, want, rtol=2e-6, atol=2e-6)


def test_cube_error_is_reported(exported):
    report = json.loads((exported / "exports" / "resolve" / "cube_errors.json").read_text())
    for entry in report["cubes"].values():
        assert np.isfinite(entry["max_abs_error"]) and entry["samples"] > 1000
