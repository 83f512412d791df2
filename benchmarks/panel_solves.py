"""Solved and exported stages of several panel types, for ``benchmarks.ocio_compat --solves``.

``python -m benchmarks.panel_solves OUT`` writes, from the simulated stage whose ceiling is
another panel model (:mod:`ocio_vp.simulator.panels`, its five scenes):

- ``OUT/three_types``: a wall, an in-frustum floor (the second model's LEDs) and an
  out-of-frustum ceiling with its own linearity ramps (a non-linear response, so a LUT) and a
  PQ signal of its own (1500 nits), solved by least squares;
- ``OUT/gamma``: the wall and the ceiling, least squares, ``--wall-encoding gamma2.4``;

each exported for every target. Then ``python -m benchmarks.ocio_compat --solves
OUT/three_types OUT/gamma`` loads every config in OpenColorIO 2.2 to 2.6 (docs/panels.md).
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np

DARK = (0.3, 0.15, 0.35)  # how dark each of the ceiling's channels is near black


def ceiling_response(d: np.ndarray, k: int) -> np.ndarray:
    """The ceiling's (non-linear) response to drive ``d`` in channel ``k``."""
    return d * (1 - DARK[k] * np.exp(-d / 0.05)) / (1 - DARK[k] * np.exp(-1 / 0.05))


def three_types(m):
    """The two-type measurements with a floor in frustum and a ceiling with ramps and PQ."""
    from ocio_vp.wall.linearity import parse_ramps

    wall, other = m.panels
    drive = np.linspace(0.0, 1.0, 33)
    ramps = parse_ramps(
        {
            c: {"drive": drive.tolist(),
                "camera": np.outer(ceiling_response(drive, k), other.SL[:, k]).tolist()}
            for k, c in enumerate(("red", "green", "blue"))
        }
    )  # fmt: skip
    ceiling = dataclasses.replace(other, ramps=ramps, encoding="pq", peak_nits=1500.0, regions=())
    floor = dataclasses.replace(other, name="floor", in_frustum=True, regions=())
    envs = []
    for e in m.environments:
        w_avg = {**e.panel_w_avg, "floor": 0.1 * e.panel_w_avg["wall"]}
        black = {"wall": e.panel_black_level["wall"], "floor": e.panel_black_level["wall"]}
        envs.append(dataclasses.replace(e, panel_w_avg=w_avg, panel_black_level=black))
    return dataclasses.replace(m, panels=(wall, floor, ceiling), environments=tuple(envs))


def main(argv: list[str] | None = None) -> int:
    from ocio_vp.cli import main as cli
    from ocio_vp.formats.measurements import save_measurements
    from ocio_vp.simulator.panels import panel_stage, simulate_panel_measurements
    from ocio_vp.simulator.stage import paper_stage

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m benchmarks.panel_solves OUT", file=sys.stderr)
        return 2
    out = Path(args[0])
    out.mkdir(parents=True, exist_ok=True)
    m = simulate_panel_measurements(panel_stage(paper_stage()))
    save_measurements(three_types(m), out / "three_types.yaml", replace=True)
    save_measurements(m, out / "two_types.yaml", replace=True)
    runs = [
        ["solve", str(out / "three_types.yaml"), "--out", str(out / "three_types"),
         "--method", "least-squares"],
        ["solve", str(out / "two_types.yaml"), "--out", str(out / "gamma"),
         "--method", "least-squares", "--wall-encoding", "gamma2.4"],
        ["export", str(out / "three_types"), str(out / "gamma"), "--target", "all"],
    ]  # fmt: skip
    for run in runs:
        if cli(run) != 0:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
