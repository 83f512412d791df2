"""Diagnostics (ocio_vp.calibration.diagnostics), clipped patches, and what the config leaves out.

Independent sources: hand-computed closed forms, a plain numpy leave-one-out loop, the paper's
Section 3.4 ratio b / w_camera, the simulator (low-pressure sodium lies outside the LED gamut:
DESIGN.md "facts already measured"), and OCIO's own processors for the configs.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.calibration.diagnostics import (
    NEGLIGIBLE_OFFSET,
    black_level_bounce,
    clipped_patches,
    in_frustum_drive_range,
    offset_is_negligible,
    out_of_frustum_drive,
)
from ocio_vp.cli import main
from ocio_vp.correction.linear import AUTO_LADDER
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import measurements_from_dict, measurements_to_dict
from ocio_vp.formats.solution import solution_to_json
from ocio_vp.ocio import config as oc
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.stage import simulate_measurements

ATOL = 1e-12


def _apply(config: OCIO.Config, src: str, dst: str, rgb) -> np.ndarray:
    cpu = config.getProcessor(src, dst).getDefaultCPUProcessor()
    return np.asarray(cpu.applyRGB([float(v) for v in rgb]), dtype=np.float64)


class TestDrives:
    def test_negative_channel_is_reported(self) -> None:
        d = out_of_frustum_drive(np.array([[1, 0, 0], [0, 1, 0], [0, -2, 1]]), [0.5, 0.5, 0.5])
        np.testing.assert_allclose(d.drive, [0.5, 0.5, -0.5])
        assert d.negative_channels == [2]
        np.testing.assert_allclose(d.clipped_drive, [0.5, 0.5, 0.0])

    def test_in_frustum_range_counts_by_hand(self) -> None:
        target = np.full((24, 3), 0.25)
        target[18] = [0.5, 0.5, 0.5]  # white -> peak drive 1 after scaling by 2
        target[0] = [0.6, 0.1, 0.1]  # drive 1.2 in red: above
        target[1] = [0.05, 0.3, 0.3]  # through the matrix below: red 0.05 - 0.2 < 0
        matrix = np.eye(3)
        matrix[0, 1] = -0.5
        r = in_frustum_drive_range(target, M=np.eye(3), matrix=matrix, white_patch=18)
        assert r.content_scale == 2.0
        # Red drive 2 (c_r - 0.5 c_g): patch 0 -> 1.1 (above), patch 1 -> -0.2 (below); the
        # others 2 (0.25 - 0.125) = 0.25, and white 2 (0.5 - 0.25) = 0.5.
        assert (r.below_zero, r.above_max, r.patches_outside) == (1, 1, [0, 1])

    def test_black_level_bounce_is_the_papers_ratio(self) -> None:
        SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])
        b = np.array([0.0416, 0.0345, 0.0204])
        # Section 3.4: w_camera = sum of the primaries' images = [1.04, 1.15, 1.02].
        np.testing.assert_allclose(black_level_bounce(b, SL), [0.04, 0.03, 0.02])

    def test_sodium_is_outside_the_led_gamut_on_the_simulator(self) -> None:
        m = simulate_measurements(["sodium_vapour", "d65"])
        sodium = solve_environment(m, m.environment("sodium_vapour"))
        daylight = solve_environment(m, m.environment("d65"))
        assert sodium.diagnostics.out_of_frustum_negative_channels
        assert sodium.diagnostics.lit_chart_error_clipped_drive is not None
        assert daylight.diagnostics.out_of_frustum_negative_channels == []
        assert daylight.diagnostics.lit_chart_error_clipped_drive is None


class TestClipping:
    def _document(self, clip_level: float) -> dict:
        data = make_measurements_dict(environments=1)
        data["stage"]["clip_level"] = clip_level
        return data

    def test_clipped_patches_are_excluded_and_reported(self) -> None:
        data = self._document(0.95)  # the primaries peak at 0.9
        target = np.asarray(data["environments"][0]["target_chart"])
        target[[2, 5]] = [0.95, 0.3, 0.3]  # at the clip level -> clipped
        target[18] = [0.9, 0.9, 0.9]
        data["environments"][0]["target_chart"] = target.tolist()
        m = measurements_from_dict(data)
        assert clipped_patches(m.SRL, target, 0.95) == [2, 5]
        s = solve_environment(m, m.environments[0], method="least-squares")
        clipped = s.diagnostics.clipped_patches
        assert clipped == [2, 5]
        assert any("clipped" in w for w in s.diagnostics.warnings)
        keep = np.setdiff1d(np.arange(24), clipped)
        X = s.diagnostics.charts.lit_baseline
        QT = np.linalg.lstsq(X[keep], target[keep], rcond=None)[0]
        np.testing.assert_allclose(s.Q, QT.T, atol=1e-12)

    def test_clipped_white_needs_w_avg(self) -> None:
        data = self._document(0.95)
        data["environments"][0]["target_chart"][18] = [0.96, 0.9, 0.9]
        m = measurements_from_dict(data)
        with pytest.raises(InputError, match="white patch 18 is clipped"):
            solve_environment(m, m.environments[0])
        data["environments"][0]["w_avg"] = [0.85, 0.85, 0.85]
        m = measurements_from_dict(data)
        assert 18 in solve_environment(m, m.environments[0]).diagnostics.clipped_patches

    def test_clipped_primary_is_an_input_error(self) -> None:
        m = measurements_from_dict(self._document(0.85))  # the red primary reads 0.9
        with pytest.raises(InputError, match="primary is clipped") as info:
            solve_environment(m, m.environments[0])
        assert "primaries" in str(info.value)

    def test_clip_level_round_trips_and_is_validated(self) -> None:
        m = measurements_from_dict(self._document(2.0))
        assert m.stage.clip_level == 2.0
        assert measurements_to_dict(m)["stage"]["clip_level"] == 2.0
        with pytest.raises(InputError, match="clip_level"):
            measurements_from_dict(self._document(0.0))


@pytest.fixture(scope="module")
def led_white():
    m = simulate_measurements(["rgb_led_white", "incandescent"])
    return m, solve_environment(m, m.environment("rgb_led_white"), method="auto")


class TestConfigLeavesOutWhatIsNotNeeded:
    def test_identity_Q_has_no_post_correction_transform(self, led_white) -> None:
        _, s = led_white
        config = oc.build_config(s)
        footage = config.getColorSpace(oc.POST_CORRECTION_COLORSPACE)
        assert footage.getTransform(OCIO.COLORSPACE_DIR_TO_REFERENCE) is None
        rgb = [0.2, 0.5, 0.9]
        np.testing.assert_allclose(
            _apply(config, oc.POST_CORRECTION_COLORSPACE, oc.REFERENCE, rgb), rgb, rtol=1e-6
        )
        assert "Q is the identity" in footage.getDescription()
        assert "N = M" in config.getColorSpace(oc.IN_FRUSTUM).getDescription()

    def test_non_identity_Q_is_applied(self, led_white) -> None:
        m, _ = led_white
        s = solve_environment(m, m.environment("incandescent"), method="least-squares")
        config = oc.build_config(s)
        rgb = np.array([0.2, 0.5, 0.9])
        np.testing.assert_allclose(
            _apply(config, oc.POST_CORRECTION_COLORSPACE, oc.REFERENCE, rgb), s.Q @ rgb, rtol=1e-5
        )

    def test_negligible_offset_is_left_out_but_kept_in_the_solution(self, led_white) -> None:
        _, s = led_white
        tiny = -s.M @ (s.SL.sum(axis=1) * NEGLIGIBLE_OFFSET * 0.5)
        assert offset_is_negligible(tiny, s.SL)
        quiet = dataclasses.replace(s, black_level_offset=tiny, black_level_method="exact")
        config = oc.build_config(quiet)
        np.testing.assert_array_equal(_apply(config, oc.REFERENCE, oc.IN_FRUSTUM, [0, 0, 0]), 0)
        assert json.loads(solution_to_json(quiet))["black_level_offset"] is not None
        loud = dataclasses.replace(quiet, black_level_offset=tiny * 1000)
        assert not offset_is_negligible(loud.black_level_offset, s.SL)
        np.testing.assert_allclose(
            _apply(oc.build_config(loud), oc.REFERENCE, oc.IN_FRUSTUM, [0, 0, 0]),
            tiny * 1000,
            rtol=1e-5,
        )


def test_solution_json_and_table_carry_the_diagnostics(tmp_path, capsys) -> None:
    import yaml

    path = tmp_path / "stage.yaml"
    path.write_text(yaml.safe_dump(make_measurements_dict(environments=1)))
    assert main(["solve", str(path), "--out", str(tmp_path / "out")]) == 0
    table = capsys.readouterr().out
    for column in ("model", "cond[SL]", "CV", "LEDs in frame", "drive<0", "clipped"):
        assert column in table
    solution = json.loads((tmp_path / "out" / "env_0" / "solution.json").read_text())
    d = solution["diagnostics"]
    assert solution["method"] == "auto"
    assert d["model"] in AUTO_LADDER
    assert d["model"] in table and d["model_reason"]
    assert np.asarray(d["residuals_per_patch"]).shape == (24, 3)
    assert len(d["cross_validated_error"]) == 3
    assert d["identity_check"]["max_abs_error"] <= d["identity_check"]["bound"]
    for key in ("in_frustum_drive_range", "black_level_bounce", "clipped_patches", "rank_target"):
        assert key in d
    # Every candidate was compared, or is named with the reason it was not a candidate.
    excluded = " ".join(d["method_notes"]["excluded_candidates"])
    for name in AUTO_LADDER:
        assert name in d["method_notes"]["cv_error"] or name in excluded


def test_clipped_drive_charts_are_what_the_spectral_stage_shows() -> None:
    """Sodium: M w_avg has a negative channel; the clipped-drive lit charts (eq. 3 with
    clip(M w_avg, 0)) equal the simulator's spectral rendering of the wall's real light."""
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.predict import predict_stage
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    stage = paper_stage()
    measurements = simulate_measurements(["sodium_vapour", "direct_sun"], stage=stage)
    sodium, sun = (
        solve_environment(measurements, env, method="least-squares")
        for env in measurements.environments
    )
    truth = predict_stage(stage, "sodium_vapour", M=sodium.M, Q=sodium.Q)
    assert truth.lit_drive_clipped
    charts = sodium.diagnostics.charts_clipped_drive
    scale = truth.target[18].max()
    np.testing.assert_allclose(charts.lit_baseline, truth.lit, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(
        charts.lit_corrected, truth.lit_corrected, rtol=0, atol=1e-12 * scale
    )
    assert sun.diagnostics.charts_clipped_drive is None  # nothing clipped: eq. 3 as is
