"""How the skin rule's constants were chosen (training half only), and whether a solve's own
skin expectation (``diagnostics.skin``) predicts measured skin (held-out half, report only).

``tuning``: on the TRAINING skin, split in two by ITA order (one half makes the skin samples,
the other judges), the tuning cameras of the accuracy benchmark (Nikon 5100, Sigma SDMerill,
Canon EOS 5D Mark II, Nikon D810) and its three tuning LED sets, seven broadband environments
and two noise levels: the root-polynomial fitted to chart and skin samples for each skin weight
and combination ridge, as ratios to least squares on the judging half and on the RAW to ACES
reflectances (general reflectances other than the skin benchmark's CES-99).

``expectation``: on the HELD-OUT half of :mod:`benchmarks.skin_eval` (cameras, LED sets,
skin no rule was chosen on), each solve's expected skin ratio to least squares against the
ratio measured on held-out skin (after the rule was fixed: nothing is chosen here).

``five``: why the accuracy benchmark's five skin samples (colour's PMC skin tones and CIE 1995
TCS13) show the default near least squares while held-out NIST skin shows it well below: both
skin sets judged on the same solves, on the accuracy benchmark's stages and on the skin
benchmark's held-out stages (0.5 % noise), per sample and per environment (report only).

Run: ``python -m benchmarks.skin_rule [--part tuning|expectation|five]`` (markdown on stdout;
about a minute for the tuning part, two for the expectation, two for the five samples).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

CAMERAS = (
    "Nikon 5100 (NPL)",
    "Sigma SDMerill (NPL)",
    "Canon EOS 5D Mark II (rawtoaces)",
    "Nikon D810 (rawtoaces)",
)
WEIGHTS = (0.25, 0.5, 1.0)
RIDGES = (1e-5, 1e-4, 1e-3, 1e-2)
NOISES = (0.002, 0.01)


def _delta_e(stage, environment, correct, reflectances, problem) -> float:
    import colour

    from ocio_vp.simulator.truth import camera_matrix, held_out_colours

    lit, target = held_out_colours(
        stage, environment, M=problem.M, w_avg=problem.w_avg, reflectances=reflectances
    )
    _, white = held_out_colours(
        stage,
        environment,
        M=problem.M,
        w_avg=problem.w_avg,
        reflectances=np.ones((1, reflectances.shape[1])),
    )
    matrix = camera_matrix(stage)
    xyz_white = matrix @ white[0]
    scale = 1.0 / xyz_white[1]
    xy = colour.XYZ_to_xy(xyz_white * scale)
    lab = [colour.XYZ_to_Lab(rgb @ matrix.T * scale, xy) for rgb in (target, correct(lit))]
    return float(np.mean(colour.delta_E(*lab)))


def tuning() -> str:
    """The tuning table (module docstring)."""
    from benchmarks.skin_eval import TUNING_LED_SETS, broadband_environments
    from ocio_vp.correction import skin as skin_module
    from ocio_vp.correction.problem import fit_least_squares
    from ocio_vp.correction.root_polynomial import make_q_root_polynomial
    from ocio_vp.model.correction import MatrixCorrection
    from ocio_vp.pipeline import post_correction_problem
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
    from ocio_vp.simulator.truth import held_out_reflectances, noisy_measurements
    from ocio_vp.skin_data import training_skin

    training = training_skin()
    order = np.argsort(training.ita())
    fit_half, judge_half = order[0::2], order[1::2]
    fitting = dataclasses.replace(
        training,
        names=tuple(training.names[i] for i in fit_half),
        reflectances=training.reflectances[fit_half],
        bands=tuple(training.bands[i] for i in fit_half),
    )
    # General reflectances: the RAW to ACES set, not CES-99 (the skin benchmark's general set).
    judged, general = training.reflectances[judge_half], held_out_reflectances()["rawtoaces"]
    sums: dict[tuple, np.ndarray] = {}
    for noise in NOISES:
        for camera in CAMERAS:
            for leds in TUNING_LED_SETS:
                stage = spectral_stage(camera=camera, leds=leds)
                clean = simulate_measurements(broadband_environments(), stage=stage)
                measurements = noisy_measurements(clean, noise, np.random.default_rng(0))
                for env in measurements.environments:
                    base = post_correction_problem(measurements, env)
                    Q = fit_least_squares(base.predicted, base.target, base.fit_weights)
                    ls = [
                        _delta_e(stage, env.name, MatrixCorrection(Q).apply, s, base)
                        for s in (judged, general)
                    ]
                    for ridge in RIDGES:
                        weights = skin_module.chart_skin_weights(
                            skin_module.chart_reflectances(),
                            fitting.reflectances,
                            base.fit_weights > 0,
                            ridge,
                        )
                        samples = dataclasses.replace(
                            skin_module.chart_skin_samples(
                                base.SRL, base.target, base.fit_weights > 0, fitting
                            ),
                            SRL=np.einsum("kj,jcl->kcl", weights, base.SRL),
                            target=weights @ base.target,
                            weights=weights,
                        )
                        problem = dataclasses.replace(base, skin=samples)
                        for weight in WEIGHTS:
                            fit = make_q_root_polynomial(2, weight)(problem).correction
                            got = [
                                _delta_e(stage, env.name, fit.apply, s, problem)
                                for s in (judged, general)
                            ]
                            key = (noise, ridge, weight)
                            sums[key] = sums.get(key, np.zeros(4)) + np.array([*got, *ls])
    rows = [
        "| noise | combination ridge | skin weight | skin / LS | RAW to ACES / LS |",
        "|---|---|---|---|---|",
    ]
    for (noise, ridge, weight), s in sums.items():
        rows.append(
            f"| {noise:.1%} | {ridge:g} | {weight:g} | {s[0] / s[2]:.3f} | {s[1] / s[3]:.3f} |"
        )
    return "\n".join(rows)


def expectation() -> str:
    """Expected against measured skin ratios on the held-out half (module docstring)."""
    from benchmarks.skin_eval import HELD_OUT_LEDS, broadband_environments, cameras_of, skin_set
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
    from ocio_vp.simulator.truth import held_out_errors, noisy_measurements

    skin = skin_set("held-out").reflectances
    out: dict[str, list[tuple[float, float]]] = {"general": [], "skin": []}
    for camera in cameras_of("held-out"):
        for leds in HELD_OUT_LEDS:
            stage = spectral_stage(camera=camera, leds=leds)
            clean = simulate_measurements(broadband_environments(), stage=stage)
            measurements = noisy_measurements(clean, 0.005, np.random.default_rng(0))
            for env in measurements.environments:
                solved = {p: solve_environment(measurements, env, priority=p) for p in out}
                ls = solve_environment(measurements, env, method="least-squares")
                reference = held_out_errors(
                    stage, env.name, M=ls.M, w_avg=ls.w_avg, Q=ls.Q, reflectances=skin
                ).delta_E_2000.mean()
                for priority, s in solved.items():
                    measured = held_out_errors(
                        stage, env.name, M=s.M, w_avg=s.w_avg, Q=s.Q, reflectances=skin,
                        correct=s.correction.apply,
                    ).delta_E_2000.mean()  # fmt: skip
                    out[priority].append((s.diagnostics.skin.ratio, measured / reference))
    rows = [
        "| priority | solves | expected skin / LS (mean) | measured skin / LS (mean) | "
        "correlation | solves where both say 'better than LS' or both 'not' |",
        "|---|---|---|---|---|---|",
    ]
    for priority, pairs in out.items():
        e, m = np.array(pairs).T
        agree = np.mean((e < 1 - 1e-9) == (m < 1))
        rows.append(
            f"| {priority} | {len(e)} | {e.mean():.3f} | {m.mean():.3f} | "
            f"{np.corrcoef(e, m)[0, 1]:.2f} | {agree:.0%} |"
        )
    return "\n".join(rows)


def _five_samples():
    """The accuracy benchmark's skin set as a :class:`~ocio_vp.skin_data.SkinSet` (ITA bands
    from the spectra)."""
    from ocio_vp.simulator.truth import _SKIN_PMC, held_out_reflectances
    from ocio_vp.skin_data import SkinSet, band_of, ita_degrees, lab_d65

    values = held_out_reflectances()["skin"]
    names = (*_SKIN_PMC, "TCS13")
    assert len(values) == len(names), "a sample of the five was dropped as a chart duplicate"
    bands = tuple(band_of(float(a)) for a in ita_degrees(lab_d65(values)))
    return SkinSet("held-out", names, values, bands)


def five() -> str:
    """Default / least squares on the five samples and on held-out NIST skin, same solves."""
    from benchmarks.skin_eval import (
        HELD_OUT_LEDS,
        TUNING_LED_SETS,
        Variant,
        evaluate,
        held_out_skin,
        summarise,
    )

    stages = {
        "accuracy benchmark's (Nikon 5100, Sigma SDMerill; its two LED sets)": dict(
            cameras=CAMERAS[:2], led_sets=TUNING_LED_SETS[:2], split="training"
        ),
        "skin benchmark's held-out (16 cameras, 2 LED sets)": dict(
            led_sets=HELD_OUT_LEDS, split="held-out", quick=False
        ),
    }
    chosen = [Variant("least-squares", "least-squares"), Variant("auto", "auto")]
    sets = {"five samples": _five_samples(), "NIST held-out (49)": held_out_skin()}
    lines = [
        "| stages | skin set | solves | least squares ΔE2000 | auto / LS | per sample (auto / LS) |",
        "|---|---|---|---|---|---|",
    ]
    per_env = []
    for stage_name, kw in stages.items():
        for set_name, skin in sets.items():
            run = evaluate(variant_list=chosen, skin=skin, **kw)  # type: ignore[arg-type]
            s = summarise(run, "auto")
            ref = np.array([r.skin for r in run.rows if r.variant == "least-squares"])
            own = np.array([r.skin for r in run.rows if r.variant == "auto"])
            samples = ""
            if len(skin.names) <= 5:
                ratio = own.mean(axis=0) / ref.mean(axis=0)
                samples = ", ".join(f"{n} {v:.2f}x" for n, v in zip(skin.names, ratio, strict=True))
            lines.append(
                f"| {stage_name} | {set_name} | {s.cells} | {ref.mean():.2f} | "
                f"{s.skin_ratio:.2f}x | {samples} |"
            )
            envs = ", ".join(f"{e} {v:.2f}x" for e, v in s.by_environment_ratio.items())
            per_env.append(f"- {stage_name}, {set_name}: {envs}")
    return "\n".join(
        [*lines, "", "Per environment (auto / LS):", "", *per_env, "", *_spectra_lines()]
    )


def _spectra_lines() -> list[str]:
    """How far the five samples' spectra lie from measured skin (every NIST subject, 400-700
    nm): RMS distance to the nearest subject, of the spectrum and of its shape (divided by its
    mean), beside the NIST subjects' own nearest-neighbour distances; and the haemoglobin dip
    near 575 nm (mean of 560 and 590 nm minus 575 nm) every measured skin shows."""
    from benchmarks.skin_eval import held_out_skin
    from ocio_vp.skin_data import ita_degrees, lab_d65, training_skin

    five = _five_samples()
    nist = np.vstack([training_skin().reflectances, held_out_skin().reflectances])
    visible = slice(4, 65)  # 400-700 nm on the 5 nm grid from 380

    def nearest(a, b, shape=False, itself=False):
        a, b = a[:, visible], b[:, visible]
        if shape:
            a, b = a / a.mean(1, keepdims=True), b / b.mean(1, keepdims=True)
        d = np.sqrt(np.mean((a[:, None] - b[None]) ** 2, axis=2))
        if itself:
            np.fill_diagonal(d, np.inf)
        return d.min(axis=1)

    def dip(r):
        return (r[:, 36] + r[:, 42]) / 2 - r[:, 39]  # 560, 590 and 575 nm

    own, own_shape = nearest(nist, nist, itself=True), nearest(nist, nist, True, True)
    ita = ita_degrees(lab_d65(five.reflectances))
    rows = [
        "| sample | ITA° | RMS to the nearest NIST subject | shape RMS | dip at 575 nm |",
        "|---|---|---|---|---|",
        f"| NIST subjects (nearest other subject: median, max) | - | {np.median(own):.3f}, "
        f"{own.max():.3f} | {np.median(own_shape):.3f}, {own_shape.max():.3f} | median "
        f"{np.median(dip(nist)):.3f}, min {dip(nist).min():.3f} |",
    ]
    for name, a, d, sd, w in zip(
        five.names,
        ita,
        nearest(five.reflectances, nist),
        nearest(five.reflectances, nist, True),
        dip(five.reflectances),
        strict=True,
    ):
        rows.append(f"| {name} | {a:.0f} | {d:.3f} | {sd:.3f} | {w:.3f} |")
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("tuning", "expectation", "five"), action="append")
    args = parser.parse_args(argv)
    for part in args.part or ("tuning", "expectation"):
        print(f"### {part}\n\n{globals()[part]()}\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
