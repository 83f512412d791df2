"""What a post-correction does beyond the chart (``ocio_vp.correction.extrapolation``).

Independent checks: closed forms (a matrix folds nowhere; the identity keeps every channel and
damages no emitter; a map with a known fold region), and a finite-difference Jacobian computed
here for the fold count.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from conftest import paper_stage_problem

from ocio_vp.correction.extrapolation import (
    FADES,
    Extrapolation,
    choose_fade,
    fold_fraction,
    in_frame_led_damage,
    saturation_probe,
)
from ocio_vp.metrics import sample_camera_to_xyz
from ocio_vp.model import MatrixCorrection, RootPolynomialCorrection


@pytest.fixture(scope="module")
def problem():
    return paper_stage_problem("incandescent")


class _Folding:
    """u -> (u_r^2 - u_r / 2, u_g, u_b) in drive space: its Jacobian is negative for u_r < 1/4
    (a quarter of the reflective solid's red axis), positive above."""

    kind, linear, invertible = "test", False, True

    def __init__(self, domain):
        self.domain = domain
        self.matrix = np.eye(3)

    def apply(self, rgb):
        u = self.domain.drive(rgb)
        u = np.stack([u[..., 0] ** 2 - u[..., 0] / 2, u[..., 1], u[..., 2]], -1)
        return u @ np.linalg.inv(self.domain.to_drive).T


def test_fold_fraction_of_closed_forms(problem):
    domain = problem.domain
    assert fold_fraction(MatrixCorrection(np.diag([1.2, 0.9, 1.1])), domain) == 0.0
    # the quasi-random sample of the solid estimates the folded quarter closely
    assert fold_fraction(_Folding(domain), domain) == pytest.approx(0.25, abs=0.01)


def test_saturation_probe_of_the_identity_and_a_flipping_matrix(problem):
    white = problem.predicted[problem.white_patch]
    kept, negative = saturation_probe(MatrixCorrection(np.eye(3)), white)
    assert kept == pytest.approx(1.0) and negative == pytest.approx(0.01)
    flip = np.array([[1.0, 0.0, 0.0], [-3.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # green -= 3 red
    kept, negative = saturation_probe(MatrixCorrection(flip), white)
    # a red input (1, 0.01, 0.01) gives green 0.01 - 3: -2.99 of its red
    assert negative == pytest.approx(-2.99)


def test_a_collapsed_dominant_channel_is_written_finite(problem):
    # A rank-1 Q onto grey (what a sodium-lit solve gives): a red input (1, 0.01, 0.01) comes
    # out as 0.34 of its red in every channel; a Q that negates green sends a green input to
    # -1 of it: no "lowest channel relative to the dominant one" exists there (it was -inf,
    # written into solution.json as the string "-inf" and shown as "-inf%").
    rank1 = np.full((3, 3), 1.0 / 3.0)
    negate_green = np.diag([1.0, -1.0, 1.0])
    white = problem.predicted[problem.white_patch]
    assert saturation_probe(MatrixCorrection(rank1), white)[0] == pytest.approx(1.02 / 3)
    kept, negative = saturation_probe(MatrixCorrection(negate_green), white)
    assert kept == pytest.approx(-1.0) and negative == -np.inf
    figures = Extrapolation(1.0, 1.0, kept=kept, negative=negative, folds=0.0)
    assert figures.negative is None and figures.flips_or_collapses
    json.dumps(dataclasses.asdict(figures), allow_nan=False)
    assert "the channel itself at or below zero" in figures.describe()
    assert "inf" not in figures.describe()


def test_the_identity_damages_no_in_frame_led(problem):
    xyz = sample_camera_to_xyz()
    white = problem.target[problem.white_patch]
    assert in_frame_led_damage(MatrixCorrection(np.eye(3)), problem.SL, white, xyz) == 0.0
    gain = in_frame_led_damage(MatrixCorrection(np.diag([1.3, 1.0, 1.0])), problem.SL, white, xyz)
    assert gain > 1.0


def test_choose_fade_takes_the_first_that_folds_nowhere(problem):
    from ocio_vp.correction.problem import fit_least_squares
    from ocio_vp.correction.root_polynomial import fit_root_polynomial

    X, P, w = problem.predicted, problem.target, problem.fit_weights
    C, A = fit_root_polynomial(X, P, w, 2), fit_least_squares(X, P, w)
    fade, tried = choose_fade(C, A, problem.domain)
    assert fade in FADES
    chosen = list(tried).index(f"{fade[0]:g}-{fade[1]:g}")
    assert all(v > 0 for v in list(tried.values())[:chosen]) and tried[list(tried)[chosen]] == 0
    assert fold_fraction(RootPolynomialCorrection(C, A, problem.domain, fade), problem.domain) == 0


def test_choose_fade_measures_each_fade_as_fold_fraction_does(problem):
    """The fades share the solid's points, fallback, gauge and polynomial: each fade's figure is
    still exactly its own correction's :func:`fold_fraction`, and a root-polynomial fit carries
    its chosen fade's, which the solve's extrapolation diagnostics read instead of measuring."""
    from ocio_vp.correction.problem import fit_least_squares
    from ocio_vp.correction.root_polynomial import fit_root_polynomial, q_root_polynomial

    X, P, w = problem.predicted, problem.target, problem.fit_weights
    C, A = fit_root_polynomial(X, P, w, 2), fit_least_squares(X, P, w)
    fade, tried = choose_fade(C, A, problem.domain)
    assert len(tried) >= 2  # more than one fade tried: the shared parts are reused
    for f in FADES[: len(tried)]:
        alone = fold_fraction(RootPolynomialCorrection(C, A, problem.domain, f), problem.domain)
        assert tried[f"{f[0]:g}-{f[1]:g}"] == alone
    fit = q_root_polynomial(problem)
    assert fit.folds is not None
    assert fit.folds.of(fit.correction, problem.domain) == fold_fraction(
        fit.correction, problem.domain
    )
    # only for that correction over that domain: another one is measured anew
    assert fit.folds.of(dataclasses.replace(fit.correction), problem.domain) is None
    assert fit.folds.of(fit.correction, dataclasses.replace(problem.domain)) is None
