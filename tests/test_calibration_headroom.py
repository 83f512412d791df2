"""Content scale and headroom against closed forms: M c, N c + offset, and on a PQ wall the
luminance of content white from colour-science's RGB -> XYZ."""

from __future__ import annotations

import dataclasses
import math

import colour
import numpy as np
from conftest import make_measurements_dict

from ocio_vp.calibration.headroom import content_scale, content_scale_lines
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.pipeline import solve_measurements
from ocio_vp.wall.encoding import with_wall_encoding


def _solution(camera=None):
    data = make_measurements_dict(seed=2, environments=1)
    if camera:
        data["stage"]["camera_colorspace"] = camera
    (solution,) = solve_measurements(measurements_from_dict(data), method="least-squares")
    return solution


def test_camera_native_white_is_m_times_ones():
    solution = _solution()
    scale = content_scale(solution)
    np.testing.assert_allclose(scale.outer_drive, solution.M @ np.ones(3), rtol=1e-12)
    inner = solution.N @ np.ones(3) + solution.black_level_offset
    np.testing.assert_allclose(scale.inner_drive, inner, rtol=1e-12)
    stops = scale.to_dict()["outer_headroom_stops"]
    assert stops == [-math.log2(d) for d in scale.outer_drive]
    assert scale.peak_content == 1.0 / max(scale.outer_drive.max(), scale.inner_drive.max())
    assert scale.white_nits is None


def test_a_clipping_solve_warns_and_pq_states_the_nits():
    solution = _solution("ARRI Wide Gamut 4")
    M = solution.M * 2.0  # a dimmer panel: content white needs twice the drive
    scale = content_scale(
        with_wall_encoding(dataclasses.replace(solution, M=M), "pq", peak_nits=600.0)
    )
    lines = scale.lines()
    out, err = content_scale_lines([scale])
    assert out == lines and scale.clips and len(err) == 1 and err[0].startswith("warning:")
    assert f"peak at content {scale.peak_content:.3g}" in lines[1]
    assert f"content white {scale.white_nits:.0f} nits" in lines[1]
    # content white: Rec.709 (1, 1, 1) in the camera gamut; its luminance relative to the wall's
    # white (SL 1) on colour-science's AWG4 -> XYZ
    awg4 = colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"]
    white = colour.RGB_to_RGB(np.ones(3), colour.RGB_COLOURSPACES["ITU-R BT.709"], awg4,
                              chromatic_adaptation_transform="CAT02")  # fmt: skip
    y = lambda rgb: colour.RGB_to_XYZ(rgb, awg4)[1]  # noqa: E731
    want = 600.0 * y(white) / y(solution.SL @ np.ones(3))
    assert abs(scale.white_nits - want) < 1e-9 * want
    assert "drive 1.0 = 600 nits" in lines[0]


def test_white_needing_negative_drive_is_stated_and_writes_strict_json():
    """A stage whose LEDs cannot reach the environment's white (a channel of M 1 below zero):
    that channel has no headroom (null, not inf, so strict JSON readers accept it) and the
    solve warns in words."""
    import json

    solution = _solution()
    M = solution.M.copy()
    M[1] = -0.5 * M[1]  # green drive of content white negative outside the frustum
    scale = content_scale(dataclasses.replace(solution, M=M))
    assert scale.outer_drive[1] < 0 and scale.negative_channels == ["green"]
    data = json.loads(json.dumps(scale.to_dict(), allow_nan=False))
    assert data["outer_headroom_stops"][1] is None
    assert data["outer_headroom_stops"][0] == -math.log2(scale.outer_drive[0])
    _, err = content_scale_lines([scale])
    assert any("negative drive in green" in line for line in err)


def test_soft_clip_is_shown_with_the_content_where_it_starts():
    """Knee k: compression starts at content k * peak_content (the drive is linear in content
    below it); to_dict says so only when the solve asked for a soft clip."""
    from ocio_vp.wall.softclip import with_soft_clip

    solution = _solution()
    solution = dataclasses.replace(solution, M=solution.M * 2.0)  # content white clips
    plain = content_scale(solution)
    assert plain.soft_clip is None and plain.knee_content is None
    assert "soft_clip_knee" not in plain.to_dict() and "soft clip" not in plain.row()
    scale = content_scale(with_soft_clip(solution, 0.8))
    assert scale.knee_content == 0.8 * scale.peak_content
    assert scale.to_dict()["soft_clip_knee"] == 0.8
    assert f"soft clip from 80% of full drive (content {scale.knee_content:.3g})" in scale.row()
    _, err = content_scale_lines([scale])
    assert "compressed towards full drive by the soft clip" in err[0]
    _, err = content_scale_lines([plain])
    assert "clips there" in err[0]
