"""Property-based tests (hypothesis) of the solve at the extremes (issue 7, docs/stability.md).

Generated stages span calibration values from 1e-6 to 1e4 (exposure), cond([SL]) from 1 to
~1e8 (an almost-dark LED channel), optional float16 quantisation and clipping; environments are
broadband (with or without channel crosstalk), the stage's own LEDs, or monochromatic (rank 1, like low-pressure sodium). The
references are closed forms: eq. 7 (Q [SL] N = I) with the rounding bound of a backward-stable
LU solve, and the scaling laws of eqs. 1-8 derived in docs/stability.md.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from conftest import make_measurements_dict
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ocio_vp.calibration.diagnostics import IDENTITY_BOUND_FACTOR
from ocio_vp.calibration.equations import MAX_CONDITION_SL, condition_number
from ocio_vp.correction.validation import CLOSED_FORM_METHODS
from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import MAX_CAMERA_VALUE, MIN_SIGNAL, measurements_from_dict
from ocio_vp.formats.solution import solution_to_json
from ocio_vp.ocio.config import build_config
from ocio_vp.pipeline import solve_environment

CHANNELS = ("red", "green", "blue")
BETA = 0.25
N_PATCHES = 24
WHITE = 18
SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
#: The InputErrors a generated (finite, non-negative) input may legitimately raise.
EXPECTED_ERRORS = re.compile(
    r"\[SL\] is singular|clipped|chart patches|is black|give w_avg|reads 0 in the camera|"
    r"not a camera value|colour direction"
)


@st.composite
def scenes(
    draw,
    *,
    quantise: bool = True,
    clip: bool = True,
    kinds: tuple[str, ...] = ("broadband", "mixed", "stage_led", "monochromatic"),
) -> dict:
    """A measurements document at the extremes (see the module docstring)."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    exposure = 10.0 ** draw(st.floats(-6, 4))
    target_exposure = 10.0 ** draw(st.floats(-6, 4))
    dark = 10.0 ** draw(st.floats(-8, 0))  # the weakest LED channel's level
    cross = draw(st.floats(0.0, 0.4))  # how much each LED leaks into the other camera channels
    kind = draw(st.sampled_from(kinds))
    gains = np.ones(3)
    gains[draw(st.integers(0, 2))] = dark
    SL = (np.eye(3) + cross * rng.uniform(0, 1, (3, 3))) * gains[None, :] * exposure
    rho = rng.uniform(0.03, 0.9, (N_PATCHES, 3))
    rho[WHITE] = 0.9
    texture = 1 + 0.1 * rng.uniform(-1, 1, (N_PATCHES, 3, 3))
    texture[WHITE] = 1.0
    SRL = BETA * rho[:, :, None] * SL[None] * texture
    env: dict = {"name": "generated"}
    if kind == "stage_led":
        drive = rng.uniform(0.2, 1.0, 3) * target_exposure / exposure
        target = np.einsum("jck,k->jc", SRL, drive) / BETA
        env["w_avg"] = (SL @ drive).tolist()
    elif kind == "monochromatic":
        colour = rng.uniform(0.05, 1.0, 3) * target_exposure
        target = rho.mean(axis=1)[:, None] * colour[None]
    else:
        light = rng.uniform(0.3, 1.0, 3) * target_exposure
        target = rho * (1 + 0.2 * rng.uniform(-1, 1, (N_PATCHES, 3))) * light
        if kind == "mixed":  # a light the LEDs render with crosstalk: a full Q is needed
            target = target @ (np.eye(3) + 0.3 * rng.uniform(0, 1, (3, 3))).T
    env["target_chart"] = target.tolist()
    if draw(st.booleans()):
        env["black_level"] = (0.04 * target[WHITE] * rng.uniform(0.5, 1.5, 3)).tolist()
    stage: dict = {"name": "generated", "beta": BETA}
    if quantise and draw(st.booleans()):
        SL, SRL, target = (np.asarray(a, np.float16).astype(np.float64) for a in (SL, SRL, target))
        env["target_chart"] = target.tolist()
    if clip and draw(st.booleans()):
        # The camera clips the brightest patches of the location chart (one clip level for
        # every plate, in camera units); w_avg then has to be given. Primaries stay below it.
        level = float(np.quantile(target, 0.9))
        if level > SL.max() and level > 0:
            env["w_avg"] = env.get("w_avg", (target[WHITE] / 0.9).tolist())
            target = np.minimum(target, level)
            env["target_chart"] = target.tolist()
            stage["clip_level"] = level
    return {
        "format": "ocio-vp/measurements",
        "version": 1,
        "stage": stage,
        "primaries": {c: SL[:, k].tolist() for k, c in enumerate(CHANNELS)},
        "lit_chart": {c: SRL[:, :, k].tolist() for k, c in enumerate(CHANNELS)},
        "environments": [env],
    }


def _finite_tree(value, path="") -> None:
    """Every number in a solution.json is finite; only cond_Q may say "inf" (a singular Q)."""
    if isinstance(value, dict):
        for key, item in value.items():
            _finite_tree(item, f"{path}.{key}")
    elif isinstance(value, list):
        for i, item in enumerate(value):
            _finite_tree(item, f"{path}[{i}]")
    elif isinstance(value, float):
        assert math.isfinite(value), path
    elif isinstance(value, str) and value in ("inf", "-inf", "nan"):
        assert path == ".diagnostics.cond_Q", path


def _solve(document: dict, method: str):
    m = measurements_from_dict(document, source="generated.yaml")
    return m, solve_environment(m, m.environments[0], method=method)


@SETTINGS
@given(scenes())
def test_outputs_are_finite_and_eq7_holds_within_its_bound(document: dict) -> None:
    for method in ("auto", "least-squares"):
        try:
            m, s = _solve(document, method)
        except InputError as error:
            assert EXPECTED_ERRORS.search(str(error)), str(error)
            if "[SL]" in str(error):
                SL = np.stack([document["primaries"][c] for c in CHANNELS], axis=1)
                assert not condition_number(SL) <= MAX_CONDITION_SL
            return
        _finite_tree(json.loads(solution_to_json(s)))
        for matrix in (s.M, s.Q, s.in_frustum_matrix, s.in_frustum_offset):
            assert np.all(np.isfinite(matrix))
        if s.N is not None:
            # Eq. 7 with the bound of docs/stability.md: 32 eps cond(Q) cond([SL]).
            error = np.max(np.abs(s.Q @ s.SL @ s.N - np.eye(3)))
            bound = IDENTITY_BOUND_FACTOR * np.finfo(float).eps
            assert error <= bound * condition_number(s.Q) * condition_number(s.SL)
            assert s.diagnostics.identity_check.max_abs_error == error
        clip = m.stage.clip_level
        target = m.environments[0].target_chart
        expected = (
            []
            if clip is None
            else np.flatnonzero(np.any(m.SRL >= clip, axis=(1, 2)) | np.any(target >= clip, axis=1))
        )
        assert s.diagnostics.clipped_patches == [int(j) for j in expected]
    build_config(s).validate()  # the config of the last solve builds and validates


@SETTINGS
@given(scenes(kinds=("monochromatic",), quantise=False))
def test_monochromatic_scenes_never_solve_N_with_auto(document: dict) -> None:
    # Not float16-quantised: below 6.1e-5 float16 is subnormal, with up to 50% rounding error,
    # and the chart is then no longer rank 1 in its data (the finiteness test covers it).
    try:
        _, s = _solve(document, "auto")
    except InputError as error:
        assert EXPECTED_ERRORS.search(str(error)), str(error)
        return
    assert s.N is None
    assert s.diagnostics.model == "rank-1"


@SETTINGS
@given(scenes(quantise=False, clip=False), st.floats(-6, 6))
def test_invariant_to_the_exposure_of_the_calibration_plates(
    document: dict, log_scale: float
) -> None:
    """[SL] -> s[SL], [SRL]_j -> s[SRL]_j: M -> M/s, x_j unchanged (eq. 3), so Q, the model and
    every chart error are unchanged, N = (Q [SL])^-1 -> N/s and the offset -M b -> offset/s."""
    scale = 10.0**log_scale
    scaled = json.loads(json.dumps(document))
    for c in CHANNELS:
        scaled["primaries"][c] = (np.asarray(document["primaries"][c]) * scale).tolist()
        scaled["lit_chart"][c] = (np.asarray(document["lit_chart"][c]) * scale).tolist()
    try:
        _, s = _solve(document, "auto")
    except InputError:
        return
    peaks = [max(np.abs(scaled[k][c]).max() for c in CHANNELS) for k in ("primaries", "lit_chart")]
    if min(peaks) < MIN_SIGNAL or max(peaks) > MAX_CAMERA_VALUE:
        # Scaled out of the range a camera reading can have: refused, not solved.
        with pytest.raises(InputError, match=r"scaled|expected a number"):
            _solve(scaled, "auto")
        return
    _, t = _solve(scaled, "auto")
    # Relative rounding of each solve grows with cond([SL]) (M) and cond(Q) (N).
    rtol = 1e-13 * s.diagnostics.cond_SL * max(1.0, min(s.diagnostics.cond_Q, 1e3))
    rtol = max(rtol, 1e-10)
    assert t.diagnostics.model == s.diagnostics.model
    np.testing.assert_allclose(t.M * scale, s.M, rtol=rtol, atol=rtol * np.abs(s.M).max())
    np.testing.assert_allclose(t.Q, s.Q, rtol=rtol, atol=rtol)
    assert (t.N is None) == (s.N is None)
    if s.N is not None:
        np.testing.assert_allclose(t.N * scale, s.N, rtol=rtol, atol=rtol * np.abs(s.N).max())
    np.testing.assert_allclose(
        t.diagnostics.lit_chart_error, s.diagnostics.lit_chart_error, rtol=rtol, atol=1e-12
    )


@SETTINGS
@given(scenes(quantise=False, clip=False), st.floats(-6, 6))
def test_invariant_to_the_exposure_of_the_target_chart(document: dict, log_scale: float) -> None:
    """p_j -> t p_j and w_avg -> t w_avg: x_j -> t x_j, so Q, M, N and the model are unchanged."""
    scale = 10.0**log_scale
    scaled = json.loads(json.dumps(document))
    env = scaled["environments"][0]
    for key in ("target_chart", "w_avg", "black_level"):
        if key in env:
            env[key] = (np.asarray(env[key]) * scale).tolist()
    try:
        _, s = _solve(document, "auto")
    except InputError:
        return
    values = [np.abs(env[k]).max() for k in ("target_chart", "w_avg", "black_level") if k in env]
    if max(values) > MAX_CAMERA_VALUE or 0 < np.abs(env["target_chart"]).max() < MIN_SIGNAL:
        # Scaled out of the range a camera reading can have: refused, not solved.
        with pytest.raises(InputError, match=r"expected a number <=|is the data scaled"):
            _solve(scaled, "auto")
        return
    _, t = _solve(scaled, "auto")
    rtol = max(1e-13 * s.diagnostics.cond_SL, 1e-10)
    assert t.diagnostics.model == s.diagnostics.model
    np.testing.assert_allclose(t.Q, s.Q, rtol=rtol, atol=rtol)
    np.testing.assert_array_equal(t.M, s.M)
    if s.N is not None:
        np.testing.assert_allclose(t.N, s.N, rtol=rtol, atol=rtol * np.abs(s.N).max())


@settings(max_examples=15, deadline=None)
@given(
    scenes(quantise=False, clip=False),
    st.sampled_from([float("nan"), float("inf"), -float("inf")]),
    st.sampled_from(["primaries", "lit_chart", "target_chart"]),
)
def test_non_finite_measurements_are_rejected_with_a_clear_message(document, bad, where) -> None:
    if where == "primaries":
        document["primaries"]["green"][1] = bad
    elif where == "lit_chart":
        document["lit_chart"]["blue"][5][2] = bad
    else:
        document["environments"][0]["target_chart"][3][0] = bad
    with pytest.raises(InputError, match="expected a finite number") as info:
        measurements_from_dict(document, source="bad.yaml")
    assert "bad.yaml" in str(info.value) and where in str(info.value)


@SETTINGS
@given(scenes(quantise=False, clip=False), st.sampled_from(["duplicate", "dark", "zero"]))
def test_singular_primaries_give_the_clear_error(document: dict, how: str) -> None:
    primaries = document["primaries"]
    if how == "duplicate":  # two primaries look alike to the camera
        primaries["green"] = list(primaries["red"])
    elif how == "dark":  # an LED channel far darker than cond 1e10 allows
        primaries["blue"] = [v * 1e-12 for v in primaries["blue"]]
    else:
        primaries["red"] = [0.0, 0.0, 0.0]
    with pytest.raises(InputError, match=r"\[SL\] is singular") as info:
        _solve(document, "auto")
    assert "primaries" in str(info.value)


@SETTINGS
@given(scenes(quantise=False, clip=False), st.sampled_from(sorted(CLOSED_FORM_METHODS)))
def test_a_degenerate_lit_chart_never_crashes(document: dict, method: str) -> None:
    # Every patch lit identically: the x_j span one direction, Q is underdetermined.
    for c in CHANNELS:
        first = document["lit_chart"][c][0]
        document["lit_chart"][c] = [list(first) for _ in document["lit_chart"][c]]
    try:
        _, s = _solve(document, method)
    except InputError as error:
        assert EXPECTED_ERRORS.search(str(error)), str(error)
        return
    _finite_tree(json.loads(solution_to_json(s)))
    if s.N is not None:
        error = np.max(np.abs(s.Q @ s.SL @ s.N - np.eye(3)))
        assert error <= s.diagnostics.identity_check.bound


def test_a_black_target_chart_is_an_input_error() -> None:
    document = make_measurements_dict(environments=1)
    document["environments"][0]["target_chart"] = [[0.0, 0.0, 0.0]] * 24
    document["environments"][0]["w_avg"] = [0.5, 0.5, 0.5]
    with pytest.raises(InputError, match="black") as info:
        _solve(document, "auto")
    assert str(info.value).startswith("generated.yaml: environments[0].target_chart: ")


def _diagonal_stage_document() -> tuple[dict, np.ndarray, np.ndarray]:
    """A stage whose camera sees each LED in one channel only ([SL] = diag(2, 4, 5)), a chart
    whose patches reflect per channel (a_j), beta 0.5 and w_avg given: every number of the solve
    has a closed form. The target is the lit chart times g = (1.1, 1.0, 0.8)."""
    j = np.arange(24.0)
    a = np.stack([0.1 + 0.03 * j, 0.2 + 0.02 * j, 0.5 - 0.015 * j], axis=1)
    a[18] = 0.9
    s = np.array([2.0, 4.0, 5.0])
    w_avg = np.array([0.4, 0.5, 0.6])
    g = np.array([1.1, 1.0, 0.8])
    lit = a * w_avg / 0.5  # eq. 3: (1/beta) [SRL]_j M w_avg, with [SRL]_j M = diag(a_j)
    document = {
        "format": "ocio-vp/measurements",
        "version": 1,
        "stage": {"name": "diagonal", "beta": 0.5},
        "primaries": {c: (s[k] * np.eye(3)[k]).tolist() for k, c in enumerate(CHANNELS)},
        "lit_chart": {
            c: (a[:, k, None] * s[k] * np.eye(3)[k]).tolist() for k, c in enumerate(CHANNELS)
        },
        "environments": [
            {"name": "env", "w_avg": w_avg.tolist(), "target_chart": (lit * g).tolist()}
        ],
    }
    return document, a, g


def test_a_diagonal_stage_by_hand() -> None:
    document, a, g = _diagonal_stage_document()
    m = measurements_from_dict(document, source="diagonal.yaml")
    s = solve_environment(m, m.environments[0], method="least-squares")
    d = s.diagnostics
    np.testing.assert_allclose(s.M, np.diag([0.5, 0.25, 0.2]), rtol=1e-15)
    np.testing.assert_allclose(s.Q, np.diag(g), atol=1e-13)
    np.testing.assert_allclose(s.N, np.diag([0.5 / 1.1, 0.25, 0.25]), atol=1e-13)
    np.testing.assert_allclose(d.charts.lit_baseline, a * [0.8, 1.0, 1.2], rtol=1e-14)
    # Fig. 11 error of M alone: |1 - g| / g times the mean reflectance over the white's 0.9.
    by_hand = np.abs(1 - g) / g * a.mean(axis=0) / 0.9
    np.testing.assert_allclose(d.lit_chart_error_baseline, by_hand, rtol=1e-12)
    np.testing.assert_allclose(d.lit_chart_error, 0.0, atol=1e-13)
    # In-frustum (eq. 7): Q [SL] N p = p, so the background is exact after Q; shown through
    # M instead it would be off by |g - 1| p.
    np.testing.assert_allclose(d.displayed_chart_error_baseline, 0.0, atol=1e-13)
    np.testing.assert_allclose(d.displayed_chart_error, 0.0, atol=1e-13)
    np.testing.assert_allclose(d.charts.displayed_corrected, d.charts.target, atol=1e-13)
