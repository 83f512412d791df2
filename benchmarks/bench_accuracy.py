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
    skipped: list = field(default_factory=list)


def config(quick: bool, methods=None) -> Config:
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.simulator.data import DEFAULT_LEDS, ENVIRONMENTS, PAPER_ENVIRONMENTS

    methods = tuple(methods or Q_SOLVE_METHODS)
    if quick:
        return Config(((CAMERAS[0], DEFAULT_LEDS),), PAPER_ENVIRONMENTS, (0.005,), 2, methods)
    stages = tuple((c, leds) for c in CAMERAS for leds in (DEFAULT_LEDS, WIDE_LEDS))
    return Config(stages, tuple(ENVIRONMENTS), NOISE_LEVELS, 2, methods)


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


def _simulate(stage, environments, results):
    """The stage's measurements for every environment it can show (the stage's own LED white
    needs a positive drive: not every camera / LED pair can make a camera-neutral white)."""
    from ocio_vp.errors import InputError
    from ocio_vp.simulator.stage import simulate_measurements

    usable = []
    for name in environments:
        try:
            simulate_measurements([name], stage=stage)
        except InputError as error:
            results.skipped.append(f"{stage.camera_name}, {stage.led_description}: {name}: {error}")
            continue
        usable.append(name)
    return simulate_measurements(usable, stage=stage)


def measure(cfg: Config, *, progress=None) -> Results:
    """Run every (stage, environment, noise, seed, method) of ``cfg``."""
    from ocio_vp.simulator.stage import spectral_stage
    from ocio_vp.simulator.truth import held_out_reflectances, noisy_measurements

    results = Results()
    held_out = held_out_reflectances(cfg.chart)
    for camera, leds in cfg.stages:
        stage = spectral_stage(camera=camera, leds=leds, chart=cfg.chart)
        clean = _simulate(stage, cfg.environments, results)
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
    if stat == "median":
        return float(np.median(pooled))
    return float(np.mean(pooled) if stat == "mean" else np.percentile(pooled, 95))


def summary_table(results: Results, cfg: Config, envs) -> str:
    rows = []
    for method in cfg.methods:
        cells = [
            _stat(results, t, method, envs, cfg.noise_levels, s)
            for t, s in (
                ("de2000", "mean"),
                ("de2000", "p95"),
                ("itp", "median"),
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
        "median ΔE ITP",
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
        f"Generated by `python -m benchmarks.bench_accuracy{' --quick' if quick else ''} "
        "--out docs/accuracy.md` "
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
        "ΔE ITP is summarised by its median and 95th percentile, not its mean: a colour "
        "corrected to (slightly) negative light (a 3x3 Q under sodium) has no PQ encoding, and "
        "colour-science's ICtCp of it gives single samples of 1e3-1e17 that swamp any mean.",
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
        *(
            [
                "",
                "## Environments a stage cannot show (left out)",
                "",
                *[f"- {s}" for s in results.skipped],
            ]
            if results.skipped
            else []
        ),
    ]
    return "\n".join(lines)


def run(quick: bool = False, methods=None) -> str:
    cfg = config(quick, methods)
    results = measure(cfg, progress=lambda text: print(f"  {text}", file=sys.stderr, flush=True))
    seeds = 3 if quick else 10
    screening = outlier_report(outlier_study(cfg, seeds), seeds)
    return report(results, cfg, quick) + "\n\n" + screening


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


# ---------------------------------------------------------------------------------------------
# Bad patches: false alarms on clean charts, and what one or two corrupted patches do to Q.

CORRUPTIONS = ("zero", "x2.5", "swap", "lit-zero", "lit-x2.5", "lit-swap")


def _corrupt(X, P, j, kind):
    """The chart with patch j corrupted: target (p) or lit-chart row (x) zeroed, x2.5 or swapped
    with its neighbour (a swapped lit-chart row is the same as a swapped target: the pair moves)."""
    X, P = X.copy(), P.copy()
    k = j + 1 if j + 1 < len(P) else j - 1
    array = X if kind.startswith("lit-") else P
    how = kind.removeprefix("lit-")
    if how == "zero":
        array[j] = 0.0
    elif how == "x2.5":
        array[j] *= 2.5
    else:
        array[[j, k]] = array[[k, j]]
    return X, P, ({j, k} if how == "swap" else {j})


def _chart_problem(measurements, env):
    from ocio_vp.calibration.equations import predict_lit_chart, solve_M
    from ocio_vp.calibration.geometry import environment_w_avg, stage_beta

    M = solve_M(measurements.SL)
    X = predict_lit_chart(
        measurements.SRL, stage_beta(measurements), M, environment_w_avg(measurements, env)
    )
    return X, np.asarray(env.target_chart, dtype=np.float64)


def _q_after_screening(X, P, white):
    """(Q by least squares without the flagged patches, flagged set) or (None, 'refused')."""
    from ocio_vp.correction.linear import fit_least_squares
    from ocio_vp.correction.outliers import inconsistent_patches
    from ocio_vp.errors import InputError

    w = np.ones(len(P))
    try:
        flagged = {f.index for f in inconsistent_patches(X, P, w, white)}
    except InputError:
        return None, "refused"
    w[list(flagged)] = 0.0
    return fit_least_squares(X, P, w), flagged


def outlier_study(cfg: Config, seeds: int, noise: float = 0.01) -> dict:
    """False alarms over ``seeds`` clean charts per stage and environment; one corrupted patch
    (every patch, every corruption) and random pairs on seed 0. Q changes are relative
    Frobenius distances to the least-squares Q of the same chart uncorrupted."""
    from ocio_vp.correction.linear import fit_least_squares
    from ocio_vp.simulator.data import ENVIRONMENTS
    from ocio_vp.simulator.stage import spectral_stage
    from ocio_vp.simulator.truth import noisy_measurements

    out = defaultdict(list)
    for camera, leds in cfg.stages:
        stage = spectral_stage(camera=camera, leds=leds, chart=cfg.chart)
        clean = _simulate(stage, cfg.environments, Results())
        white = clean.stage.white_patch
        for seed in range(seeds):
            m = noisy_measurements(clean, noise, np.random.default_rng([seed, 99]))
            for env in m.environments:
                kind = "broadband" if ENVIRONMENTS[env.name].broadband else "narrow"
                X, P = _chart_problem(m, env)
                _, flagged = _q_after_screening(X, P, white)
                out[("clean", camera, kind)].append(flagged != set())
                if seed:
                    continue
                Q0 = fit_least_squares(X, P, np.ones(len(P)))
                _one_bad(out, X, P, Q0, white, (camera, kind))
                _two_bad(out, X, P, Q0, white, (camera, kind), np.random.default_rng(seed))
    return out


def _q_change(Q, Q0):
    return float(np.linalg.norm(Q - Q0) / np.linalg.norm(Q0))


def _one_bad(out, X, P, Q0, white, key):
    from ocio_vp.correction.linear import fit_least_squares

    for j in range(len(P)):
        for kind in CORRUPTIONS:
            Xc, Pc, bad = _corrupt(X, P, j, kind)
            Q, flagged = _q_after_screening(Xc, Pc, white)
            plain = _q_change(fit_least_squares(Xc, Pc, np.ones(len(P))), Q0)
            found = flagged != "refused" and bool(bad & flagged)
            out[("one", *key)].append(
                (found, np.nan if Q is None else _q_change(Q, Q0), plain, flagged == "refused")
            )


def _two_bad(out, X, P, Q0, white, key, rng, pairs: int = 12):
    from ocio_vp.correction.linear import fit_least_squares

    for _ in range(pairs):
        j, k = rng.choice(len(P), 2, replace=False)
        Xc, Pc, _ = _corrupt(X, P, int(j), str(rng.choice(["zero", "x2.5"])))
        Xc, Pc, _ = _corrupt(Xc, Pc, int(k), str(rng.choice(["zero", "x2.5", "lit-zero"])))
        Q, flagged = _q_after_screening(Xc, Pc, white)
        plain = _q_change(fit_least_squares(Xc, Pc, np.ones(len(P))), Q0)
        found = flagged != "refused" and {int(j), int(k)} <= flagged
        out[("two", *key)].append(
            (found, np.nan if Q is None else _q_change(Q, Q0), plain, flagged == "refused")
        )


def outlier_report(out: dict, seeds: int) -> str:
    rows = []
    for (what, camera, kind), values in sorted(out.items()):
        if what == "clean":
            rows.append(
                (
                    camera,
                    kind,
                    f"clean x {len(values)}",
                    f"{100 * np.mean(values):.1f}% false alarms",
                    "",
                    "",
                    "",
                )
            )
            continue
        found, q, plain, refused = (np.asarray(v, dtype=float) for v in zip(*values, strict=True))
        accepted = q[~np.isnan(q)]
        rows.append(
            (
                camera,
                kind,
                f"{what} bad x {len(values)}",
                f"{100 * found.mean():.0f}% named"
                + (f", {100 * refused.mean():.0f}% refused" if what == "two" else ""),
                f"{100 * np.median(accepted):.1f}% / {100 * np.percentile(accepted, 95):.1f}% / {100 * accepted.max():.0f}%"
                if accepted.size
                else "-",
                f"{100 * np.median(plain):.1f}% / {100 * np.percentile(plain, 95):.1f}% / {100 * plain.max():.0f}%",
                f"{100 * np.mean(accepted > 0.05):.1f}%" if accepted.size else "-",
            )
        )
    header = [
        "camera",
        "light",
        "charts",
        "screening",
        "Q change after screening (median / p95 / max)",
        "Q change without screening",
        "> 5% after screening",
    ]
    return "\n".join(
        [
            "## Bad patches: screening before the fit",
            "",
            f"Clean charts: {seeds} noise draws (1% on every value) per stage and environment; a false "
            "alarm is any patch flagged. One bad patch: every patch of seed 0 read as zero, x2.5 or "
            "swapped with its neighbour, in the target chart or in the lit chart (`lit-`). Two bad "
            "patches: 12 random pairs per chart. Q change: relative Frobenius distance between the "
            "least-squares Q fitted after screening and the one fitted on the same chart uncorrupted.",
            "",
            markdown_table(header, rows),
        ]
    )


if __name__ == "__main__":
    sys.exit(main())
