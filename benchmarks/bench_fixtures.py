"""Practical fixtures beside the wall: held-out colour rendition with and without them.

For every simulated environment, fixture kind (none, ``rgbw``, ``rgbww``, ``rgbacl``,
``rgbw-fluorescent``: :mod:`ocio_vp.simulator.fixtures`), noise level and seed: the stage's
measurements with that fixture are simulated, every photographed value (fixture charts too)
gets multiplicative Gaussian noise (:func:`ocio_vp.simulator.truth.noisy_measurements`), and
the product's own solve (:func:`ocio_vp.pipeline.solve_environment`, Q by least squares, the
paper's eq. 5) drives the fixtures with the wall. The result is judged on reflectances that
are not on the chart (the 190 RAW to ACES training samples), lit by what the stage really
emits (the wall's drive clipped at 0 through its true LEDs, plus each fixture spectrum times
its solved drive), against the same samples under the real light: mean and 95th-percentile
ΔE2000 (:func:`ocio_vp.simulator.truth.held_out_errors`). Also checked per solve: every drive
within [0, max], the light's white within the joint method's 2 ΔE2000, and the solve time.

Run alone: ``python -m benchmarks.bench_fixtures [--quick]``; by ``python -m benchmarks.run``
it writes ``docs/fixtures_benchmark.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict

import numpy as np

from benchmarks import markdown_table

#: ``benchmarks.run`` writes this module's section to docs/<DOC>.
DOC = "fixtures_benchmark.md"
KINDS = ("wall only", "rgbw", "rgbww", "rgbacl", "rgbw-fluorescent")
METHOD = "least-squares"


def _solve_and_judge(stage, measurements, env_name, kind, noise, seed, reflectances):
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.fixtures import fixture_spectra
    from ocio_vp.simulator.truth import held_out_errors, noisy_measurements

    rng = np.random.default_rng(seed)
    noisy = noisy_measurements(measurements, noise, rng)
    start = time.perf_counter()
    solution = solve_environment(noisy, noisy.environment(env_name), method=METHOD)
    seconds = time.perf_counter() - start
    extra, drives_ok, white_ok = None, True, True
    if solution.fixtures:
        block = solution.fixtures[kind.replace("-", "_")]
        drives = np.array(block.drives)
        extra = fixture_spectra(stage, kind)[1] @ drives
        notes = solution.diagnostics.fixtures
        drives_ok = bool(np.all(drives >= 0) and np.all(drives <= block.max_drive + 1e-9))
        white_ok = notes.limits.get("white_point_delta_e", 0.0) <= 2.0 + 1e-6
    errors = held_out_errors(
        stage, env_name, M=solution.M, w_avg=solution.w_avg, Q=solution.Q,
        reflectances=reflectances, extra_emission=extra,
    ).delta_E_2000  # fmt: skip
    return errors, seconds, drives_ok and white_ok


def measure(quick: bool):
    from ocio_vp.simulator.data import ENVIRONMENTS, PAPER_ENVIRONMENTS
    from ocio_vp.simulator.fixtures import with_simulated_fixtures
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements
    from ocio_vp.simulator.truth import held_out_reflectances

    stage = paper_stage()
    names = PAPER_ENVIRONMENTS if quick else tuple(ENVIRONMENTS)
    noises, seeds = ((0.005,), 1) if quick else ((0.005, 0.01), 3)
    reflectances = held_out_reflectances()["rawtoaces"]
    base = simulate_measurements(names, stage=stage)
    de, seconds, ok = defaultdict(list), defaultdict(list), defaultdict(bool)
    for kind in KINDS:
        m = base if kind == "wall only" else with_simulated_fixtures(base, stage, [kind])
        for name in names:
            for noise in noises:
                for seed in range(seeds):
                    e, s, fine = _solve_and_judge(stage, m, name, kind, noise, seed, reflectances)
                    de[(kind, name)].append(e)
                    seconds[kind].append(s)
                    ok[kind] = ok.get(kind, True) and fine
    return names, noises, seeds, de, seconds, ok


def report(quick: bool) -> str:
    from ocio_vp.simulator.data import ENVIRONMENTS

    names, noises, seeds, de, seconds, ok = measure(quick)
    rows, gains = [], defaultdict(list)
    for name in names:
        wall = np.concatenate(de[("wall only", name)])
        row = [name, "yes" if ENVIRONMENTS[name].broadband else "no", f"{wall.mean():.2f}"]
        for kind in KINDS[1:]:
            values = np.concatenate(de[(kind, name)])
            change = values.mean() / wall.mean() - 1
            row.append(f"{values.mean():.2f} ({100 * change:+.0f}%)")
            if ENVIRONMENTS[name].broadband:
                gains[kind].append(change)
        rows.append(row)
    header = ["environment", "broadband", "wall only", *KINDS[1:]]
    summary = [
        [kind, f"{100 * np.mean(gains[kind]):+.0f}%", f"{100 * np.max(gains[kind]):+.0f}%",
         "yes" if ok[kind] else "NO", f"{np.median(seconds[kind]):.2f}", f"{np.max(seconds[kind]):.2f}"]
        for kind in KINDS[1:]
    ]  # fmt: skip
    return "\n\n".join(
        [
            "# Practical fixtures: held-out colour rendition",
            "Generated by `python -m benchmarks.bench_fixtures"
            + (" --quick" if quick else "")
            + "` (also by `python -m benchmarks.run`). Method in docs/fixtures.md; "
            f"Q by {METHOD}, noise {', '.join(f'{100 * n:g}%' for n in noises)}, "
            f"{seeds} seed(s), the paper-like simulated stage, 190 held-out reflectances.",
            "## Mean ΔE2000 after Q per environment (change against the wall alone)",
            markdown_table(header, rows),
            "## Broadband environments, and the limits",
            markdown_table(
                [
                    "fixture",
                    "mean change",
                    "worst change",
                    "drives in [0, max], white <= 2 ΔE",
                    "median solve s",
                    "max solve s",
                ],
                summary,
            ),
        ]
    )


def run(quick: bool = False) -> str:
    return report(quick)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    print(run(args.quick))
    return 0


if __name__ == "__main__":
    sys.exit(main())
