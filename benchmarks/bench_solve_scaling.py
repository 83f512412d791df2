"""Q-solve time against the number of chart patches, every method, with held-out accuracy.

Charts with hundreds of patches are real (ColorChecker SG 140, IT8 288, custom skin charts). The
charts here are the simulated ColorChecker of the paper stage's incandescent environment plus
mixtures of its patches: a mixture of reflectances photographs, and is lit, as the same mixture
of the patches' values, so ``[SRL]_j`` and ``p_j`` of a mixture are those weighted sums (each
with 0.5% multiplicative noise, as a photograph has). The ColorChecker stays patches 0-23 (its
white is patch 18). Each method is timed once per size (the sizes take seconds, so noise is
small against the growth measured; one untimed warm-up solve first); a method whose solve took over :data:`BUDGET_S` seconds is
not run on larger charts. Accuracy: mean ΔE2000 of 200 mixtures that are in no fitted chart,
corrected by the fitted post-correction (the model itself for root-polynomial, not its 3x3
approximation; the simulated camera's XYZ matrix, as ``bench_qsolve``).
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks import fmt_ms, markdown_table

SIZES = (24, 140, 288, 500, 1000)
QUICK_SIZES = (24, 140)
#: A method is not run on larger charts after a solve that took longer than this.
BUDGET_S = 15.0


def _mixtures(rng, count: int, n_base: int) -> np.ndarray:
    """(count, n_base) non-negative weights summing to 1, each mixing 2-4 base patches."""
    weights = np.zeros((count, n_base))
    for row in weights:
        picks = rng.choice(n_base, size=rng.integers(2, 5), replace=False)
        row[picks] = rng.dirichlet(np.ones(len(picks)))
    return weights


def _charts(base_srl, base_target, n: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """The base chart plus ``n - 24`` noisy mixtures of it: (n, 3, 3) SRL and (n, 3) targets."""
    extra = _mixtures(rng, n - len(base_target), len(base_target))
    srl = np.concatenate([base_srl, np.einsum("kj,jab->kab", extra, base_srl)])
    target = np.concatenate([base_target, extra @ base_target])
    srl[24:] *= 1 + 0.005 * rng.standard_normal(srl[24:].shape)
    target[24:] *= 1 + 0.005 * rng.standard_normal(target[24:].shape)
    return srl, target


def run(quick: bool = False) -> str:
    """Markdown section: solve time per method and chart size, with held-out ΔE2000."""
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.metrics import camera_to_xyz_matrix, chart_errors
    from ocio_vp.pipeline import post_correction_problem
    from ocio_vp.simulator.stage import paper_stage, paper_stage_measurements

    measurements = paper_stage_measurements(("incandescent",))
    env = measurements.environments[0]
    matrix = camera_to_xyz_matrix(paper_stage().camera)
    # The incandescent problem as the solve poses it; the charts below replace its patches.
    base = post_correction_problem(measurements, env)
    base_srl, base_target = np.asarray(base.SRL), np.asarray(base.target)
    rng = np.random.default_rng(7)
    held = _mixtures(rng, 200, len(base_target))
    held_problem = _replace(
        base, SRL=np.einsum("kj,jab->kab", held, base_srl), target=held @ base_target
    )
    sizes = QUICK_SIZES if quick else SIZES
    problems = {}
    for n in sizes:
        srl, target = _charts(base_srl, base_target, n, np.random.default_rng(n))
        problems[n] = _replace(base, SRL=srl, target=target)
    rows = []
    for name, solver in Q_SOLVE_METHODS.items():
        cells, last = [], 0.0
        solver(problems[sizes[0]])  # warm-up (lazy imports, caches): not timed
        for n in sizes:
            if last > BUDGET_S:
                cells.append("not run")
                continue
            problem = problems[n]
            start = time.perf_counter()
            fit = solver(problem)
            last = time.perf_counter() - start
            lit = held_problem if fit.M is None else _replace(held_problem, M=fit.M)
            corrected = fit.correction.apply(lit.predicted)  # the model, not Q
            de = float(
                chart_errors(corrected, lit.target, camera_to_xyz=matrix).delta_E_2000.mean()
            )
            cells.append(f"{fmt_ms(last)} / {de:.2f}")
        rows.append((f"`{name}`", *cells))
    rows.append(_screening_row(problems))
    return "\n".join(
        [
            "## Q-solve time against the number of patches",
            "",
            __doc__.split("\n\n", 1)[1].replace("\n", " ").strip(),
            "",
            "Each cell: solve time / mean ΔE2000 on the 200 held-out mixtures. The last row is "
            "the bad-patch screening every solve runs first (unless `--keep-all-patches`): its "
            "time / the patches it excluded (the mixtures carry 0.5% noise, no bad patch).",
            "",
            markdown_table(["method", *(f"{n} patches" for n in sizes)], rows),
            "",
        ]
    )


def _screening_row(problems: dict) -> tuple[str, ...]:
    """Time of ``inconsistent_patches`` per chart size, and how many patches it excluded."""
    from ocio_vp.correction.outliers import inconsistent_patches

    cells = []
    for n, problem in problems.items():
        X, P = problem.predicted, problem.target
        inconsistent_patches(X, P, np.ones(n), 18)  # warm-up at every size: not timed
        start = time.perf_counter()
        found = inconsistent_patches(X, P, np.ones(n), 18)
        cells.append(f"{fmt_ms(time.perf_counter() - start)} / {len(found)} excluded")
    return ("screening (`inconsistent_patches`)", *cells)


def _replace(problem, **fields):
    """``problem`` with ``fields`` replaced; the weights follow a new chart's size (all 1)."""
    import dataclasses

    if "target" in fields:
        fields["weights"] = None
    return dataclasses.replace(problem, **fields)


if __name__ == "__main__":
    import sys

    print(run(quick="--quick" in sys.argv))
