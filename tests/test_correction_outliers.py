"""Screening of inconsistent patches (ocio_vp.correction.outliers), on the spectral simulator.

Oracles: the simulator's ground truth (which patch was corrupted, the least-squares Q of the
same chart uncorrupted, fitted here with numpy's lstsq, and the held-out colours under the real
light), numpy re-fits without each patch with colour-science's ΔE2000 for the influence,
colour-science's ColorChecker names, and the solve's own outputs through the CLI.
"""

from __future__ import annotations

import dataclasses
import json

import colour
import numpy as np
import pytest
from conftest import measurement_problem

from ocio_vp.correction.outliers import (
    COLORCHECKER_NAMES,
    DELETION_GAIN,
    EXPLAINS_RELATIVE,
    OUTLIER_RELATIVE,
    SWAP_RATIO,
    deletion_gain,
    inconsistent_patches,
    pair_residuals,
    patch_influence,
    patch_name,
    patch_scores,
)
from ocio_vp.errors import InputError
from ocio_vp.metrics import sample_camera_to_xyz
from ocio_vp.pipeline import solve_environment
from ocio_vp.simulator.data import ENVIRONMENTS as ALL_ENVIRONMENTS
from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
from ocio_vp.simulator.truth import held_out_errors, held_out_reflectances, noisy_measurements

ENVIRONMENTS = (
    "direct_sun",
    "incandescent",
    "warm_white_led",
    "d65",
    "sodium_vapour",
    "high_pressure_sodium",
)


@pytest.fixture(scope="module")
def clean():
    return simulate_measurements(list(ENVIRONMENTS))


def _chart(m, env):
    """The lit chart as the wall emits it (drive clipped at 0, as the product fits it)."""
    problem = measurement_problem(m, env)
    return problem.predicted, problem.target


def _lstsq(X, P, keep=None):
    keep = np.ones(len(P), bool) if keep is None else keep
    return np.linalg.lstsq(X[keep], P[keep], rcond=None)[0].T


def test_names_are_colour_sciences_colorchecker_names() -> None:
    assert list(COLORCHECKER_NAMES) == list(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"])
    assert patch_name(18, 24) == "patch 19 (white 9.5 (.05 D))"  # people count from 1
    assert patch_name(18, 140) == "patch 19"


@pytest.mark.parametrize("camera", [None, "Sigma SDMerill (NPL)"])
def test_no_false_alarm_on_clean_charts_with_one_percent_noise(clean, camera) -> None:
    # Ten draws per environment, broadband and line-spectrum lights, two cameras.
    measurements = clean if camera is None else simulate_measurements(ENVIRONMENTS, camera=camera)
    alarms = 0
    for seed in range(10):
        m = noisy_measurements(measurements, 0.01, np.random.default_rng([seed, 7]))
        for env in m.environments:
            X, P = _chart(m, env)
            alarms += len(inconsistent_patches(X, P, np.ones(24), 18))
    assert alarms == 0


def _corrupted(X, P, j, kind):
    Xc, Pc = X.copy(), P.copy()
    array = Xc if kind.startswith("lit-") else Pc
    how = kind.removeprefix("lit-")
    if how == "zero":
        array[j] = 0
    elif how == "x2.5":
        array[j] *= 2.5
    else:
        array[[j, j + 1]] = array[[j + 1, j]]
    return Xc, Pc


@pytest.mark.parametrize("kind", ["zero", "x2.5", "swap", "lit-zero", "lit-x2.5"])
@pytest.mark.parametrize("j", [1, 6, 13])
def test_one_corrupted_patch_is_named_and_Q_stays_close(clean, kind: str, j: int) -> None:
    m = noisy_measurements(clean, 0.005, np.random.default_rng(1))
    X, P = _chart(m, m.environment("direct_sun"))
    Q_clean = _lstsq(X, P)
    Xc, Pc = _corrupted(X, P, j, kind)
    found = {f.index for f in inconsistent_patches(Xc, Pc, np.ones(24), 18)}
    assert j in found and found <= {j, j + 1}
    keep = ~np.isin(np.arange(24), list(found))
    change = np.linalg.norm(_lstsq(Xc, Pc, keep) - Q_clean) / np.linalg.norm(Q_clean)
    assert change < 0.05
    if kind != "lit-zero":  # a zero lit-chart row adds nothing to the normal equations
        plain = np.linalg.norm(_lstsq(Xc, Pc) - Q_clean) / np.linalg.norm(Q_clean)
        assert plain > 2 * change  # without screening the bad patch moves Q much more


def _held_out_delta_e(problem, environment: str, Q) -> np.ndarray:
    """ΔE2000 of the simulator's held-out colours (RAW to ACES and CIE 2017 reflectances)
    under the real light, corrected by Q."""
    sets = held_out_reflectances()
    return held_out_errors(
        spectral_stage(),  # the stage simulate_measurements used
        environment,
        M=problem.M,
        w_avg=problem.w_avg,
        Q=Q,
        reflectances=np.vstack([sets["rawtoaces"], sets["cie2017"]]),
    ).delta_E_2000


@pytest.mark.parametrize("kind", ["zero", "x2.5", "lit-x2.5"])
@pytest.mark.parametrize("j", [8, 16])
def test_a_bad_magenta_or_moderate_red_leaves_the_clean_red_in(clean, kind: str, j: int) -> None:
    # With magenta (16) or moderate red (8) gone, red (14) is the only patch of its hue and is
    # predicted 32 % off; it drags nothing (influence < 1 ΔE2000), so it stays: losing it costs
    # the held-out colours near red more than keeping it.
    m = noisy_measurements(clean, 0.005, np.random.default_rng(1))
    problem = measurement_problem(m, m.environment("direct_sun"))
    X, P = problem.predicted, problem.target
    Q_clean = _lstsq(X, P)
    Xc, Pc = _corrupted(X, P, j, kind)
    assert {f.index for f in inconsistent_patches(Xc, Pc, np.ones(24), 18)} == {j}
    keep = np.arange(24) != j
    change = np.linalg.norm(_lstsq(Xc, Pc, keep) - Q_clean) / np.linalg.norm(Q_clean)
    plain = np.linalg.norm(_lstsq(Xc, Pc) - Q_clean) / np.linalg.norm(Q_clean)
    assert change < 0.05 and plain > 2 * change
    without_red = keep & (np.arange(24) != 14)
    kept, lost = (
        np.percentile(_held_out_delta_e(problem, "direct_sun", _lstsq(Xc, Pc, k)), 95)
        for k in (keep, without_red)
    )
    assert lost > kept + 1.0  # p95 7.7 -> 9.4 and 7.8 -> 10.3 ΔE2000 against the real light


def test_two_bad_patches_are_both_excluded(clean) -> None:
    m = noisy_measurements(clean, 0.005, np.random.default_rng(2))
    X, P = _chart(m, m.environment("d65"))
    P[3] = 0.0
    P[11] *= 2.5
    assert {f.index for f in inconsistent_patches(X, P, np.ones(24), 18)} == {3, 11}


def test_many_bad_patches_are_refused(clean) -> None:
    X, P = _chart(clean, clean.environment("d65"))
    P[[1, 5, 9, 13, 17]] = 0.0
    with pytest.raises(InputError, match="too many to exclude safely"):
        inconsistent_patches(X, P, np.ones(24), 18)


def _zeroed(measurements, name: str, j: int):
    env = measurements.environment(name)
    target = np.array(env.target_chart)
    target[j] = 0.0
    changed = dataclasses.replace(env, target_chart=target)
    envs = tuple(changed if e.name == name else e for e in measurements.environments)
    return dataclasses.replace(measurements, environments=envs), changed


def test_the_solve_excludes_names_and_can_keep_all(clean) -> None:
    m, env = _zeroed(clean, "incandescent", 6)
    s = solve_environment(m, env, method="least-squares")
    assert [p.index for p in s.diagnostics.excluded_patches] == [6]
    assert s.diagnostics.excluded_patches[0].name == "patch 7 (orange)"
    assert any("patch 7 (orange)" in w for w in s.diagnostics.warnings)
    clean_Q = solve_environment(clean, clean.environment("incandescent"), method="least-squares").Q
    assert np.linalg.norm(s.Q - clean_Q) / np.linalg.norm(clean_Q) < 0.03
    kept = solve_environment(m, env, method="least-squares", keep_all_patches=True)
    assert kept.diagnostics.excluded_patches == [] and not kept.diagnostics.patch_screening
    assert np.linalg.norm(kept.Q - clean_Q) / np.linalg.norm(clean_Q) > 0.1


def test_a_bad_white_patch_that_sets_w_avg_is_refused(clean) -> None:
    env = clean.environment("d65")
    target = np.array(env.target_chart)
    target[18] *= 2.5  # the white read 2.5x too bright: w_avg from it would be 2.5x too
    no_w_avg = dataclasses.replace(env, target_chart=target, w_avg=None)
    m = clean
    envs = tuple(no_w_avg if e.name == "d65" else e for e in m.environments)
    m = dataclasses.replace(m, environments=envs)
    with pytest.raises(InputError) as error:
        solve_environment(m, no_w_avg)
    assert "white patch" in str(error.value) and ".w_avg" in str(error.value)


def test_cli_names_the_patch_and_keep_all_patches_opts_out(clean, tmp_path, capsys) -> None:
    from ocio_vp.cli import main
    from ocio_vp.formats.measurements import save_measurements

    m, _ = _zeroed(clean, "direct_sun", 13)
    path = tmp_path / "m.yaml"
    save_measurements(m, path)
    # least squares: the screening runs before any method (auto would also bake LUTs here).
    fast = ["--environment", "direct_sun", "--method", "least-squares"]
    assert main(["solve", str(path), "--out", str(tmp_path / "a"), *fast]) == 0
    out = capsys.readouterr().err  # warnings go to stderr
    assert "patch 14 (green)" in out
    solution = json.loads((tmp_path / "a" / "direct_sun" / "solution.json").read_text())
    assert solution["diagnostics"]["excluded_patches"][0]["index"] == 13
    args = ["solve", str(path), "--out", str(tmp_path / "b"), *fast]
    assert main([*args, "--keep-all-patches"]) == 0
    assert "patch 14 (green)" not in capsys.readouterr().err


def _delta_e_2000(rgb, reference_rgb, white_rgb):
    """colour-science's ΔE2000 of camera RGB through the generic camera matrix, on a white."""
    matrix = sample_camera_to_xyz()
    white = matrix @ white_rgb
    xy = colour.XYZ_to_xy(white)

    def lab(values):
        return colour.XYZ_to_Lab(values @ matrix.T / white[1], xy)

    return colour.delta_E(lab(reference_rgb), lab(rgb), method="CIE 2000")


def test_influence_is_the_delta_e_of_a_refit_without_the_patch() -> None:
    X, P = _linear_chart(24, [7], seed=3)
    w = np.ones(24)
    w[2] = 0.0  # an excluded patch takes no part
    influence = patch_influence(X, P, w, 18)
    fitted = [j for j in range(24) if w[j] > 0]
    Q_all = np.linalg.lstsq(X[fitted], P[fitted], rcond=None)[0]
    for j in fitted:
        rest = [i for i in fitted if i != j]
        Q_without = np.linalg.lstsq(X[rest], P[rest], rcond=None)[0]
        expected = _delta_e_2000(X[rest] @ Q_without, X[rest] @ Q_all, X[18] @ Q_all).mean()
        assert influence[j] == pytest.approx(expected, rel=1e-6, abs=1e-9)
    assert influence[2] == 0.0
    assert int(np.argmax(influence)) == 7


@pytest.mark.parametrize(
    ("environment", "j", "kind"),
    [
        ("sodium_vapour", 11, "x2.5"),
        ("sodium_vapour", 5, "lit-x2.5"),
        ("high_pressure_sodium", 15, "x2.5"),
        ("high_pressure_sodium", 1, "lit-x2.5"),
    ],
)
def test_under_line_spectrum_light_a_patch_that_drags_the_fit_is_named(
    clean, environment: str, j: int, kind: str
) -> None:
    # Under sodium the 3x3 misses some clean patches by 50-70 % of their value, so a patch read
    # 2.5x too bright does not stand out by its residual; it does by how far it drags the fit.
    # Oracle: the simulator's held-out colours under the real light.
    m = noisy_measurements(clean, 0.01, np.random.default_rng(1))
    env = m.environment(environment)
    problem = measurement_problem(m, env)
    X, P = problem.predicted, problem.target
    Xc, Pc = _corrupted(X, P, j, kind)
    found = {f.index for f in inconsistent_patches(Xc, Pc, np.ones(24), 18)}
    assert found == {j}
    keep = np.arange(24) != j

    def held_out(Q):
        return _held_out_delta_e(problem, environment, Q).mean()

    truth = held_out(_lstsq(X, P))
    screened = held_out(_lstsq(Xc, Pc, keep))
    plain = held_out(_lstsq(Xc, Pc))
    # Without screening the held-out colours get 2.7-4.9 ΔE2000 worse; after it, <= 0.15.
    assert plain - truth > 2.5
    assert abs(screened - truth) < 0.2


def _linear_chart(n: int, bad, seed: int = 4):
    """A chart a known 3x3 Q explains, 1 % noise, the ``bad`` patches read 2.5x too bright."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0.03, 0.9, (n, 3))
    X[18] = 0.9
    Q_true = np.array([[1.2, -0.15, 0.02], [-0.05, 1.1, -0.03], [0.01, -0.1, 0.95]])
    P = X @ Q_true.T * (1 + 0.01 * rng.standard_normal((n, 3)))
    P[list(bad)] *= 2.5
    return X, P


def test_influence_on_a_large_chart_estimates_the_full_mean() -> None:
    """Over 128 patches the influence is judged on 128 of them: against numpy re-fits without
    each patch and colour-science's ΔE2000 over *all* the others, the estimate names the same
    patch and is within 15 % (or 0.01 ΔE2000, 100x below LATER_INFLUENCE, the smallest
    threshold) everywhere. Measured on this chart: at most 8.5 % (p95), 5 % on the bad patch."""
    X, P = _linear_chart(300, [40])
    influence = patch_influence(X, P, np.ones(300), 18)
    Q_all = np.linalg.lstsq(X, P, rcond=None)[0]
    full = np.empty(300)
    for j in range(300):
        rest = np.arange(300) != j
        Q_without = np.linalg.lstsq(X[rest], P[rest], rcond=None)[0]
        full[j] = _delta_e_2000(X[rest] @ Q_without, X[rest] @ Q_all, X[18] @ Q_all).mean()
    assert int(np.argmax(influence)) == int(np.argmax(full)) == 40
    np.testing.assert_allclose(influence, full, rtol=0.15, atol=0.01)


def test_screening_a_large_chart_is_bounded() -> None:
    """1000 patches: five bad ones are named exactly; thirty are refused in one line (at most
    MAX_EXCLUDED exclusions are tried, each re-judging the chart in linear time)."""
    from ocio_vp.correction.outliers import MAX_EXCLUDED

    bad = [100, 250, 400, 650, 900]
    X, P = _linear_chart(1000, bad)
    assert sorted(f.index for f in inconsistent_patches(X, P, np.ones(1000), 18)) == bad
    many = list(range(30, 930, 30))
    X, P = _linear_chart(1000, many)
    with pytest.raises(InputError) as error:
        inconsistent_patches(X, P, np.ones(1000), 18)
    message = str(error.value)
    assert f"{MAX_EXCLUDED + 1} or more chart patches" in message
    # the first six names, then "...": 25 names would not fit MAX_MESSAGE (InputError clips)
    names = message.rsplit("--keep-all-patches): ", 1)[1]
    assert names.count("patch ") == 6 and names.endswith(", ...")


def test_a_clean_white_that_drags_an_ill_determined_fit_is_not_flagged() -> None:
    # Under sodium the 3x3 is ill-determined and the white patch, the brightest, drags it by
    # 3 ΔE2000 on this draw, yet the other patches predict it within 2 %: not a bad patch.
    # The accuracy benchmark's draw: every simulated light, so the same random numbers.
    leds = ((620.0, 30.0), (530.0, 45.0), (465.0, 25.0))
    clean = simulate_measurements(list(ALL_ENVIRONMENTS), camera="Nikon 5100 (NPL)", leds=leds)
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 100]))
    X, P = _chart(m, m.environment("sodium_vapour"))
    assert patch_influence(X, P, np.ones(24), 18)[18] > 3.0
    assert inconsistent_patches(X, P, np.ones(24), 18) == []


def test_pair_residuals_are_refits_without_both_patches(clean) -> None:
    """Against numpy: for every neighbour pair, lstsq on the other patches (weighted by sqrt of
    the weights), both predicted, their residuals as read and exchanged summed; a pair with an
    unfitted patch has none."""
    m = noisy_measurements(clean, 0.01, np.random.default_rng(3))
    X, P = _chart(m, m.environment("sodium_vapour"))
    w = np.random.default_rng(5).uniform(0.5, 1.0, 24)
    w[9] = 0.0
    scale = np.array([0.8, 0.6, 0.05])
    as_read, exchanged = pair_residuals(X, P, w, scale)
    for j in range(23):
        k = j + 1
        if j in (8, 9):
            assert np.isnan(as_read[j]) and np.isnan(exchanged[j])
            continue
        rest = (np.arange(24) != j) & (np.arange(24) != k) & (w > 0)
        root = np.sqrt(w[rest])[:, None]
        Q = np.linalg.lstsq(X[rest] * root, P[rest] * root, rcond=None)[0].T
        pj, pk = X[j] @ Q.T / scale, X[k] @ Q.T / scale
        tj, tk = P[j] / scale, P[k] / scale
        norm = np.linalg.norm
        assert as_read[j] == pytest.approx(norm(pj - tj) + norm(pk - tk), rel=1e-9)
        assert exchanged[j] == pytest.approx(norm(pj - tk) + norm(pk - tj), rel=1e-9)


@pytest.mark.parametrize(("environment", "j"), [("sodium_vapour", 11), ("high_pressure_sodium", 8)])
@pytest.mark.parametrize("kind", ["swap", "lit-swap"])
def test_a_swapped_pair_under_sodium_light_is_named_and_both_excluded(
    clean, environment: str, j: int, kind: str
) -> None:
    """Under sodium light the 3x3 model misses single patches by up to ~70 %, so the
    single-patch test lets a swap pass; the pair test names both, each with the other."""
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 7]))
    X, P = _chart(m, m.environment(environment))
    Xc, Pc = _corrupted(X, P, j, kind)
    found = inconsistent_patches(Xc, Pc, np.ones(24), 18)
    assert sorted(f.index for f in found) == [j, j + 1]
    by_index = {f.index: f for f in found}
    assert by_index[j].swapped_with == j + 1 and by_index[j + 1].swapped_with == j
    as_read, exchanged = by_index[j].swap_residuals
    assert as_read >= SWAP_RATIO * exchanged
    text = by_index[j].describe()
    name_j, name_k = patch_name(j, 24), patch_name(j + 1, 24)
    assert text.startswith(f"{name_j} and {name_k} look swapped")
    assert f"{100 * as_read:.0f}% of white as read" in text
    # The clean chart has no alarm, and the same pair as read scores below the limits.
    assert inconsistent_patches(X, P, np.ones(24), 18) == []


def test_the_solve_says_which_patches_look_swapped(clean) -> None:
    env = clean.environment("sodium_vapour")
    target = np.array(env.target_chart)
    target[[11, 12]] = target[[12, 11]]
    swapped = dataclasses.replace(env, target_chart=target)
    envs = tuple(swapped if e.name == env.name else e for e in clean.environments)
    m = dataclasses.replace(clean, environments=envs)
    s = solve_environment(m, swapped, method="least-squares")
    excluded = s.diagnostics.excluded_patches
    assert [(p.index, p.swapped_with) for p in excluded] == [(11, 12), (12, 11)]
    assert excluded[0].swapped_name == "patch 13 (blue)"
    assert any(
        "patch 12 (orange yellow) and patch 13 (blue) look swapped" in w
        for w in s.diagnostics.warnings
    )


def test_a_swapped_pair_on_a_large_chart_is_named() -> None:
    # 1000 patches: the pair test is one batched 3x3 downdate per neighbour pair (linear).
    X, P = _linear_chart(1000, [])
    P[[500, 501]] = P[[501, 500]]
    found = inconsistent_patches(X, P, np.ones(1000), 18)
    assert sorted((f.index, f.swapped_with) for f in found) == [(500, 501), (501, 500)]


def test_deletion_gain_is_the_rest_refitted_without_each_patch() -> None:
    """Against numpy: for each fitted patch j, lstsq on the chart without j and each other
    fitted patch k in turn predicts k; the root mean square of those residuals (relative to
    white) over k, and the median of that over j divided by it. An unfitted patch scores 0 and
    judges nothing."""
    X, P = _linear_chart(24, [9], seed=5)
    w = np.ones(24)
    w[3] = 0.0
    scale = P[18]
    gain = deletion_gain(X, P, w, scale)
    fitted = np.flatnonzero(w > 0)
    cost = {}
    for j in fitted:
        held = []
        for k in fitted[fitted != j]:
            keep = (w > 0) & (np.arange(24) != j) & (np.arange(24) != k)
            Q = np.linalg.lstsq(X[keep], P[keep], rcond=None)[0]
            held.append(np.sum(((P[k] - X[k] @ Q) / scale) ** 2))
        cost[j] = np.sqrt(np.mean(held))
    typical = np.median(list(cost.values()))
    expected = np.array([typical / cost[j] if j in cost else 0.0 for j in range(24)])
    np.testing.assert_allclose(gain, expected, rtol=1e-9)
    assert int(np.argmax(gain)) == 9 and gain[9] > DELETION_GAIN


def test_under_high_pressure_sodium_a_patch_the_rest_cannot_explain_is_named(clean) -> None:
    """Patch 1 read 2.5x too bright under high-pressure sodium: it misses its prediction by
    61 % of itself, less than the 3x3 misses clean patches there, and drags the fit by less
    than a clean white can, so neither test names it; without it, the other patches are
    predicted more than DELETION_GAIN times better than without a typical patch. Oracle: the
    simulator's held-out colours under the real light, and numpy's fit without the patch."""
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 7]))
    problem = measurement_problem(m, m.environment("high_pressure_sodium"))
    X, P = problem.predicted, problem.target
    Xc, Pc = _corrupted(X, P, 1, "x2.5")
    scores = patch_scores(Xc, Pc, np.ones(24), 18)
    assert scores["suspect"].max() < 1.0 < scores["explains"][1]
    assert scores["deletion"][1] > DELETION_GAIN
    found = inconsistent_patches(Xc, Pc, np.ones(24), 18)
    assert [f.index for f in found] == [1]
    assert found[0].deletion == pytest.approx(scores["deletion"][1])
    assert f"predicted {scores['deletion'][1]:.1f}x better than without a typical" in (
        found[0].describe()
    )

    def held_out(Q):
        return _held_out_delta_e(problem, "high_pressure_sodium", Q).mean()

    truth = held_out(_lstsq(X, P))
    # Measured: 0.96 ΔE2000 worse on average without screening, 0.05 better after it.
    assert held_out(_lstsq(Xc, Pc)) - truth > 0.8
    assert abs(held_out(_lstsq(Xc, Pc, np.arange(24) != 1)) - truth) < 0.1


@pytest.mark.parametrize(
    ("patch", "environment", "where"),
    [(18, e, w) for e in ("direct_sun", "incandescent", "d65") for w in ("target", "lit")]
    + [(15, "direct_sun", "target")],
)
def test_a_bright_patch_read_1_3x_too_bright_is_named(clean, patch, environment, where) -> None:
    """A flare on the white patch (18; its target value or its lit-chart row 1.3x too bright),
    or on the yellow (15), under broadband light: it misses its held-out prediction by only
    18-25 % of itself, under OUTLIER_RELATIVE, but the rest of the chart is over DELETION_GAIN
    times more consistent without it. Oracle: the simulator's held-out colours under the real
    light, and numpy's fit with and without the patch."""
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 7]))
    problem = measurement_problem(m, m.environment(environment))
    X, P = problem.predicted, problem.target
    Xc, Pc = X.copy(), P.copy()
    (Pc if where == "target" else Xc)[patch] *= 1.3
    scores = patch_scores(Xc, Pc, np.ones(24), 18)
    assert EXPLAINS_RELATIVE < scores["relative"][patch] < OUTLIER_RELATIVE
    assert scores["deletion"][patch] > DELETION_GAIN
    found = inconsistent_patches(Xc, Pc, np.ones(24), 18)
    assert [f.index for f in found] == [patch]

    def held_out(Q):
        return _held_out_delta_e(problem, environment, Q).mean()

    truth = held_out(_lstsq(X, P))
    # Measured on these charts: 0.66-1.10 ΔE2000 worse on average without screening (white:
    # 0.76-1.10, yellow 0.66), within 0.04 of the clean chart's after it.
    assert held_out(_lstsq(Xc, Pc)) - truth > 0.4
    assert abs(held_out(_lstsq(Xc, Pc, np.arange(24) != patch)) - truth) < 0.1


def test_after_one_exclusion_a_lit_row_read_as_zero_is_still_named(clean) -> None:
    """Two bad patches under sodium light: patch 1 read 2.5x too bright, and patch 4's lit row
    lost (zero). The lost row cannot drag the fit (a zero row adds nothing to it) and misses
    its prediction by exactly 100 % of itself (the prediction of a zero row is zero), which
    must count as far off after the first exclusion, as it does before it."""
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 7]))
    X, P = _chart(m, m.environment("high_pressure_sodium"))
    Xc, Pc = _corrupted(X, P, 1, "x2.5")
    Xc, Pc = _corrupted(Xc, Pc, 4, "lit-zero")
    found = inconsistent_patches(Xc, Pc, np.ones(24), 18)
    assert [f.index for f in found] == [1, 4]
    assert found[1].relative == pytest.approx(1.0) and found[1].influence == 0.0


def test_when_the_data_cannot_tell_two_patches_apart_both_are_excluded_and_named() -> None:
    """The bad-patch study's Nikon chart under high-pressure sodium with patch 13 (green) read
    2.5x too bright: on its own evidence the clean patch 10 (yellow green) is the one flagged
    (it drags the ill-determined fit by 3 ΔE2000), yet without patch 13 the rest of the chart
    is predicted at least as well, and patch 13 looked suspect too. Both are excluded and
    each names the other. Oracle: the corrupted patch is known; the simulator's held-out
    colours under the real light with numpy's fit without both."""
    clean = simulate_measurements(list(ALL_ENVIRONMENTS), camera="Nikon 5100 (NPL)")
    m = noisy_measurements(clean, 0.01, np.random.default_rng([0, 99]))
    problem = measurement_problem(m, m.environment("high_pressure_sodium"))
    X, P = problem.predicted, problem.target
    Xc, Pc = _corrupted(X, P, 13, "x2.5")
    scores = patch_scores(Xc, Pc, np.ones(24), 18)
    assert scores["score"][10] >= 1.0 > scores["misses"][10]
    assert scores["score"][13] < 1.0 and scores["deletion"][13] > scores["deletion"][10]
    found = inconsistent_patches(Xc, Pc, np.ones(24), 18)
    assert [(f.index, f.ambiguous_with) for f in found] == [(10, 13), (13, 10)]
    text = found[0].describe()
    assert text.startswith(
        "patch 11 (yellow green) or patch 14 (green): one of the two is inconsistent with the "
        "rest and the data cannot tell which"
    )
    assert f"without patch 14 (green) {scores['deletion'][13]:.2f}x" in text
    assert text.endswith("both are excluded")

    def held_out(Q):
        return _held_out_delta_e(problem, "high_pressure_sodium", Q).mean()

    def q_change(Q):
        return np.linalg.norm(Q - Q0) / np.linalg.norm(Q0)

    Q0 = _lstsq(X, P)
    both = _lstsq(Xc, Pc, ~np.isin(np.arange(24), [10, 13]))
    only_10 = _lstsq(Xc, Pc, np.arange(24) != 10)
    # Measured: Q moves by 78 % of itself without both, 111 % without patch 10 alone (Q is
    # ill-determined under this light); the mean held-out ΔE2000 under the real light moves
    # by 0.22 and 0.29 from the clean chart's 7.14.
    assert q_change(both) < 0.85 < 1.05 < q_change(only_10)
    assert abs(held_out(both) - held_out(Q0)) < abs(held_out(only_10) - held_out(Q0))


@pytest.mark.parametrize(
    ("environment", "seed"), [("outdoor_shade", 31), ("indoor_daylight", 42), ("d65", 88)]
)
def test_a_colour_the_3x3_cannot_model_is_not_a_bad_patch(environment: str, seed: int) -> None:
    # With the paper stage's 630/20 nm red LED, daylight's saturated red (patch 14) is missed
    # by the 3x3 fitted on the other patches by ~28 % of itself, over the 30 % limit in 3-4 %
    # of 1 %-noise draws (these three, among 300). The root-polynomial, the default's non-linear
    # candidate, predicts it: a model limit, not a defect. A defect is missed by both.
    m = noisy_measurements(
        simulate_measurements([environment]), 0.01, np.random.default_rng([seed, 99])
    )
    X, P = _chart(m, m.environment(environment))
    keep = np.arange(24) != 14
    miss = np.linalg.norm(X[14] @ _lstsq(X, P, keep).T - P[14])  # oracle: numpy re-fit
    assert miss / np.linalg.norm(P[14]) > 0.3
    assert inconsistent_patches(X, P, np.ones(24), 18) == []
    for kind in ("zero", "x2.5", "lit-zero"):
        Xc, Pc = _corrupted(X, P, 14, kind)
        assert [f.index for f in inconsistent_patches(Xc, Pc, np.ones(24), 18)] == [14], kind
