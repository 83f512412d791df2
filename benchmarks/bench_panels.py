"""Several panel types on one stage: one calibration per panel type against the wall's alone.

For each simulated stage whose ceiling is another panel model (:mod:`ocio_vp.simulator.panels`),
way the ceiling's processor was matched to the wall (``xyz``: to the wall's white on a
spectroradiometer, as panel vendors calibrate; ``camera``: to the wall's white as this camera
sees it, the most a calibration of the wall alone can hope for), environment (scenes lit from
above and the sides), Q method, noise level and seed: the stage's measurements are simulated,
every photographed value gets multiplicative Gaussian noise
(:func:`ocio_vp.simulator.truth.noisy_measurements`), and two calibrations are solved through
the product's own path (:func:`ocio_vp.pipeline.solve_environment`) from the same noisy data:

- **wall only**: the wall's primaries and lit chart and the whole environment's w_avg, no
  ``panels`` (:func:`ocio_vp.simulator.panels.wall_only_measurements`); its M drives the
  ceiling too, as on a stage calibrated for one panel type;
- **per panel type**: the measurements file with ``panels``, one M per type, Q fitted to the
  summed light.

Each is judged on reflectances the chart does not contain (RAW to ACES training set and CIE
2017 colour evaluation samples, pooled), lit by what both panel types really emit (each type's
part of the environment through the M it is driven with, clipped at 0, through its true LEDs),
post-corrected by the solve's own ``solution.correction.apply``, against the samples under the
real light: mean ΔE2000 (:func:`ocio_vp.simulator.panels.panel_held_out_errors`). Also the lit
white patch before Q, per channel relative to the target's (largest channel), from the spectra.

The **held-out** stage is one no test and no default uses: the Sigma SDMerill camera, the wider
LED set of the accuracy benchmark on the wall, a third LED set on the ceiling.

Run alone: ``python -m benchmarks.bench_panels [--quick] [--out docs/panels_benchmark.md]``;
``python -m benchmarks.run`` writes ``docs/panels_benchmark.md`` too.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict

import numpy as np

from benchmarks import markdown_table

#: ``benchmarks.run`` writes this module's section to docs/<DOC>.
DOC = "panels_benchmark.md"
#: name -> (camera, wall LEDs, ceiling LEDs), peak/FWHM nm.
STAGES = {
    "held-out": (
        "Sigma SDMerill (NPL)",
        ((620.0, 30.0), (530.0, 45.0), (465.0, 25.0)),
        ((612.0, 22.0), (545.0, 38.0), (452.0, 22.0)),
    ),
    "default": ("Nikon 5100 (NPL)", None, None),
}
WHITES = ("xyz", "camera")
METHODS = ("auto", "least-squares")
GENERAL_SETS = ("rawtoaces", "cie2017")


def _stage(name: str, white: str):
    from ocio_vp.simulator.panels import DEFAULT_CEILING_LEDS, panel_stage
    from ocio_vp.simulator.stage import spectral_stage

    camera, wall_leds, ceiling_leds = STAGES[name]
    wall = spectral_stage(camera=camera, leds=wall_leds)
    return panel_stage(wall, ceiling_leds=ceiling_leds or DEFAULT_CEILING_LEDS, white=white)


def _lit_white(stage, env: str, M: dict) -> float:
    """Largest channel error of the lit white patch before Q (spectral truth), relative."""
    from ocio_vp.simulator.panels import scene_light
    from ocio_vp.simulator.stage import camera_rgb

    light = scene_light(stage.wall, env)
    w = {k: camera_rgb(stage.wall, v) for k, v in light.items()}
    emitted = sum(s.leds @ np.clip(M[k] @ w[k], 0.0, None) for k, s in stage.types)
    white = stage.wall.reflectances[stage.wall.white_patch]
    lit = camera_rgb(stage.wall, white * emitted)
    target = camera_rgb(stage.wall, white * (light["wall"] + light["ceiling"]))
    return float(np.max(np.abs(lit - target) / target))


def _judge(stage, env, solution, M, reflectances) -> tuple[float, float]:
    from ocio_vp.simulator.panels import panel_held_out_errors

    errors = panel_held_out_errors(
        stage, env, M=M, correct=solution.correction.apply, reflectances=reflectances
    ).delta_E_2000
    return float(np.mean(errors)), _lit_white(stage, env, M)


def _one(stage, m, env, method, noise, seed, reflectances):
    """(wall-only, per-panel) (mean ΔE2000, lit white error) and the per-panel solve time."""
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.panels import wall_only_measurements
    from ocio_vp.simulator.truth import noisy_measurements

    noisy = noisy_measurements(m, noise, np.random.default_rng(seed))
    flat = wall_only_measurements(noisy)
    theirs = solve_environment(flat, flat.environment(env), method=method)
    start = time.perf_counter()
    ours = solve_environment(noisy, noisy.environment(env), method=method)
    seconds = time.perf_counter() - start
    M_ours = {name: panel.M for name, panel in ours.panels.items()}
    return (
        _judge(stage, env, theirs, {"wall": theirs.M, "ceiling": theirs.M}, reflectances),
        _judge(stage, env, ours, M_ours, reflectances),
        seconds,
    )


def measure(quick: bool):
    from ocio_vp.simulator.panels import SCENES, simulate_panel_measurements
    from ocio_vp.simulator.truth import held_out_reflectances

    stages = ("held-out",) if quick else tuple(STAGES)
    whites = ("xyz",) if quick else WHITES
    methods = ("auto",) if quick else METHODS
    noises, seeds = ((0.005,), 1) if quick else ((0.005, 0.01), 3)
    sets = held_out_reflectances()
    reflectances = np.vstack([sets[s] for s in GENERAL_SETS])
    envs = tuple(SCENES)
    results = defaultdict(list)
    seconds = []
    for name in stages:
        for white in whites:
            stage = _stage(name, white)
            m = simulate_panel_measurements(stage, envs)
            for method in methods:
                for env in envs:
                    for noise in noises:
                        for seed in range(seeds):
                            base, ours, s = _one(stage, m, env, method, noise, seed, reflectances)
                            results[(name, white, method, env)].append((*base, *ours))
                            seconds.append(s)
    config = {"stages": stages, "whites": whites, "methods": methods, "noises": noises}
    return config | {"seeds": seeds, "envs": envs, "samples": len(reflectances)}, results, seconds


def extrapolation_rows(stages) -> list[list[str]]:
    """How the per-panel post-correction behaves beyond the chart (noise-free solves, the
    default method, with and without ``--protect-emitters``): its diagnostics ``extrapolation``
    (:mod:`ocio_vp.correction.extrapolation`), whose domain is built from the summed light and
    the wall's M."""
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.panels import SCENES, simulate_panel_measurements

    rows = []
    for name in stages:
        m = simulate_panel_measurements(_stage(name, "xyz"), tuple(SCENES))
        for env in m.environments:
            for protect in (False, True):
                s = solve_environment(m, env, protect_emitters=protect)
                x = s.diagnostics.extrapolation
                rows.append(
                    [name, env.name, "protect-emitters" if protect else "default",
                     s.diagnostics.model, f"{100 * x.folds:.2f}%", f"{x.kept:.2f}",
                     "-" if x["negative"] is None else f"{x['negative']:.2f}",
                     f"{x.led_damage:.1f}",
                     f"{x.led_damage_least_squares:.1f}"]
                )  # fmt: skip
    return rows


def _rows(config, results):
    summary, detail = [], []
    for name in config["stages"]:
        for white in config["whites"]:
            for method in config["methods"]:
                gains = []
                for env in config["envs"]:
                    values = np.mean(results[(name, white, method, env)], axis=0)
                    gain = 1.0 - values[2] / values[0]
                    gains.append(gain)
                    detail.append(
                        [name, white, method, env, f"{values[0]:.2f}", f"{values[2]:.2f}",
                         f"{-100 * gain:+.0f}%",
                         f"{100 * values[1]:.1f}%", f"{100 * values[3]:.1f}%"]
                    )  # fmt: skip
                means = np.mean([np.mean(results[(name, white, method, e)], axis=0) for e in config["envs"]], axis=0)  # fmt: skip
                summary.append(
                    [name, white, method, f"{means[0]:.2f}", f"{means[2]:.2f}",
                     f"{100 * np.mean(gains):.0f}%", f"{100 * np.min(gains):.0f}%",
                     "yes" if min(gains) > 0 else "NO"]
                )  # fmt: skip
    return summary, detail


def report(quick: bool) -> str:
    config, results, seconds = measure(quick)
    summary, detail = _rows(config, results)
    noises = ", ".join(f"{100 * n:g}%" for n in config["noises"])
    return "\n\n".join(
        [
            "# Several panel types: one calibration per type against the wall's alone",
            "Generated by `python -m benchmarks.bench_panels"
            + (" --quick" if quick else " --out docs/panels_benchmark.md")
            + "` (also by `python -m benchmarks.run`). Method in the module docstring and "
            f"docs/panels.md: noise {noises}, {config['seeds']} seed(s), "
            f"{config['samples']} held-out reflectances (RAW to ACES training set and CIE 2017 "
            "colour evaluation samples), the scenes of `ocio_vp.simulator.panels.SCENES` "
            "(light from above on the ceiling, from the sides on the wall). Stages: `held-out` "
            "(Sigma SDMerill, wall LEDs 620/30, 530/45, 465/25 nm, ceiling 612/22, 545/38, "
            "452/22 nm), `default` (what `ocio-vp simulate --ceiling-leds 618/24,538/40,470/26` "
            "simulates: Nikon 5100, the paper-like wall). White: how the ceiling's processor "
            "was matched to the wall (`xyz`: on a spectroradiometer; `camera`: through this "
            "camera).",
            "## Mean held-out ΔE2000 after Q, averaged over the scenes",
            "Gain: the per-panel calibration's error below the wall-only one's, per scene, "
            "then averaged; worst: the smallest gain of any scene.",
            markdown_table(
                [
                    "stage",
                    "white",
                    "method",
                    "wall only",
                    "per panel type",
                    "mean gain",
                    "worst scene's gain",
                    "better in every scene",
                ],
                summary,
            ),
            "## Per scene",
            "ΔE2000: mean over the held-out reflectances, seeds and noise levels. Lit white: "
            "the white patch lit by both types before Q, its largest channel's error relative "
            "to the target (spectral truth), mean over seeds.",
            markdown_table(
                [
                    "stage",
                    "white",
                    "method",
                    "scene",
                    "ΔE wall only",
                    "ΔE per panel",
                    "change",
                    "lit white, wall only",
                    "lit white, per panel",
                ],
                detail,
            ),
            f"Per-panel solve time: median {np.median(seconds):.2f} s, max {np.max(seconds):.2f} s "
            "(this run's machine).",
            "## The post-correction beyond the chart",
            "Per-panel solves without noise, white `xyz`: the extrapolation diagnostics of "
            "solution.json (docs/stability.md): folds (share of the reflective solid mapped two "
            "to one), kept (least share of a bright saturated input's dominant channel kept), "
            "negative (lowest channel relative to it), and the p95 ΔE2000 by which it moves the "
            "wall's own LEDs in frame, against least squares on the same patches.",
            markdown_table(
                [
                    "stage",
                    "scene",
                    "post-correction",
                    "model",
                    "folds",
                    "kept",
                    "negative",
                    "LED damage",
                    "least squares' LED damage",
                ],
                extrapolation_rows(config["stages"]),
            ),
        ]
    )


def run(quick: bool = False) -> str:
    return report(quick)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=None, help="write the document here too")
    args = parser.parse_args(argv)
    text = run(args.quick)
    print(text)
    if args.out:
        from pathlib import Path

        Path(args.out).write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
