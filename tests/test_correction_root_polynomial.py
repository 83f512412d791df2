"""The ``root-polynomial`` Q-solve and its exact inverse.

Independent checks: colour-science's own root-polynomial regression
(:func:`colour.characterisation.matrix_colour_correction_Finlayson2015`,
:func:`colour.characterisation.colour_correction_Finlayson2015`) is the oracle for the fit;
homogeneity (``Q(k x) = k Q(x)``) and ``Q(Q^-1(c)) = c`` are checked by evaluating the forward
model, never the quantities the solver itself reports.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from colour.characterisation import (
    colour_correction_Finlayson2015,
    matrix_colour_correction_Finlayson2015,
)
from conftest import paper_stage_problem

from ocio_vp.correction import (
    Q_SOLVE_METHODS,
    ROOT_POLYNOMIAL_TERMS,
    apply_root_polynomial,
    fit_least_squares,
    fit_root_polynomial,
    invert_root_polynomial,
    root_polynomial_expansion,
    root_polynomial_jacobian,
    root_polynomial_loo_predictions,
    solve_post_correction,
)
from ocio_vp.correction.problem import QProblem
from ocio_vp.errors import InputError


@pytest.fixture(scope="module", params=["incandescent", "indoor_daylight"])
def problem(request) -> QProblem:
    return paper_stage_problem(request.param)


@pytest.mark.parametrize("degree", [2, 3])
def test_fit_matches_colour_science(problem, degree):
    X, P = problem.predicted, problem.target
    C = fit_root_polynomial(X, P, np.ones(len(X)), degree)
    oracle = matrix_colour_correction_Finlayson2015(X, P, degree, root_polynomial_expansion=True)
    np.testing.assert_allclose(C, oracle, rtol=1e-7, atol=1e-9)
    rgb = np.random.default_rng(1).uniform(0, 1, (50, 3))
    np.testing.assert_allclose(
        apply_root_polynomial(C, rgb),
        colour_correction_Finlayson2015(rgb, X, P, degree, root_polynomial_expansion=True),
        rtol=1e-7,
        atol=1e-10,
    )


def test_zero_weight_patches_are_left_out(problem):
    X, P = problem.predicted, problem.target
    w = np.ones(len(X))
    w[[2, 7, 11]] = 0.0
    keep = w > 0
    P_bad = P.copy()
    P_bad[~keep] = 100.0  # excluded patches must not matter
    C = fit_root_polynomial(X, P_bad, w, 2)
    oracle = matrix_colour_correction_Finlayson2015(X[keep], P[keep], 2)
    np.testing.assert_allclose(C, oracle, rtol=1e-7, atol=1e-9)


def test_registry_method_keeps_a_3x3_and_carries_the_model(problem):
    fit = solve_post_correction(problem, method="root-polynomial")
    X, P, w = problem.predicted, problem.target, problem.fit_weights
    np.testing.assert_allclose(fit.Q, fit_least_squares(X, P, w), rtol=1e-12)
    model = fit.correction
    assert model.kind == "root-polynomial" and model.degree == 2
    np.testing.assert_allclose(
        model.coefficients, matrix_colour_correction_Finlayson2015(X, P, 2), rtol=1e-7, atol=1e-9
    )
    assert np.all(np.isfinite(fit.cross_validated_error))
    # Inside the chart's domain (weight 1: the greys at least) it is the polynomial itself.
    inside = model.weight(X) == 1.0
    assert inside[18:].all() and np.all(model.weight(X) > 0)
    np.testing.assert_allclose(
        model.apply(X[inside]), apply_root_polynomial(model.coefficients, X[inside])
    )
    assert "root-polynomial-3" in Q_SOLVE_METHODS
    # The non-linear model fits the chart at least as well as its own 3x3 part can.
    assert np.sum((model.apply(X) - P) ** 2) < np.sum((X @ fit.Q.T - P) ** 2)


@pytest.mark.parametrize("scale", [1e-4, 1e-2, 1e2, 1e4])
def test_exposure_invariance(problem, scale):
    """Fit and apply at any exposure: the same corrected chromaticities (~1e-9 relative)."""
    fit = solve_post_correction(problem, method="root-polynomial")
    scaled = dataclasses.replace(problem, target=problem.target * scale, SRL=problem.SRL * scale)
    fit_s = solve_post_correction(scaled, method="root-polynomial")
    X = problem.predicted
    a = fit.correction.apply(X)
    b = fit_s.correction.apply(X * scale)
    np.testing.assert_allclose(b / scale, a, rtol=1e-9, atol=1e-12 * np.abs(a).max())


def test_guards_name_the_key(problem):
    few = np.zeros(len(problem.target))
    few[:5] = 1.0
    with pytest.raises(InputError, match=r"6 terms .* only 5") as info:
        solve_post_correction(dataclasses.replace(problem, weights=few), method="root-polynomial")
    assert info.value.key == "--method"
    grey = np.tile([[0.2, 0.2, 0.2]], (24, 1)) * np.linspace(1, 2, 24)[:, None]
    with pytest.raises(InputError, match="rank-deficient"):
        fit_root_polynomial(grey, grey, np.ones(24), 2)


def _fitted(problem, degree=2):
    return fit_root_polynomial(problem.predicted, problem.target, problem.fit_weights, degree)


def _in_gamut(problem, n, rng):
    """Colours inside the target chart's gamut: positive mixtures of its patches, any exposure."""
    mix = rng.dirichlet(np.full(len(problem.target), 0.3), n)
    return (mix @ problem.target) * rng.uniform(0.01, 16, (n, 1))


def test_inverse_round_trip_in_gamut(problem):
    C = _fitted(problem)
    c = _in_gamut(problem, 5000, np.random.default_rng(2))
    x = invert_root_polynomial(C, c)
    np.testing.assert_allclose(apply_root_polynomial(C, x), c, rtol=1e-9, atol=0)


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1e6, 1e12])
def test_inverse_at_extreme_scales(problem, scale):
    C = _fitted(problem)
    c = _in_gamut(problem, 500, np.random.default_rng(3))
    x = invert_root_polynomial(C, c)
    x_s = invert_root_polynomial(C, c * scale)
    np.testing.assert_allclose(x_s / scale, x, rtol=1e-9)


def test_inverse_of_black_saturated_and_negative_is_defined(problem):
    C = _fitted(problem)
    rng = np.random.default_rng(4)
    special = np.vstack(
        [
            np.zeros(3),
            [1e-150, 0, 0],
            np.eye(3),
            np.eye(3) * 16,
            [[-1e-3, 0.5, 0.5], [-1, -1, -1], [16, -1, 16]],
            rng.uniform(-1, 16, (2000, 3)),
        ]
    )
    x, residual = invert_root_polynomial(C, special, return_residual=True)
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(residual))
    assert np.array_equal(x[0], np.zeros(3))
    # Where the iteration converged, it is a true inverse.
    ok = residual < 1e-12
    scale = np.abs(special[ok]).max(axis=1, keepdims=True)
    error = np.abs(apply_root_polynomial(C, x[ok]) - special[ok])
    assert np.all(error <= 1e-9 * scale)
    # The primaries (saturated content) and black converge; the fitted models do not reach
    # every colour of the RGB cube (saturated blue-cyan with little red has no preimage for
    # incandescent light: there the best iterate is returned, finite, with its residual).
    assert np.all(ok[:8])


def test_inverse_is_unique_on_the_content_range(problem):
    """Injectivity, sampled: preimages of in-gamut colours are found again from their images."""
    C = _fitted(problem)
    A = fit_least_squares(problem.predicted, problem.target, problem.fit_weights)
    x = _in_gamut(problem, 3000, np.random.default_rng(5)) @ np.linalg.inv(A).T
    np.testing.assert_allclose(
        invert_root_polynomial(C, apply_root_polynomial(C, x)), x, rtol=1e-8, atol=1e-12
    )


@pytest.mark.parametrize("degree", [1, 2, 3, 4])
def test_expansion_matches_colour_science(degree):
    """The hand-vectorised expansion is colour-science's, term for term, signs included."""
    from colour.characterisation import polynomial_expansion_Finlayson2015

    rng = np.random.default_rng(9)
    rgb = np.vstack([rng.uniform(-1, 16, (500, 3)), np.zeros((1, 3)), [[0, 1e-8, 1e4]]])
    oracle = polynomial_expansion_Finlayson2015(rgb, degree, root_polynomial_expansion=True)
    np.testing.assert_allclose(
        root_polynomial_expansion(rgb, degree), oracle, rtol=1e-14, atol=1e-14
    )


@pytest.mark.parametrize("degree", [2, 3, 4])
def test_analytic_jacobian_matches_finite_differences(degree):
    rng = np.random.default_rng(10)
    C = rng.normal(size=(3, ROOT_POLYNOMIAL_TERMS[degree]))
    x = rng.uniform(0.05, 2.0, (200, 3))
    h = 1e-6
    numeric = np.stack(
        [
            (apply_root_polynomial(C, x + h * e) - apply_root_polynomial(C, x - h * e)) / (2 * h)
            for e in np.eye(3)
        ],
        axis=-1,
    )
    np.testing.assert_allclose(root_polynomial_jacobian(C, x), numeric, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("degree", [2, 3])
def test_closed_form_leave_one_out_matches_refitting(problem, degree):
    X, P = problem.predicted, problem.target
    w = np.random.default_rng(11).uniform(0.5, 2.0, len(X))
    w[4] = 0.0
    held = root_polynomial_loo_predictions(X, P, w, degree)
    for j in range(len(X)):
        w_j = w.copy()
        w_j[j] = 0.0
        refit = apply_root_polynomial(fit_root_polynomial(X, P, w_j, degree), X[j])
        np.testing.assert_allclose(held[j], refit, rtol=1e-8, atol=1e-10)
