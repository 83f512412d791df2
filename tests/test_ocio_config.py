"""The written OCIO config, checked by meaning: colours pushed through OCIO's own processors."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.ocio import config as oc
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements

COLOURS = np.random.default_rng(7).uniform(-0.2, 4.0, size=(64, 3))  # HDR and negative too


def _apply(processor: OCIO.Processor, rgb: np.ndarray) -> np.ndarray:
    cpu = processor.getDefaultCPUProcessor()
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu.applyRGB(out)
    return out.astype(np.float64)


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> tuple[Path, list]:
    data = make_measurements_dict(seed=11)
    data["stage"]["camera_colorspace"] = "ARRI Wide Gamut 4"
    solutions = solve_measurements(measurements_from_dict(data), method="least-squares")
    out = tmp_path_factory.mktemp("calib")
    return out, write_solutions(solutions, out)


def _close(actual: np.ndarray, matrix: np.ndarray, offset=None) -> None:
    """OCIO's CPU path is float32: allow 1e-6 of the terms' magnitude, |matrix| |c| + |offset|."""
    offset = np.zeros(3) if offset is None else offset
    expected = COLOURS @ matrix.T + offset
    scale = np.abs(COLOURS) @ np.abs(matrix).T + np.abs(offset)
    assert np.all(np.abs(actual - expected) <= 1e-6 * scale + 1e-9), np.max(
        np.abs(actual - expected) / scale
    )


def test_processors_match_numpy(written) -> None:
    out, solutions = written
    for s in solutions:
        config = OCIO.Config.CreateFromFile(str(out / s.environment / "config.ocio"))
        # float32 processing: compare with a tolerance relative to the values' size.
        outer = _apply(config.getProcessor(oc.REFERENCE, oc.OUT_OF_FRUSTUM), COLOURS)
        _close(outer, s.M)
        inner = _apply(config.getProcessor(oc.REFERENCE, oc.IN_FRUSTUM), COLOURS)
        _close(inner, s.N, s.black_level_offset)
        footage = _apply(config.getProcessor(oc.POST_CORRECTION_COLORSPACE, oc.REFERENCE), COLOURS)
        _close(footage, s.Q)
        named = config.getNamedTransform(oc.POST_CORRECTION)
        q = _apply(config.getProcessor(named.getTransform(OCIO.TRANSFORM_DIR_FORWARD)), COLOURS)
        _close(q, s.Q)
        view = _apply(
            config.getProcessor(
                oc.REFERENCE, oc.DISPLAY, oc.VIEW_INNER, OCIO.TRANSFORM_DIR_FORWARD
            ),
            COLOURS,
        )
        _close(view, s.N, s.black_level_offset)


def test_working_spaces_use_colour_science_matrices(written) -> None:
    out, solutions = written
    config = OCIO.Config.CreateFromFile(str(out / solutions[0].environment / "config.ocio"))
    to_camera = colour.matrix_RGB_to_RGB(
        colour.RGB_COLOURSPACES["ACEScg"],
        colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"],
        chromatic_adaptation_transform="CAT02",
    )
    _close(_apply(config.getProcessor("ACEScg", oc.REFERENCE), COLOURS), to_camera)
    assert config.getRoleColorSpace("aces_interchange") == "ACES2065-1"


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
def test_ociocheck_passes(written) -> None:
    out, solutions = written
    for s in solutions:
        result = subprocess.run(
            ["ociocheck", "--iconfig", str(out / s.environment / "config.ocio")],
            capture_output=True,
            text=True,
            check=False,
        )
        assert result.returncode == 0, result.stdout + result.stderr
        assert "Validation: passed" in result.stdout or "passed" in result.stdout.lower()


def test_profile_version_and_descriptions(written) -> None:
    out, solutions = written
    s = solutions[0]
    text = (out / s.environment / "config.ocio").read_text()
    assert text.startswith("ocio_profile_version: 2.1")
    config = OCIO.Config.CreateFromFile(str(out / s.environment / "config.ocio"))
    inner = config.getColorSpace(oc.IN_FRUSTUM).getDescription()
    assert s.environment in inner and "black-level offset" in inner
    assert s.measurements_sha256 is None or s.measurements_sha256[:16] in inner
    assert sorted(config.getViews(oc.DISPLAY)) == sorted([oc.VIEW_INNER, oc.VIEW_OUTER, "Raw"])


def test_xyz_interchange_matches_colour_science(written) -> None:
    # Independent path: colour.RGB_to_XYZ with CAT02 adaptation to D65.
    out, solutions = written
    config = OCIO.Config.CreateFromFile(str(out / solutions[0].environment / "config.ocio"))
    assert config.getRoleColorSpace("cie_xyz_d65_interchange") == "CIE-XYZ-D65"
    got = _apply(config.getProcessor(oc.REFERENCE, "CIE-XYZ-D65"), COLOURS)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    expected = colour.RGB_to_XYZ(
        COLOURS,
        colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"],
        d65,
        chromatic_adaptation_transform="CAT02",
    )
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize(
    ("wall", "encoding"),
    [(None, "scene-linear"), ("gamma2.4", "sdr-video"), ("pq", "hdr-video")],
)
def test_wall_colorspace_encoding_follows_the_wall_signal(written, wall, encoding) -> None:
    import dataclasses

    _, solutions = written
    linearity = None if wall is None else {"wall_encoding": {"name": wall}}
    config = oc.build_config(dataclasses.replace(solutions[0], linearity=linearity))
    for name in (oc.OUT_OF_FRUSTUM, oc.IN_FRUSTUM):
        assert config.getColorSpace(name).getEncoding() == encoding
