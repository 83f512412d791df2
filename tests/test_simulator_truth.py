"""Held-out truth (ocio_vp.simulator.truth) against hand-made spectra and colour-science."""

from __future__ import annotations

import colour
import numpy as np

from ocio_vp.simulator.data import chart_reflectances
from ocio_vp.simulator.stage import (
    camera_rgb,
    environment_spectrum,
    paper_stage,
    simulate_measurements,
)
from ocio_vp.simulator.truth import (
    CHART_DUPLICATE_TOLERANCE,
    held_out_errors,
    held_out_reflectances,
    noisy_measurements,
)


def test_sets_are_off_the_chart_and_from_colour_science() -> None:
    sets = held_out_reflectances()
    chart = chart_reflectances()
    for values in sets.values():
        distance = np.abs(values[:, None, :] - chart[None]).max(axis=2).min(axis=1)
        assert np.all(distance > CHART_DUPLICATE_TOLERANCE)
    assert 150 < len(sets["rawtoaces"]) <= 190  # the RAW to ACES set minus chart look-alikes
    assert len(sets["cie2017"]) == 99
    tcs13 = colour.quality.SDS_TCS["CIE 1995"]["TCS13"]
    np.testing.assert_allclose(sets["skin"][-1][4:65:2], tcs13[np.arange(400, 705, 10)], atol=1e-9)


def test_a_perfect_solve_has_zero_error_and_a_wrong_drive_does_not() -> None:
    # The stage's own LED white: with M = [SL]^-1 and the true w_avg the wall emits the light
    # exactly, so Q = I renders every held-out sample exactly.
    stage = paper_stage()
    spectrum = environment_spectrum(stage, "rgb_led_white")
    w_avg = camera_rgb(stage, spectrum)
    M = np.linalg.inv(stage.SL)
    skin = held_out_reflectances()["skin"]
    exact = held_out_errors(
        stage, "rgb_led_white", M=M, w_avg=w_avg, Q=np.eye(3), reflectances=skin
    )
    assert np.max(exact.delta_E_2000) < 1e-6 and np.max(exact.delta_E_ITP) < 1e-6
    off = held_out_errors(
        stage, "rgb_led_white", M=M, w_avg=w_avg * [1.05, 1, 1], Q=np.eye(3), reflectances=skin
    )
    assert np.all(off.delta_E_2000 > 0.5)


def test_negative_drive_is_clipped_like_the_wall() -> None:
    stage = paper_stage()
    M = np.linalg.inv(stage.SL)
    skin = held_out_reflectances()["skin"]
    w = camera_rgb(stage, environment_spectrum(stage, "d65"))
    negative = held_out_errors(stage, "d65", M=-M, w_avg=w, Q=np.eye(3), reflectances=skin)
    dark = held_out_errors(stage, "d65", M=0 * M, w_avg=w, Q=np.eye(3), reflectances=skin)
    np.testing.assert_allclose(negative.delta_E_2000, dark.delta_E_2000)


def test_noise_touches_every_photographed_value_by_its_level() -> None:
    m = simulate_measurements(["d65"])
    noisy = noisy_measurements(m, 0.01, np.random.default_rng(0))
    ratios = np.concatenate([
        (noisy.SRL / m.SRL).ravel(), (noisy.SL / m.SL)[m.SL != 0],
        (noisy.environments[0].target_chart / m.environments[0].target_chart).ravel(),
    ])  # fmt: skip
    assert np.all(ratios != 1.0)
    assert 0.008 < np.std(ratios - 1) < 0.012


def test_a_solutions_held_out_errors_use_its_drive_and_its_correction() -> None:
    from ocio_vp.formats import Solution
    from ocio_vp.model import MatrixCorrection
    from ocio_vp.simulator.truth import solution_held_out_errors

    stage = paper_stage()
    w_avg = camera_rgb(stage, environment_spectrum(stage, "rgb_led_white"))
    M = np.linalg.inv(stage.SL)
    skin = held_out_reflectances()["skin"]
    gain = np.diag([1.1, 1.0, 0.95])

    def solution(Q: np.ndarray) -> Solution:
        return Solution(
            stage="s", environment="rgb_led_white", method="least-squares", beta=1.0,
            w_avg=w_avg, SL=stage.SL, M=M, post_correction=MatrixCorrection(Q), N=None,
            black_level_offset=None, black_level_method=None,
        )  # fmt: skip

    exact = solution_held_out_errors(stage, "rgb_led_white", solution(np.eye(3)), skin)
    assert np.max(exact.delta_E_2000) < 1e-6  # the perfect solve above, through its Solution
    got = solution_held_out_errors(stage, "rgb_led_white", solution(gain), skin)
    want = held_out_errors(stage, "rgb_led_white", M=M, w_avg=w_avg, Q=gain, reflectances=skin)
    np.testing.assert_array_equal(got.delta_E_2000, want.delta_E_2000)
    assert np.all(got.delta_E_2000 > 0.1)
