"""Skin samples, the default's skin rule and ``--priority skin`` (ocio_vp.correction.skin*).

Independent references: the simulator's spectral stage (camera RGB computed from spectra), the
chart's own reflectances (a patch is its own combination), and least squares fitted here.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ocio_vp.correction.skin import (
    COMBINATION_RIDGE,
    SKIN_CHART,
    chart_reflectances,
    chart_skin_samples,
    chart_skin_weights,
    patch_skin_samples,
)
from ocio_vp.correction.skin_priority import CHART_BUDGET
from ocio_vp.errors import InputError
from ocio_vp.pipeline import solve_environment
from ocio_vp.skin_data import training_skin

BROADBAND = ("warm_white_led", "incandescent", "indoor_daylight", "outdoor_shade", "direct_sun")


@pytest.fixture(scope="module")
def stage_and_measurements():
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    stage = paper_stage()
    return stage, simulate_measurements((*BROADBAND, "sodium_vapour"), stage=stage)


@pytest.fixture(scope="module")
def solved(stage_and_measurements):
    """Every environment solved by default and with skin first (shared by the tests)."""
    _, m = stage_and_measurements
    return {
        (env.name, priority): solve_environment(m, env, priority=priority)
        for env in m.environments
        for priority in ("general", "skin")
    }


class TestChartSkinWeights:
    def test_a_chart_patch_is_its_own_combination(self):
        chart = chart_reflectances()
        active = np.ones(24, bool)
        weights = chart_skin_weights(chart, chart[[0, 1, 11]], active)
        # Ridge-regularised, so close to (not exactly) the unit vectors: with R = U S Vᵀ and
        # λ = COMBINATION_RIDGE * trace(R Rᵀ) / 24 (the docstring's definition), a patch j is
        # rebuilt short by exactly λ Σ_k U_jk s_k / (s_k² + λ) V_k (closed form, by SVD).
        U, sv, Vt = np.linalg.svd(chart, full_matrices=False)
        lam = COMBINATION_RIDGE * np.sum(sv**2) / len(chart)
        short = lam * (U[[0, 1, 11]] * (sv / (sv**2 + lam))) @ Vt
        np.testing.assert_allclose(weights @ chart, chart[[0, 1, 11]] - short, atol=1e-9)
        assert np.argmax(weights, axis=1).tolist() == [0, 1, 11]

    def test_excluded_patches_get_no_weight(self):
        active = np.ones(24, bool)
        active[[0, 1, 5]] = False
        weights = chart_skin_weights(chart_reflectances(), training_skin().reflectances, active)
        assert np.all(weights[:, ~active] == 0)

    def test_measured_skin_is_reproduced_from_the_chart(self):
        skin = training_skin().reflectances
        weights = chart_skin_weights(chart_reflectances(), skin, np.ones(24, bool))
        # Visible range: the skin spectrum within a few % reflectance everywhere.
        visible = slice(4, 65)  # 400-700 nm on the 5 nm grid from 380
        assert np.max(np.abs(weights @ chart_reflectances() - skin)[:, visible]) < 0.05


def test_virtual_skin_is_the_skin_the_stage_camera_sees(stage_and_measurements):
    """Camera RGB is linear in reflectance: the chart combination of a skin that lies in the
    chart's span is that skin as the stage photographs it (the simulator's spectra)."""
    from ocio_vp.simulator.stage import SpectralStage

    stage, m = stage_and_measurements
    chart = chart_reflectances(SKIN_CHART)
    stage = dataclasses.replace(stage, reflectances=chart)  # a chart whose spectra we know
    rng = np.random.default_rng(1)
    inside = rng.dirichlet(np.ones(24), size=4) @ chart  # skin-like reflectances in the span
    skin_stage = SpectralStage(**{**vars(stage), "reflectances": inside})
    training = dataclasses.replace(training_skin(), reflectances=inside, bands=("light",) * 4)
    samples = chart_skin_samples(
        stage.beta * stage.SRL_unscaled, np.ones((24, 3)), np.ones(24, bool), training
    )
    np.testing.assert_allclose(
        samples.SRL, skin_stage.beta * skin_stage.SRL_unscaled, rtol=0.02, atol=1e-4
    )


def test_the_colorchecker_skin_patches_are_found_by_colour(stage_and_measurements):
    _, m = stage_and_measurements
    for env in m.environments[: len(BROADBAND)]:
        samples = patch_skin_samples(m.SRL, env.target_chart, 18, np.ones(24, bool))
        assert samples is not None and np.argmax(samples.weights, axis=1).tolist() == [0, 1]


def test_the_default_never_expects_skin_worse_than_least_squares(solved):
    """Worse by at most a thousandth of a ΔE2000 (a thousandth of a just-noticeable difference,
    ~1 ΔE2000: invisible), better overall."""
    skin = [solved[(name, "general")].diagnostics.skin for name in BROADBAND]
    assert all(s.expected <= s.least_squares + 1e-3 for s in skin), skin
    assert np.mean([s.ratio for s in skin]) < 0.95


def test_skin_first_renders_the_samples_better_and_keeps_emitters(solved):
    ratios = []
    for name in BROADBAND:
        skin = solved[(name, "skin")].diagnostics.skin
        ratios.append(skin.ratio)
        assert skin.chart_ratio <= CHART_BUDGET
        default = skin.default
        assert default.led_damage <= default.led_damage_default * (1 + 1e-9), name
        assert default.background <= default.background_default * (1 + 1e-9), name
        assert skin.expected <= default.expected + 1e-6, name
    assert np.mean(ratios) < 0.9


def test_the_background_figure_is_what_the_stage_shows(stage_and_measurements, solved):
    """The solve's model of the in-frustum background (the chart through Q^-1, the wall, the
    black level and the drive's clipping, then Q) against the spectral simulator's displayed
    chart: without noise the measured wall is the real one, so they agree to rounding."""
    from ocio_vp.correction.skin_figures import background_error
    from ocio_vp.pipeline import post_correction_problem
    from ocio_vp.simulator.evaluate import evaluate_solution

    stage, m = stage_and_measurements
    environments = {env.name: env for env in m.environments}
    for name in ("warm_white_led", "direct_sun"):
        problem = post_correction_problem(m, environments[name], [])
        assert problem.black_level is not None  # the bounce is part of what is modelled
        for priority in ("general", "skin"):
            solution = solved[(name, priority)]
            shown = float(np.mean(evaluate_solution(stage, solution).displayed))
            assert shown > 1e-4  # chart colours outside the LEDs' gamut: a figure to compare
            assert background_error(problem, solution.correction) == pytest.approx(shown, rel=1e-9)


def test_skin_first_is_drawn_towards_the_default_where_it_costs_the_background():
    """With 0.5 % noise under the warm white LED the skin fit alone raises the background
    error (the precondition, checked); skin first then takes a model between the default and
    the skin fit: background and LEDs no worse than the default's, skin still better."""
    from ocio_vp.correction.auto import bounded_candidate, q_auto
    from ocio_vp.correction.skin_figures import background_error
    from ocio_vp.correction.skin_priority import PRIORITY_SKIN_WEIGHT
    from ocio_vp.pipeline import post_correction_problem, with_skin
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements
    from ocio_vp.simulator.truth import noisy_measurements

    clean = simulate_measurements(("warm_white_led",), stage=paper_stage())
    m = noisy_measurements(clean, 0.005, np.random.default_rng(0))
    env = m.environments[0]
    problem = with_skin(post_correction_problem(m, env, []), (), None, env.name)
    alone, _ = bounded_candidate(problem, "root-polynomial", PRIORITY_SKIN_WEIGHT)
    default = q_auto(problem)
    # the precondition: the skin fit alone raises the background clearly (by over 1 %), so the
    # rule has a rise to project out
    assert background_error(problem, alone.correction) > 1.01 * background_error(
        problem, default.correction
    )
    solution = solve_environment(m, env, priority="skin")
    skin = solution.diagnostics.skin
    assert skin.default.background <= skin.default.background_default * (1 + 1e-9)
    assert skin.default.led_damage <= skin.default.led_damage_default * (1 + 1e-9)
    # and the projected step still keeps a real part (at least a tenth) of skin-first's gain
    assert skin.expected < 0.9 * skin.default.expected
    assert "of the way from the default" in solution.diagnostics.model_reason


def test_skin_first_is_safe_under_sodium(solved):
    """Rank 1: no colour to put first. Solved as the default solves it: N not solved, every
    number finite, every warning one line."""
    general = solved[("sodium_vapour", "general")]
    skin = solved[("sodium_vapour", "skin")]
    assert skin.diagnostics.model == general.diagnostics.model == "rank-1"
    np.testing.assert_array_equal(skin.Q, general.Q)
    assert skin.N is None and skin.diagnostics.N_reason
    for values in (skin.M, skin.Q, skin.correction.apply(np.eye(3))):
        assert np.all(np.isfinite(values))
    figures = skin.diagnostics.skin
    assert figures.priority == "skin" and np.isfinite(figures.expected)
    assert figures.default.background is None  # Q has no inverse: no background to model
    assert skin.diagnostics.warnings
    assert all("\n" not in str(w) for w in skin.diagnostics.warnings)


def test_skin_first_composes_with_the_emitter_guard(stage_and_measurements, solved):
    """Both act: the guard wraps a skin-first model (not the default's: skin better than
    the default's), and moves the wall's LEDs in frame clearly less than that model alone does;
    judged through the guard, skin first is no worse than the guarded default on them."""
    from ocio_vp.correction.extrapolation import in_frame_led_damage
    from ocio_vp.metrics import sample_camera_to_xyz
    from ocio_vp.model.correction import unprotected

    _, m = stage_and_measurements
    # Direct sun: under the warm lights the guarded skin fit moves the LEDs a little more than
    # the guarded default, and skin first keeps the default there (docs/skin.md).
    env = next(e for e in m.environments if e.name == "direct_sun")
    guarded = solve_environment(m, env, priority="skin", protect_emitters=True)
    default = solved[(env.name, "general")]
    assert guarded.correction.kind == "protected"
    inner = unprotected(guarded.correction)
    x = np.random.default_rng(2).uniform(0.05, 0.8, (50, 3))
    assert not np.allclose(inner.apply(x), default.correction.apply(x), rtol=1e-3)
    assert "faces first" in guarded.diagnostics.model_reason
    white = np.asarray(env.target_chart)[m.stage.white_patch]
    camera = sample_camera_to_xyz()
    damage = [in_frame_led_damage(c, m.SL, white, camera) for c in (guarded.correction, inner)]
    assert damage[0] < 0.7 * damage[1]  # 11.0 against 18.7 here
    skin = guarded.diagnostics.skin
    assert skin.priority == "skin" and skin.ratio < 1.0
    assert skin.expected < 0.95 * skin.default.expected
    # Guarded alike, the wall's LEDs in frame move as little as by the default.
    assert skin.default.led_damage <= skin.default.led_damage_default * (1 + 1e-9)


def test_skin_first_with_another_method_is_refused_on_one_line(stage_and_measurements):
    _, m = stage_and_measurements
    with pytest.raises(InputError, match=r"--priority.*cannot be combined with --method") as e:
        solve_environment(m, m.environments[0], method="least-squares", priority="skin")
    assert "\n" not in str(e.value)


def test_skin_from_spectra_is_the_skin_the_stage_camera_sees(stage_and_measurements):
    """Given the stage's own LED spectra, camera and light, the skin samples are the simulator's
    skin (up to the gains fitted through the chart's reference spectra, a different chart
    measurement than the simulated one)."""
    from ocio_vp.correction.skin_spectra import StageSpectra, spectral_skin_samples
    from ocio_vp.simulator.stage import environment_spectrum

    stage, m = stage_and_measurements
    env = m.environment("incandescent")
    light = environment_spectrum(stage, "incandescent")
    spectra = StageSpectra(stage.leds, stage.camera, {"incandescent": light}, "the stage's")
    samples = spectral_skin_samples(
        m.SRL, env.target_chart, np.ones(24, bool), spectra, "incandescent"
    )
    skin = training_skin().reflectances
    lit = stage.beta * np.einsum("wc,kw,wl->kcl", stage.camera, skin, stage.leds)
    np.testing.assert_allclose(samples.SRL, lit, rtol=0.03)
    np.testing.assert_allclose(samples.target, (skin * light) @ stage.camera, rtol=0.03)
    assert "location light measured" in samples.source


def test_a_bad_spectral_file_writes_nothing(stage_and_measurements, tmp_path, capsys):
    from ocio_vp.cli import main
    from ocio_vp.formats.measurements import save_measurements

    _, m = stage_and_measurements
    save_measurements(m, tmp_path / "m.yaml")
    (tmp_path / "leds.csv").write_text("nm,red,green,blue\n400,1,1,1\n700,1,1,-1\n")
    code = main(
        ["solve", str(tmp_path / "m.yaml"), "--out", str(tmp_path / "out"),
         "--led-spectra", str(tmp_path / "leds.csv"), "--camera-sensitivities", "Nikon 5100 (NPL)"]
    )  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2 and not (tmp_path / "out").exists()
    assert err.endswith(
        "leds.csv: column 'wavelength': too few samples: 2 between 400 and 700 nm, need at least 16"
    )
    assert "\n" not in err
