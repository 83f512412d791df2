"""Shared fixtures. Test data is made here from closed forms or colour-science datasets."""

from __future__ import annotations

import numpy as np
import pytest

CHANNELS = ("red", "green", "blue")


def make_measurements_dict(
    *, n: int = 24, seed: int = 0, environments: int = 2, black_level: bool = True
) -> dict:
    """A valid measurements document with random but plausible values (positive, well-conditioned)."""
    rng = np.random.default_rng(seed)
    SL = np.array([[0.9, 0.12, 0.02], [0.25, 0.8, 0.1], [0.02, 0.15, 0.85]])
    SRL = rng.uniform(0.02, 0.25, size=(n, 3, 3)) * SL[None]
    SRL[18] = 0.9 * 0.23946 * SL  # a near-perfect white patch
    envs = []
    for i in range(environments):
        target = rng.uniform(0.02, 0.8, size=(n, 3))
        target[18] = rng.uniform(0.6, 0.9, size=3)
        env = {"name": f"env_{i}", "target_chart": target.tolist()}
        if black_level:
            env["black_level"] = (0.04 * target[18]).tolist()
        envs.append(env)
    return {
        "format": "ocio-vp/measurements",
        "version": 1,
        "stage": {
            "name": "test-stage",
            "calibration_panel": {"width": 1.0, "height": 1.0, "distance": 1.0},
        },
        "primaries": {c: SL[:, k].tolist() for k, c in enumerate(CHANNELS)},
        "lit_chart": {c: SRL[:, :, k].tolist() for k, c in enumerate(CHANNELS)},
        "environments": envs,
    }


@pytest.fixture
def measurements_dict() -> dict:
    return make_measurements_dict()


def measurement_problem(m, env):
    """The Q problem of environment ``env`` of measurements ``m``, as the pipeline poses it,
    with a copy of the target (callers corrupt it in place)."""
    import dataclasses

    from ocio_vp.pipeline import post_correction_problem

    problem = post_correction_problem(m, env)
    return dataclasses.replace(problem, target=np.array(problem.target))


def paper_stage_problem(environment: str):
    """The Q problem of one environment of the simulated paper stage, as the pipeline poses it."""
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements((environment,))
    return measurement_problem(m, m.environments[0])
