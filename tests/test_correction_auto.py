"""auto's candidate rules (ocio_vp.correction.auto) against hand-computed standard errors and the
product's own saturation probe."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.correction.auto import SHRUNK_SE_FACTOR, _choose, bounded_candidate
from ocio_vp.correction.extrapolation import MIN_NEGATIVE, MIN_RETAINED, saturation_probe
from ocio_vp.model.correction import MatrixCorrection
from ocio_vp.pipeline import post_correction_problem
from ocio_vp.simulator.stage import paper_stage_measurements


def _scores(gain_in_standard_errors: float) -> dict[str, np.ndarray]:
    """Least squares and a shrunk least squares better by the given number of standard errors
    of the paired differences (computed here: mean / (std / sqrt(n)))."""
    rng = np.random.default_rng(1)
    base = rng.uniform(2.0, 4.0, 24)
    wiggle = rng.normal(0.0, 1.0, 24)
    wiggle = (wiggle - wiggle.mean()) / wiggle.std(ddof=1)  # mean 0, sd 1: SE = 1 / sqrt(24)
    gain = gain_in_standard_errors / np.sqrt(24)
    return {"identity": base + 5.0, "regularised": base - gain + wiggle, "least-squares": base}


@pytest.mark.parametrize(("gain", "expected"), [(1.5, "least-squares"), (2.5, "regularised")])
def test_a_shrunk_least_squares_needs_its_own_standard_errors(gain, expected) -> None:
    assert SHRUNK_SE_FACTOR == 2.0
    chosen, table, note = _choose(_scores(gain))
    assert chosen == expected
    row = table["regularised"]
    assert row["difference"] == pytest.approx(-gain / np.sqrt(24))
    assert row["standard_error"] == pytest.approx(1 / np.sqrt(24))
    assert bool(note) == (expected == "least-squares")


def test_a_shrinkage_of_nothing_is_least_squares_and_stays_a_tie() -> None:
    scores = _scores(0.0)
    scores["regularised"] = scores["least-squares"].copy()
    chosen, _, note = _choose(scores)
    assert chosen == "regularised" and note == []  # the simplest of two equal models


def test_the_root_polynomial_is_judged_against_its_own_fallback() -> None:
    # High-pressure sodium on the sample stage: least squares itself flips a bright saturated
    # input there (the light, not the model); the bounded polynomial, no worse than it, stays a
    # candidate.
    m = paper_stage_measurements(["high_pressure_sodium"])
    problem = post_correction_problem(m, m.environments[0])
    fit, why = bounded_candidate(problem, "root-polynomial")
    assert why is None and fit is not None
    white = problem.predicted[problem.white_patch]
    kept, negative = saturation_probe(fit.correction, white)
    ls_kept, ls_negative = saturation_probe(MatrixCorrection(fit.correction.matrix), white)
    assert ls_kept < MIN_RETAINED or ls_negative < MIN_NEGATIVE
    assert kept >= min(MIN_RETAINED, ls_kept) and negative >= min(MIN_NEGATIVE, ls_negative)
