"""Skin first: every method on HELD-OUT measured human skin, light to dark, beside least squares.

The machinery is :mod:`benchmarks.skin_eval` (simulated stages, the product's solve, judged
against the real light). This module runs its held-out half: the held-out NIST subjects, the
held-out physlight cameras and the held-out LED sets, every broadband environment, and writes
the ``## Skin`` section of ``docs/accuracy.md``: per environment, per ITA band, per camera,
general reflectances (CES-99), emitters and background, each as a ratio to least squares on the
same solves, and the issue's criteria with the measured figure beside each.

The two slowest methods (``perceptual``, ``joint``: about 1 s and 0.2 s a solve) run on the
first held-out LED set only, so the whole section takes a few minutes; their cell counts say so.

Run alone: ``python -m benchmarks.bench_skin [--quick] [--out docs/accuracy.md]`` (``--out``
replaces only this section of an existing document); ``python -m benchmarks.run`` appends it
to the accuracy document it writes (or replaces it there when the accuracy benchmark is
skipped).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from benchmarks import markdown_table
from benchmarks.skin_eval import (
    HELD_OUT_LEDS,
    LOSS_MARGIN,
    REFERENCE,
    Evaluation,
    Variant,
    VariantSummary,
    evaluate,
    led_label,
    paired_difference,
    summarise,
    variants,
)

#: ``benchmarks.run`` puts this section into docs/<SECTION_OF> (after the module that owns it).
SECTION_OF = "accuracy.md"
HEADING = "## Skin: held-out measured skin, light to dark"
SLOW = ("perceptual", "joint")
DEFAULT = "auto"
PRIORITY = "auto, priority skin"
MEASURED = "auto, priority skin, measured spectra"


def measure(quick: bool, progress=None) -> Evaluation:
    """The held-out half (``quick``: four cameras, the first LED set)."""
    everything = variants()
    fast = [v for v in everything if v.method not in SLOW or v.options]
    slow = [v for v in everything if v.method in SLOW and not v.options]
    main = evaluate(variant_list=fast, split="held-out", quick=quick, progress=progress)
    if not slow:
        return main
    extra = evaluate(
        variant_list=[Variant(REFERENCE, REFERENCE), *slow],
        split="held-out",
        quick=quick,
        led_sets=HELD_OUT_LEDS[:1],
        cameras=main.cameras,
        progress=progress,
    )
    main.rows.extend(r for r in extra.rows if r.variant != REFERENCE)
    main.skipped.extend(s for s in extra.skipped if s not in main.skipped)
    main.seconds += extra.seconds
    return main


def measure_training(progress=None) -> Evaluation:
    """The training half's quick subset (four tuning cameras, one LED set) for the default and
    the skin priority: what a rule tuned there promised, beside what it holds on held-out data."""
    chosen = [v for v in variants() if v.label in (REFERENCE, DEFAULT, PRIORITY, MEASURED)]
    return evaluate(variant_list=chosen, split="training", quick=True, progress=progress)


def measure_second_draw(quick: bool, progress=None) -> Evaluation:
    """The default and the skin priority on the held-out half again, with another noise draw:
    how far the headline ratios move with the noise alone."""
    chosen = [v for v in variants() if v.label in (REFERENCE, DEFAULT, PRIORITY, MEASURED)]
    return evaluate(variant_list=chosen, split="held-out", quick=quick, seed=1, progress=progress)


def noise_line(summaries: dict[str, VariantSummary], second: Evaluation) -> str:
    """One line: the headline skin and CES-99 ratios of the other draw beside this one's."""
    parts = []
    for label in (DEFAULT, PRIORITY, MEASURED):
        if label in summaries:
            other = summarise(second, label)
            here = summaries[label]
            parts.append(
                f"`{label}` skin {_r(other.skin_ratio)} (here {_r(here.skin_ratio)}), CES-99 "
                f"{_r(other.general_ratio)} (here {_r(here.general_ratio)})"
            )
    return "- Another noise draw on the same stages: " + "; ".join(parts) + "."


def generalisation_table(held_out: dict[str, VariantSummary], training: Evaluation) -> str:
    """Skin and CES-99 ratios on the training half's quick subset beside the held-out half."""
    rows = []
    for label in (DEFAULT, PRIORITY, MEASURED):
        if label not in held_out:
            continue
        tuned, judged = summarise(training, label), held_out[label]
        rows.append(
            (
                f"`{label}`",
                _r(tuned.skin_ratio),
                _r(judged.skin_ratio),
                _r(tuned.general_ratio),
                _r(judged.general_ratio),
            )
        )
    header = ["method", "skin, training", "skin, held-out", "CES-99, training", "CES-99, held-out"]
    return markdown_table(header, rows)


def _r(value: float) -> str:
    return f"{value:.2f}x"


def _labels(evaluation: Evaluation) -> list[str]:
    seen: list[str] = []
    for row in evaluation.rows:
        if row.variant not in seen:
            seen.append(row.variant)
    return seen


def environment_table(summaries: dict[str, VariantSummary], environments) -> str:
    """Skin per environment: least squares in ΔE2000, every other method as a ratio to it."""
    rows = []
    for label, s in summaries.items():
        if label == REFERENCE:
            cells = [f"{s.by_environment.get(e, np.nan):.2f}" for e in environments]
            rows.append((f"`{label}` (ΔE2000)", *cells, f"{s.skin:.2f}", "-", "-"))
            continue
        rows.append(
            (
                f"`{label}`",
                *[_r(s.by_environment_ratio.get(e, np.nan)) for e in environments],
                _r(s.skin_ratio),
                f"{s.cameras_lost} of {len(s.by_camera)}",
                f"{s.cells_lost} of {s.cells}",
            )
        )
    return markdown_table(["method", *environments, "all", "cameras lost", "solves lost"], rows)


def band_table(summaries: dict[str, VariantSummary], bands: list[tuple[str, int]]) -> str:
    """Skin per ITA band (samples in brackets)."""
    rows = []
    for label, s in summaries.items():
        if label == REFERENCE:
            rows.append((f"`{label}` (ΔE2000)", *[f"{s.by_band[b]:.2f}" for b, _ in bands]))
        else:
            rows.append((f"`{label}`", *[_r(s.by_band_ratio.get(b, np.nan)) for b, _ in bands]))
    return markdown_table(["method", *[f"{b} ({n})" for b, n in bands]], rows)


def overall_table(summaries: dict[str, VariantSummary]) -> str:
    """Skin beside general reflectances, emitters, the background and the solve time."""
    rows = [
        (
            f"`{label}`",
            s.cells,
            f"{s.skin:.2f}",
            _r(s.skin_ratio),
            f"{s.general:.2f}",
            _r(s.general_ratio),
            f"{s.emitters_p95:.1f}",
            f"{100 * s.background:.2f}%",
            f"{1e3 * s.seconds:.0f} ms",
        )
        for label, s in summaries.items()
    ]
    header = [
        "method",
        "solves",
        "skin ΔE2000",
        "skin / LS",
        "CES-99 ΔE2000",
        "CES-99 / LS",
        "emitter p95 ΔE2000",
        "background error (of white)",
        "solve time",
    ]
    return markdown_table(header, rows)


def camera_table(summaries: dict[str, VariantSummary]) -> str:
    """Skin per camera: least squares in ΔE2000, the others as ratios (mean over LED sets and
    environments)."""
    ls = summaries[REFERENCE]
    others = [label for label in summaries if label != REFERENCE]
    rows = [
        (
            camera,
            f"{value:.2f}",
            *[_r(summaries[o].by_camera_ratio.get(camera, np.nan)) for o in others],
        )
        for camera, value in ls.by_camera.items()
    ]
    return markdown_table(["camera", f"`{REFERENCE}` (ΔE2000)", *[f"`{o}`" for o in others]], rows)


def criteria(summaries: dict[str, VariantSummary]) -> list[str]:
    """The issue's targets on held-out skin, each with the measured figure."""
    lines = []
    auto = summaries.get(DEFAULT)
    if auto is not None:
        worst = max(auto.by_environment_ratio.items(), key=lambda kv: kv[1])
        lines.append(
            f"- Default (`{DEFAULT}`) at most 1.00x least squares on skin in every broadband "
            f"environment: worst {_r(worst[1])} ({worst[0]}), all {_r(auto.skin_ratio)}, "
            f"{auto.cameras_lost} of {len(auto.by_camera)} cameras lost: "
            f"**{'met' if worst[1] <= 1.0 else 'NOT met'}**."
        )
        lines.append(
            f"- Default at most 0.95x least squares on general reflectances (CES-99): "
            f"{_r(auto.general_ratio)}: **{'met' if auto.general_ratio <= 0.95 else 'NOT met'}**."
        )
    priority = summaries.get(PRIORITY)
    if priority is None:
        lines.append("- Skin priority: not in this solver (no `priority` solve option yet).")
        return lines
    skin = float(np.mean(list(priority.by_environment_ratio.values())))
    lines.append(
        f"- Skin priority at most 0.80x least squares on skin (mean over broadband "
        f"environments): {_r(skin)}: **{'met' if skin <= 0.80 else 'NOT met'}**; general "
        f"reflectances at most 1.15x: {_r(priority.general_ratio)}: "
        f"**{'met' if priority.general_ratio <= 1.15 else 'NOT met'}**; emitters "
        f"{priority.emitters_p95:.1f} and background {100 * priority.background:.3f}% against "
        f"the default's {auto.emitters_p95:.1f} and {100 * auto.background:.3f}%."
        if auto is not None
        else f"- Skin priority: skin {_r(skin)}, general {_r(priority.general_ratio)}."
    )
    measured = summaries.get(MEASURED)
    if measured is None:
        lines.append(
            "- Skin priority with the measured LED spectra and camera sensitivities: not in "
            "this solver (no `led_spectra` / `camera_sensitivities` solve options yet)."
        )
    else:
        with_spectra = float(np.mean(list(measured.by_environment_ratio.values())))
        lines.append(
            f"- Skin priority with the measured LED spectra and camera sensitivities: skin "
            f"{_r(with_spectra)} against {_r(skin)} without "
            f"({100 * (1 - with_spectra / skin):.0f}% better), general "
            f"{_r(measured.general_ratio)}."
        )
    return lines


def elsewhere_lines(evaluation: Evaluation) -> list[str]:
    """Skin first against the default on the background and the emitters, solve by solve: the
    mean paired difference and its standard error (no worse: at most one standard error
    above 0, i.e. not worse beyond the noise of the comparison)."""
    lines = []
    for label in (PRIORITY, MEASURED):
        if label not in _labels(evaluation) or DEFAULT not in _labels(evaluation):
            continue
        parts, met = [], True
        for figure, name, scale, unit in (
            ("background", "background error", 100.0, " % of white"),
            ("emitters_p95", "emitter p95", 1.0, " ΔE2000"),
        ):
            d = paired_difference(evaluation, label, DEFAULT, figure)
            met = met and d.mean <= d.standard_error
            parts.append(
                f"{name} {scale * d.mean:+.4f} ± {scale * d.standard_error:.4f}{unit} (worse in "
                f"{d.worse}, better in {d.better} of {d.solves})"
            )
        lines.append(
            f"- `{label}` no worse than the default on the background and the emitters (paired "
            f"differences over the same solves, ± one standard error): {'; '.join(parts)}: "
            f"**{'met' if met else 'NOT met'}**."
        )
    return lines


def models_line(summary: VariantSummary) -> str:
    shares = sorted(summary.models.items(), key=lambda kv: -kv[1])
    return ", ".join(f"{model} {100 * share:.0f}%" for model, share in shares)


def preamble(evaluation: Evaluation, skin, missing: list[str], quick: bool) -> list[str]:
    """The section's heading, how it was generated and what it judged on."""
    ita = skin.ita()
    return [
        HEADING,
        "",
        f"Generated by `python -m benchmarks.bench_skin{' --quick' if quick else ''} --out "
        "docs/accuracy.md` (replaces only this section; also run by `python -m benchmarks.run`"
        "; do not edit by hand). Method: `benchmarks/skin_eval.py`; data and split: "
        "`ocio_vp/data/SKIN_LICENSE.md`, `ocio_vp/data/CAMERAS_LICENSE.md`.",
        "",
        f"- Skin: the {len(skin.names)} held-out subjects of NIST's *Reference Data Set of Human "
        f"Skin Reflectance* (no fit, rule or constant uses them), ITA° {ita.min():.0f} to "
        f"{ita.max():.0f}; bands empty here: {', '.join(missing) or 'none'} (the NIST set has "
        "no skin darker than ITA° -21; no measured darker skin with a licence to ship was "
        "found).",
        f"- Cameras: {len(evaluation.cameras)} held-out physlight bodies "
        f"({', '.join(evaluation.cameras)}).",
        "- LEDs (peak/FWHM nm, Gaussian: no measured RGB LED panel spectra with a licence to "
        "ship were found): "
        + "; ".join(led_label(x) for x in evaluation.led_sets)
        + f" (`{'`, `'.join(SLOW)}`: the first set only).",
        f"- Environments: {', '.join(evaluation.environments)} (all but sodium and the LEDs' "
        f"own white); 0.5% noise on every photographed value, one draw per stage.",
        "- Every figure but least squares' is a ratio to least squares on the same solves. A "
        f"camera or solve is *lost* when the method's mean skin ΔE2000 there is more than "
        f"{100 * LOSS_MARGIN:g}% above least squares'.",
        f"- Run time: {evaluation.seconds / 60:.1f} min.",
    ]


def report(
    evaluation: Evaluation,
    quick: bool,
    training: Evaluation | None = None,
    second: Evaluation | None = None,
) -> str:
    from benchmarks.skin_eval import held_out_skin

    skin = held_out_skin()
    counts = {name: skin.bands.count(name) for name, _ in _bands()}
    bands = [(b, n) for b, n in counts.items() if n]
    summaries = {label: summarise(evaluation, label) for label in _labels(evaluation)}
    lines = [
        *preamble(evaluation, skin, [b for b, n in counts.items() if not n], quick),
        "",
        "### Targets",
        "",
        *criteria(summaries),
        *elsewhere_lines(evaluation),
        *([noise_line(summaries, second)] if second is not None and DEFAULT in summaries else []),
        "",
        "### Skin per environment (mean ΔE2000 over cameras, LED sets and subjects)",
        "",
        environment_table(summaries, evaluation.environments),
        "",
        "### Skin per lightness band (ITA°; held-out subjects in brackets)",
        "",
        band_table(summaries, bands),
        "",
        "### Skin beside general reflectances, emitters and the background",
        "",
        overall_table(summaries),
        "",
        "### Skin per camera",
        "",
        camera_table(summaries),
        "",
        f"What `{DEFAULT}` chose: {models_line(summaries[DEFAULT])}."
        if DEFAULT in summaries
        else "",
        *(
            [
                "",
                "### Training half against held-out half",
                "",
                "The same ratios on the training half (training skin, four tuning cameras: "
                f"{', '.join(training.cameras)}; LEDs {led_label(training.led_sets[0])}), "
                "where rules may be tuned. A held-out figure much worse than its training one "
                "would say a rule learnt the training data rather than skin.",
                "",
                generalisation_table(summaries, training),
            ]
            if training is not None and DEFAULT in summaries
            else []
        ),
        *(
            ["", "Not run:", "", *[f"- {s}" for s in evaluation.skipped]]
            if evaluation.skipped
            else []
        ),
    ]
    return "\n".join(lines).rstrip() + "\n"


def _bands():
    from ocio_vp.skin_data import ITA_BANDS

    return ITA_BANDS


def _progress(text: str) -> None:
    print(f"  {text}", file=sys.stderr, flush=True)


def run(quick: bool = False) -> str:
    held_out = measure(quick, progress=_progress)
    return report(
        held_out,
        quick,
        training=measure_training(progress=_progress),
        second=measure_second_draw(quick, progress=_progress),
    )


def main(argv=None) -> int:
    from benchmarks import replace_section

    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_skin", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="four cameras, one LED set")
    parser.add_argument(
        "--out", help="replace this section of that document (default: print the section)"
    )
    args = parser.parse_args(argv)
    start = time.perf_counter()
    text = run(quick=args.quick)
    if args.out:
        try:
            with open(args.out, encoding="utf-8") as handle:
                existing = handle.read()
        except FileNotFoundError:
            existing = ""
        with open(args.out, "w", encoding="utf-8") as handle:
            handle.write(replace_section(existing, text))
    else:
        print(text)
    print(f"bench_skin: {time.perf_counter() - start:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
