"""Shared fixtures. Test data is made here from closed forms or colour-science datasets."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.cli import _defer_colour_plotting

# As every ``ocio-vp`` command does (ocio_vp.cli.main): colour-science's own import of
# colour.plotting, and with it matplotlib's pyplot, waits until something reads an attribute
# of colour.plotting (nothing here plots with it).
_defer_colour_plotting()

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


def _gauge_by_bisection(c: np.ndarray, hull: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The domain's gauge computed another way: the scale lambda at which ``centre + (c -
    centre) / lambda`` leaves the polygon, by bisection on matplotlib's point-in-polygon test
    (not the half-plane formula of ocio_vp.model)."""
    from matplotlib.path import Path

    polygon = Path(np.vstack([hull, hull[:1]]))
    low, high = np.full(len(c), 1e-6), np.full(len(c), 1e6)
    for _ in range(90):
        mid = np.sqrt(low * high)
        inside = polygon.contains_points(centre + (c - centre) / mid[:, None])
        low, high = np.where(inside, low, mid), np.where(inside, mid, high)
    return high


def _fade_out(t: np.ndarray) -> np.ndarray:
    t = np.clip(t, 0.0, 1.0)
    return 1.0 - (3 * t * t - 2 * t**3)


def oracle_correction(block: dict, rgb) -> np.ndarray:
    """solution.json's ``post_correction`` block applied by an independent implementation:
    colour-science's root-polynomial expansion, the domain gauge by bisection
    (:func:`_gauge_by_bisection`), the fades written out here. For the tests of every host."""
    from colour.characterisation import polynomial_expansion_Finlayson2015

    x = np.asarray(rgb, dtype=np.float64).reshape(-1, 3)
    kind, p, domain = block["kind"], block["parameters"], block["domain"]
    if kind in ("matrix", "rank-deficient"):
        return (x @ np.asarray(p["Q"]).T).reshape(np.shape(rgb))
    if kind == "protected":
        inner = oracle_correction({**p["inner"], "domain": domain}, x)
        u = x @ np.asarray(domain["to_drive"]).T
        d = x @ np.asarray(p["drive_matrix"]).T
        # the floor: dark times the largest drive channel of the colour whose drive relative
        # to a perfect white is 1 in every channel (least squares: it is exact here)
        white, *_ = np.linalg.lstsq(np.asarray(domain["to_drive"]), np.ones(3), rcond=None)
        floor = p.get("dark", 0.0) * max(float(np.max(np.asarray(p["drive_matrix"]) @ white)), 0)
        v, top = u.max(axis=1), np.maximum(d.max(axis=1), floor)
        (b0, b1), (n0, n1) = p["bright"], p["negative"]
        with np.errstate(divide="ignore", invalid="ignore"):
            g_bright = np.where(v > 0, _fade_out(np.log2(v / b0) / np.log2(b1 / b0)), 1.0)
            g_negative = _fade_out((-d.min(axis=1) / top - n0) / (n1 - n0))
        g = np.where(top > 0, g_bright * g_negative, 0.0)[:, None]
        return (x + g * (inner - x)).reshape(np.shape(rgb))
    C = np.asarray(p["coefficients"])
    terms = polynomial_expansion_Finlayson2015(x, p["degree"], root_polynomial_expansion=True)
    polynomial = np.asarray(terms).reshape(len(x), -1) @ C.T
    linear = x @ np.asarray(p["fallback"]).T
    if domain is None:
        return polynomial.reshape(np.shape(rgb))
    u = x @ np.asarray(domain["to_drive"]).T
    total = u.sum(axis=1)
    c = np.stack([u[:, 0], u[:, 2]], -1) / np.where(total > 0, total, 1.0)[:, None]
    gauge = _gauge_by_bisection(c, np.asarray(domain["hull"]), np.asarray(domain["centre"]))
    start, end = p["fade"]
    w = np.where(total > 0, _fade_out((gauge - start) / (end - start)), 0.0)[:, None]
    return (linear + w * (polynomial - linear)).reshape(np.shape(rgb))


def panel_stage_measurements(environments=("overcast", "interior"), **options):
    """A simulated stage of two panel types (paper-like wall, a ceiling of another panel
    model: ocio_vp.simulator.panels) and its exact measurements."""
    from ocio_vp.simulator.panels import panel_stage, simulate_panel_measurements
    from ocio_vp.simulator.stage import paper_stage

    stage = panel_stage(paper_stage(), **options)
    return stage, simulate_panel_measurements(stage, environments)


@pytest.fixture(scope="session")
def panel_stage_and_measurements():
    return panel_stage_measurements()


@pytest.fixture(scope="session", autouse=True)
def _writing_in_this_process():
    """``ocio-vp solve`` and ``demo`` called in-process (``ocio_vp.cli.main``) write every
    environment in this process instead of starting a helper process for each call.

    The helper is a fresh "spawn" interpreter per call, whose imports cost far more than the
    small solves of this suite, made in-process about a hundred times. What it
    writes is the same bytes (tests/test_ocio_writer.py compares both ways, byte for byte, and
    its failures), and every ``ocio-vp`` run in a subprocess (the CLI tests of exit codes,
    signals, FIFOs, concurrent runs) still starts it. A test marked ``writer_helper`` gets the
    real helper back (:func:`_writer_helper_when_marked`)."""
    import contextlib

    from ocio_vp.ocio import writer

    @contextlib.contextmanager
    def no_helper(method=None, *, protect_emitters=False, environments=None):
        yield None

    real = writer.writer_pool
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(writer, "writer_pool", no_helper)
        yield real


@pytest.fixture(autouse=True)
def _writer_helper_when_marked(request, _writing_in_this_process):
    """The real writing helper for tests marked ``writer_helper`` (see above)."""
    if request.node.get_closest_marker("writer_helper") is None:
        yield
        return
    from ocio_vp.ocio import writer

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(writer, "writer_pool", _writing_in_this_process)
        yield
