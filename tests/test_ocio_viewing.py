"""The pipeline side of a per-environment config: log roles, camera log footage, monitors."""

from __future__ import annotations

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.ocio import config as oc
from ocio_vp.ocio import viewing
from ocio_vp.pipeline import solve_measurements


def _apply(processor, rgb) -> np.ndarray:
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    processor.getDefaultCPUProcessor().applyRGB(out)
    return out.astype(np.float64)


def _config(camera: str | None):
    data = make_measurements_dict(seed=5, environments=1)
    if camera:
        data["stage"]["camera_colorspace"] = camera
    (solution,) = solve_measurements(measurements_from_dict(data), method="least-squares")
    return solution, oc.build_config(solution)


@pytest.fixture(scope="module")
def arri():
    return _config("ARRI Wide Gamut 4")


def test_log_roles_on_acescct(arri):
    _, config = arri
    for role in ("compositing_log", "color_timing"):
        space = config.getColorSpace(config.getRoleColorSpace(role))
        assert space.getName() == viewing.ACESCCT and space.getEncoding() == "log"
    # ACEScct -> ACES2065-1 through the camera gamut equals colour-science's ACEScct decoding
    cct = np.random.default_rng(0).uniform(0.1, 0.9, (50, 3))
    got = _apply(config.getProcessor(viewing.ACESCCT, "ACES2065-1"), cct)
    ap1_to_ap0 = colour.matrix_RGB_to_RGB(
        colour.RGB_COLOURSPACES["ACEScg"], colour.RGB_COLOURSPACES["ACES2065-1"]
    )
    want = colour.log_decoding(cct, function="ACEScct") @ ap1_to_ap0.T
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-6)
    for role in ("aces_interchange", "cie_xyz_d65_interchange"):
        assert config.hasRole(role)


def test_without_a_camera_gamut_no_log_roles():
    _, config = _config(None)
    assert not config.hasRole("compositing_log") and not config.hasRole("color_timing")
    view = viewing.UNTONEMAPPED_VIEW
    assert view in config.getViews("sRGB - Display")
    assert "not stated" in config.getViewTransform(view).getDescription()


def test_stage_footage_in_log_decodes_then_applies_q(arri):
    solution, config = arri
    native, footage = viewing.camera_log_names(viewing.camera_log_for("ARRI Wide Gamut 4"))
    log = np.random.default_rng(1).uniform(0.05, 0.9, (200, 3))
    decoded = colour.log_decoding(log, function="ARRI LogC4")
    got = _apply(config.getProcessor(footage, oc.REFERENCE), log)
    np.testing.assert_allclose(got, decoded @ solution.Q.T, rtol=1e-4, atol=1e-5)
    # log in, log out: the DIT cart's conversion
    got = _apply(config.getProcessor(footage, native), log)
    with np.errstate(invalid="ignore"):  # colour evaluates both branches of np.where
        want = colour.log_encoding(decoded @ solution.Q.T, function="ARRI LogC4")
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-4)  # float32 far below black


def _show(config, display, view, rgb):
    return _apply(config.getProcessor(oc.REFERENCE, display, view, OCIO.TRANSFORM_DIR_FORWARD), rgb)


def test_monitors_show_content_and_footage_after_q(arri):
    solution, config = arri
    displays = (
        list(config.getActiveDisplays().split(", "))
        if isinstance(config.getActiveDisplays(), str)
        else list(config.getActiveDisplays())
    )
    assert displays[0] == "sRGB - Display" and oc.DISPLAY in displays
    rgb = np.random.default_rng(2).uniform(0.0, 2.0, (100, 3))
    for monitor in viewing.MONITORS:
        views = list(config.getViews(monitor.display))
        assert views[:2] == [monitor.view, monitor.view + viewing.FOOTAGE_VIEW_SUFFIX]

        after_q = _show(config, monitor.display, monitor.view + viewing.FOOTAGE_VIEW_SUFFIX, rgb)
        want = _show(config, monitor.display, monitor.view, rgb @ solution.Q.T)
        np.testing.assert_allclose(after_q, want, atol=2e-5)
    # the content view is the ACES output of the built-in ACES config after camera -> ACES
    aces = OCIO.Config.CreateFromFile(viewing.ACES_CG_CONFIG)
    to_aces = _apply(config.getProcessor(oc.REFERENCE, "ACES2065-1"), rgb)
    want = _apply(
        aces.getProcessor(
            "ACES2065-1", "sRGB - Display", "ACES 1.0 - SDR Video", OCIO.TRANSFORM_DIR_FORWARD
        ),
        to_aces,
    )
    got = _apply(
        config.getProcessor(
            oc.REFERENCE, "sRGB - Display", "ACES 1.0 - SDR Video", OCIO.TRANSFORM_DIR_FORWARD
        ),
        rgb,
    )
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_rec709_matrix_is_colour_sciences_to_the_bit():
    # the packaged matrix the un-tone-mapped view uses (so config writing needs no colour)
    want = colour.RGB_COLOURSPACES["ITU-R BT.709"].matrix_RGB_to_XYZ
    assert np.array_equal(viewing.rec709_to_xyz(), want)
