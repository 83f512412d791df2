"""Accuracy on colours the chart does not contain: every Q method, judged on held-out spectra.

For each simulated stage (camera x LED set), environment, noise level and seed: the stage's
measurements are simulated, every photographed value gets multiplicative Gaussian noise
(:func:`ocio_vp.simulator.truth.noisy_measurements`), and each Q method of the registry
(``Q_SOLVE_METHODS``: a method added there is benchmarked without touching this file) is
solved through the product's own path (:func:`ocio_vp.pipeline.solve_environment`). The
solution is then judged on reflectances that are not on the chart, lit by what the wall really
emits (drive clipped at 0) and compared with the real light
(:func:`ocio_vp.simulator.truth.held_out_errors`): mean and 95th percentile ΔE2000 and ΔE ITP.

Run alone: ``python -m benchmarks.bench_accuracy [--quick] [--methods ...] [--out FILE]``; by
``python -m benchmarks.run`` it writes ``docs/accuracy.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from benchmarks import markdown_table

#: ``benchmarks.run`` writes this module's section to docs/<DOC> instead of docs/performance.md.
DOC = "accuracy.md"

#: Second LED set: broader, shifted emitters (a different panel product than the default).
WIDE_LEDS = ((620.0, 30.0), (530.0, 45.0), (465.0, 25.0))
CAMERAS = ("Nikon 5100 (NPL)", "Sigma SDMerill (NPL)")
NOISE_LEVELS = (0.002, 0.005, 0.01)
#: Sets pooled as "held-out"; "skin" is reported on its own.
GENERAL_SETS = ("rawtoaces", "cie2017")


@dataclass
class Config:
    """What to run: stages as (camera, LEDs) pairs, environments, noise levels, seeds, methods."""

    stages: tuple
    environments: tuple
    noise_levels: tuple
    seeds: int
    methods: tuple
    chart: str = "ColorChecker N Ohta"


@dataclass
class Results:
    """Per (method, environment, noise): pooled per-sample ΔE arrays and auto's chosen models."""

    de2000: dict = field(default_factory=lambda: defaultdict(list))
    itp: dict = field(default_factory=lambda: defaultdict(list))
    skin: dict = field(default_factory=lambda: defaultdict(list))
    models: dict = field(default_factory=lambda: defaultdict(lambda: defaultdict(int)))
    seconds: dict = field(default_factory=lambda: defaultdict(float))
    failures: dict = field(default_factory=lambda: defaultdict(list))


def config(quick: bool, methods=None) -> Config:
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.simulator.data import DEFAULT_LEDS, ENVIRONMENTS, PAPER_ENVIRONMENTS

    methods = tuple(methods or Q_SOLVE_METHODS)
    if quick:
        return Config(((CAMERAS[0], DEFAULT_LEDS),), PAPER_ENVIRONMENTS, (0.005,), 2, methods)
    stages = tuple((c, leds) for c in CAMERAS for leds in (DEFAULT_LEDS, WIDE_LEDS))
    return Config(stages, tuple(ENVIRONMENTS), NOISE_LEVELS, 3, methods)


def _solve_and_judge(results, stage, measurements, env, noise, method, held_out):
    from ocio_vp.correction.root_polynomial import post_correction
    from ocio_vp.errors import InputError
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.truth import held_out_errors

    key = (method, env.name, noise)
    start = time.perf_counter()
    try:
        solution = solve_environment(measurements, env, method=method)
    except InputError as error:
        results.failures[key].append(str(error))
        return
    results.seconds[method] += time.perf_counter() - start
    results.models[(method, env.name)][solution.diagnostics.get("model", method)] += 1
    for name, reflectances in held_out.items():
        errors = held_out_errors(
            stage,
            env.name,
            M=solution.M,
            w_avg=solution.w_avg,
            Q=solution.Q,
            reflectances=reflectances,
            correct=post_correction(solution.Q, solution.diagnostics.get("method_notes")),
        )
        if name in GENERAL_SETS:
            results.de2000[key].append(errors.delta_E_2000)
            results.itp[key].append(errors.delta_E_ITP)
        else:
            results.skin[key].append(errors.delta_E_2000)


def measure(cfg: Config, *, progress=None) -> Results:
    """Run every (stage, environment, noise, seed, method) of ``cfg``."""
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
    from ocio_vp.simulator.truth import held_out_reflectances, noisy_measurements

    results = Results()
    held_out = held_out_reflectances(cfg.chart)
    for camera, leds in cfg.stages:
        stage = spectral_stage(camera=camera, leds=leds, chart=cfg.chart)
        clean = simulate_measurements(cfg.environments, stage=stage)
        for noise in cfg.noise_levels:
            for seed in range(cfg.seeds):
                rng = np.random.default_rng([seed, round(noise * 1e4)])
                measurements = noisy_measurements(clean, noise, rng)
                for env in measurements.environments:
                    for method in cfg.methods:
                        _solve_and_judge(results, stage, measurements, env, noise, method, held_out)
            if progress:
                progress(f"{camera} / {leds}: noise {noise:g} done")
    return results


def _pooled(values: list) -> np.ndarray:
    return np.concatenate(values) if values else np.array([np.nan])


def _stat(results: Results, table: str, method: str, envs, noises, stat: str) -> float:
    source = getattr(results, table)
    pooled = _pooled([a for e in envs for n in noises for a in source.get((method, e, n), [])])
    return float(np.mean(pooled) if stat == "mean" else np.percentile(pooled, 95))


def summary_table(results: Results, cfg: Config, envs) -> str:
    rows = []
    for method in cfg.methods:
        cells = [
            _stat(results, t, method, envs, cfg.noise_levels, s)
            for t, s in (
                ("de2000", "mean"),
                ("de2000", "p95"),
                ("itp", "mean"),
                ("itp", "p95"),
                ("skin", "mean"),
                ("skin", "p95"),
            )
        ]
        n = sum(len(results.de2000.get((method, e, x), [])) for e in envs for x in cfg.noise_levels)
        calls = max(n, 1)
        rows.append(
            (
                f"`{method}`",
                *[f"{v:.2f}" for v in cells],
                f"{1e3 * results.seconds[method] / calls:.0f} ms",
            )
        )
    header = [
        "method",
        "mean ΔE2000",
        "p95 ΔE2000",
        "mean ΔE ITP",
        "p95 ΔE ITP",
        "skin mean ΔE2000",
        "skin p95 ΔE2000",
        "solve time",
    ]
    return markdown_table(header, rows)


def environment_table(results: Results, cfg: Config, reference="least-squares", default="auto"):
    """Mean ΔE2000 per environment and noise for every method, and default / reference."""
    rows, ratios = [], []
    for env in cfg.environments:
        for noise in cfg.noise_levels:
            means = {m: _stat(results, "de2000", m, [env], [noise], "mean") for m in cfg.methods}
            ratio = means.get(default, np.nan) / means.get(reference, np.nan)
            ratios.append(ratio)
            rows.append(
                (
                    env,
                    f"{100 * noise:g}%",
                    *[f"{means[m]:.2f}" for m in cfg.methods],
                    f"{ratio:.3f}",
                )
            )
    header = [
        "environment",
        "noise",
        *[f"`{m}`" for m in cfg.methods],
        f"`{default}` / `{reference}`",
    ]
    return markdown_table(header, rows), np.asarray(ratios)


def models_table(results: Results, cfg: Config, method="auto") -> str:
    rows = []
    for env in cfg.environments:
        counts = results.models.get((method, env), {})
        total = sum(counts.values()) or 1
        text = ", ".join(
            f"{k} {100 * v / total:.0f}%" for k, v in sorted(counts.items(), key=lambda kv: -kv[1])
        )
        rows.append((env, text))
    return markdown_table(["environment", f"models `{method}` chose (share of solves)"], rows)


def report(results: Results, cfg: Config, quick: bool) -> str:
    from ocio_vp.simulator.data import ENVIRONMENTS
    from ocio_vp.simulator.truth import held_out_reflectances

    sets = held_out_reflectances(cfg.chart)
    broadband = [e for e in cfg.environments if ENVIRONMENTS[e].broadband]
    env_table, ratios = environment_table(results, cfg)
    failures = [
        f"- `{m}` / {e} / {100 * n:g}%: {len(v)} solve(s) refused: {v[0]}"
        for (m, e, n), v in sorted(results.failures.items())
    ]
    stages = "; ".join(
        f"{c} with LEDs {', '.join(f'{p:g}/{w:g}' for p, w in leds)} nm" for c, leds in cfg.stages
    )
    lines = [
        "# Accuracy on colours the chart does not contain",
        "",
        f"Generated by `python -m benchmarks.bench_accuracy{' --quick' if quick else ''}` "
        "(also run by `python -m benchmarks.run`; do not edit by hand). See the module "
        "docstring of `benchmarks/bench_accuracy.py` for the method.",
        "",
        f"- Stages (camera, LED peak/FWHM): {stages}; chart {cfg.chart}.",
        f"- Environments: {', '.join(cfg.environments)}.",
        f"- Noise on every photographed value: {', '.join(f'{100 * n:g}%' for n in cfg.noise_levels)}"
        f"; {cfg.seeds} seeds each.",
        f"- Held-out reflectances: RAW to ACES training set ({len(sets['rawtoaces'])} kept), CIE "
        f"2017 colour evaluation samples ({len(sets['cie2017'])} kept), pooled; skin "
        f"({len(sets['skin'])}: PMC skin tones and CIE 1995 TCS13) separately.",
        "",
        f"## All broadband environments ({len(broadband)}), every stage and noise level",
        "",
        summary_table(results, cfg, broadband),
        "",
        "## All environments",
        "",
        summary_table(results, cfg, list(cfg.environments)),
        "",
        "## Mean ΔE2000 per environment and noise level",
        "",
        env_table,
        "",
        f"`auto` / `least-squares`: worst {np.nanmax(ratios):.3f}, mean {np.nanmean(ratios):.3f} "
        f"(target: worst <= 1.03, mean < 1).",
        "",
        "## What `auto` chose",
        "",
        models_table(results, cfg),
        *(["", "## Refused solves", "", *failures] if failures else []),
    ]
    return "\n".join(lines)


def run(quick: bool = False, methods=None) -> str:
    cfg = config(quick, methods)
    results = measure(cfg, progress=lambda text: print(f"  {text}", file=sys.stderr, flush=True))
    return report(results, cfg, quick)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.bench_accuracy", description=__doc__
    )
    parser.add_argument("--quick", action="store_true", help="one stage, 0.5%% noise, 2 seeds")
    parser.add_argument("--methods", nargs="+", help="registry names (default: all)")
    parser.add_argument("--out", help="write the markdown here (default: print it)")
    args = parser.parse_args(argv)
    text = run(quick=args.quick, methods=args.methods)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as handle:
            handle.write(text + "\n")
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
