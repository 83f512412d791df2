"""The per-pixel functions footage is corrected with: the model's own formulas, rearranged, in
float64 and float32, against the tests' independent implementation of the model."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.model import (
    MatrixCorrection,
    ProtectedCorrection,
    RootPolynomialCorrection,
    correction_to_dict,
    fit_domain,
)
from ocio_vp.model.pixels import pixel_function
from tests.conftest import oracle_correction

SL = np.array([[0.9, 0.12, 0.02], [0.2, 0.8, 0.1], [0.01, 0.1, 0.9]])


def _corrections() -> dict[str, object]:
    rng = np.random.default_rng(5)
    rho = rng.uniform(0.05, 0.9, (24, 3))
    rho[18] = 0.9
    M = np.linalg.inv(SL)
    domain = fit_domain(rho @ SL.T, M=M, white_patch=18, white_reflectance=0.9)
    fallback = np.eye(3) + 0.05 * rng.standard_normal((3, 3))
    out = {}
    for degree, terms in ((2, 6), (3, 13)):
        C = np.hstack([fallback, 0.03 * rng.standard_normal((3, terms - 3))])
        out[f"root-polynomial {degree}"] = RootPolynomialCorrection(C, fallback, domain)
    out["unbounded"] = RootPolynomialCorrection(C[:, :6], fallback, None)
    rp = out["root-polynomial 2"]
    out["protected"] = ProtectedCorrection(rp, domain, M, dark=2.0**-5)
    out["protected matrix"] = ProtectedCorrection(MatrixCorrection(fallback), domain, M)
    return out


def _footage(n: int = 3000) -> np.ndarray:
    """Reflective colours lit by the wall at 1/16-16x, saturated and negative ones, emitters
    (one LED channel alone), zeros and noise around black."""
    rng = np.random.default_rng(9)
    lit = rng.uniform(0.02, 1.0, (n, 3)) @ SL.T * 2.0 ** rng.uniform(-4, 4, (n, 1))
    wild = rng.uniform(-0.1, 3.0, (n, 3))
    emitters = np.kron(2.0 ** rng.uniform(-2, 3, (n // 10, 1)), np.eye(3)) @ SL.T
    black = np.vstack([np.zeros((5, 3)), 1e-4 * rng.standard_normal((200, 3))])
    return np.vstack([lit, wild, emitters, black])


@pytest.mark.parametrize("name", list(_corrections()))
def test_pixel_functions_are_the_model(name):
    """float64: the model's apply to 1e-12 and the independent oracle to 1e-9 (the oracle's
    gauge is a bisection); float32 (what half footage is computed in): within 2e-6 of each
    pixel's largest channel, and finite wherever the model is."""
    correction = _corrections()[name]
    x = _footage()
    reference = correction.apply(x)
    scale = np.maximum(np.abs(reference).max(axis=1, keepdims=True), 1e-6)
    oracle = oracle_correction(correction_to_dict(correction), x)
    assert np.all(np.abs(oracle - reference) <= 1e-9 * scale)
    planes = np.ascontiguousarray(x.T)
    got64 = pixel_function(correction, np.float64)(planes).T
    assert np.all(np.abs(got64 - reference) <= 1e-12 * scale)
    got32 = pixel_function(correction, np.float32)(planes.astype(np.float32)).T
    assert got32.dtype == np.float32 and np.all(np.isfinite(got32))
    assert np.all(np.abs(got32 - reference) <= 2e-6 * scale)
    assert np.array_equal(planes, np.ascontiguousarray(x.T))  # the input is kept
