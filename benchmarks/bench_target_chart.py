"""Synthesized target charts (``ocio-vp target-chart``): how close to a photographed chart?

On the spectral simulator (paper stage: 630/525/460 nm LEDs, ColorChecker N Ohta), for each
environment the real target chart is the chart under the true spectrum; the synthesized one is
made from the environment's w_avg alone. Q is solved (paper eq. 5, least squares) from both,
with 0.5% multiplicative noise on every measured value and several seeds, and judged on the RAW
to ACES training reflectances that are not on the chart (187 of 190) by mean ΔE2000
(:func:`ocio_vp.synthesis.evaluate.study_environment`, through :mod:`ocio_vp.simulator.truth`). ``docs/target_chart.md`` quotes the
tables; regenerate with ``python -m benchmarks.run --only target_chart``.
"""

from __future__ import annotations

import numpy as np

from benchmarks import markdown_table

NOISE = 0.005


#: The natural illuminants the secondary tables use in --quick mode (sun, shade, tungsten, glass).
QUICK_SUBSET = (
    "direct_sun (D55)",
    "outdoor_shade (D75)",
    "incandescent (A)",
    "indoor_daylight (ID65)",
)


def _natural(quick: bool = False):
    """Natural illuminants: the simulator's daylights, shade, sun, tungsten, and ISO 7589."""
    import colour

    from ocio_vp.spectra import spectral_shape

    shape = spectral_shape()
    everything = {
        "direct_sun (D55)": "direct_sun",
        "d65": "d65",
        "outdoor_shade (D75)": "outdoor_shade",
        "d50": "d50",
        "indoor_daylight (ID65)": "indoor_daylight",
        "incandescent (A)": "incandescent",
        "ISO 7589 photographic daylight": colour.SDS_ILLUMINANTS["ISO 7589 Photographic Daylight"],
        "ISO 7589 studio tungsten": colour.SDS_ILLUMINANTS["ISO 7589 Studio Tungsten"],
        "sunset, Planckian 2200 K": colour.sd_blackbody(2200, shape),
        "blue sky, CIE D 12000 K": colour.sd_CIE_illuminant_D_series(
            colour.temperature.CCT_to_xy_CIE_D(12000)
        ),
    }
    return {k: v for k, v in everything.items() if k in QUICK_SUBSET or not quick}


def _spiky():
    import colour

    return {
        "warm_white_led (Luxeon WW)": "warm_white_led",
        "LED-B3 (phosphor LED)": colour.SDS_ILLUMINANTS["LED-B3"],
        "LED-RGB1": colour.SDS_ILLUMINANTS["LED-RGB1"],
        "FL2 (cool white fluorescent)": colour.SDS_ILLUMINANTS["FL2"],
        "FL11 (triphosphor)": colour.SDS_ILLUMINANTS["FL11"],
        "high_pressure_sodium": "high_pressure_sodium",
        "sodium_vapour (LPS)": "sodium_vapour",
    }


def _synthesizer(camera, method="auto", spectrum_of=None):
    from ocio_vp.simulator import paper_stage, white_reflectance
    from ocio_vp.synthesis import chart_spectra, synthesize_target

    reflectances = chart_spectra()
    white = white_reflectance(paper_stage())

    def synthesize(w_avg):
        spectrum = None if spectrum_of is None else spectrum_of
        return synthesize_target(
            w_avg, camera, reflectances, white_reflectance=white, method=method, spectrum=spectrum
        ).target_chart

    return synthesize


def _fitted_gamut(name: str):
    """The simulator camera as a stated gamut: XYZ -> camera fitted on the training colours."""
    from colour.characterisation import matrix_colour_correction

    from ocio_vp.metrics import training_rgb_xyz
    from ocio_vp.spectra import camera_sensitivities
    from ocio_vp.synthesis import camera_from_matrix

    rgb, xyz = training_rgb_xyz(camera_sensitivities(name))
    matrix = matrix_colour_correction(xyz, rgb, method="Cheung 2004", terms=3)
    return camera_from_matrix(matrix, f"{name} as a 3x3 gamut")


def _study(stage, environments, synthesize, seeds, held_out, w_avg_noise=None):
    from ocio_vp.synthesis.evaluate import study_environment

    out = {}
    for label, env in environments.items():
        try:
            out[label] = study_environment(
                stage,
                env,
                synthesize,
                name=label,
                noise=NOISE,
                w_avg_noise=w_avg_noise,
                seeds=seeds,
                held_out=held_out,
            )
        except ValueError as error:  # InputError: the estimate refused this colour
            out[label] = str(error)
    return out


def _methods_table(stage, seeds, held_out, camera, quick):
    from ocio_vp.synthesis import ILLUMINANT_METHODS

    rows = []
    natural = _natural(quick)
    for method in ILLUMINANT_METHODS:
        studies = _study(stage, natural, _synthesizer(camera, method), seeds, held_out)
        ok = [s for s in studies.values() if not isinstance(s, str)]
        ratios = [s.ratio for s in ok]
        rows.append(
            (
                f"`{method}`",
                f"{len(ok)}/{len(natural)}",
                f"{np.mean([s.chart_delta_E for s in ok]):.3f}",
                f"{np.max([s.chart_delta_E for s in ok]):.3f}",
                f"{np.mean([s.q_synthesized for s in ok]):.3f}",
                f"{np.max(ratios):.3f}",
            )
        )
    header = [
        "base spectrum",
        "usable",
        "chart ΔE00 mean",
        "chart ΔE00 worst",
        "held-out ΔE00 with Q (synth.)",
        "worst Q ratio synth./real",
    ]
    return markdown_table(header, rows)


def _row(label, s, exact, kind=""):
    verdict = (
        "ok" if s.ratio <= 1.10 and s.q_real < s.m_only and s.q_synthesized < s.m_only else "FAIL"
    )
    return (
        label,
        kind,
        f"{s.chart_delta_E:.3f}",
        f"{s.m_only:.2f}",
        f"{s.q_real:.2f}",
        f"{s.q_synthesized:.2f}",
        f"{s.ratio:.3f}",
        verdict,
        f"{exact.ratio:.3f}",
    )


_HEADER = [
    "environment",
    "light (CCT, Duv)",
    "chart ΔE00 synth. vs real",
    "held-out M only",
    "Q real chart",
    "Q synth. chart",
    "ratio",
    "within 10%, both beat M",
    "ratio, exact w_avg",
]


def _light(stage, env):
    from ocio_vp.metrics import camera_to_xyz_matrix
    from ocio_vp.simulator.stage import camera_rgb, environment_spectrum
    from ocio_vp.synthesis import cct_duv

    w = camera_rgb(stage, environment_spectrum(stage, env))
    cct, duv = cct_duv(camera_to_xyz_matrix(stage.camera) @ w)
    return f"{cct:.0f} K, {duv:+.4f}"


def _main_table(stage, environments, synthesize, seeds, held_out):
    studies = _study(stage, environments, synthesize, seeds, held_out)
    exact = _study(stage, environments, synthesize, seeds, held_out, w_avg_noise=0.0)
    rows = [_row(k, s, exact[k], _light(stage, environments[k])) for k, s in studies.items()]
    return markdown_table(_HEADER, rows), studies


def _camera_table(seeds, held_out, quick):
    from ocio_vp.simulator import spectral_stage
    from ocio_vp.synthesis import camera_from_dataset

    rows = []
    for name in ("Nikon 5100 (NPL)", "Sigma SDMerill (NPL)"):
        stage = spectral_stage(camera=name, name="bench")
        for model in (camera_from_dataset(name), _fitted_gamut(name)):
            studies = _study(stage, _natural(quick), _synthesizer(model), seeds, held_out)
            ok = [s for s in studies.values() if not isinstance(s, str)]
            exact = _study(stage, _natural(quick), _synthesizer(model), seeds, held_out, 0.0)
            rows.append(
                (
                    name,
                    "spectral sensitivities" if model.spectral else "3x3 gamut from XYZ",
                    f"{np.mean([s.chart_delta_E for s in ok]):.3f}",
                    f"{np.max([s.chart_delta_E for s in ok]):.3f}",
                    f"{np.mean([s.m_only for s in ok]):.2f}",
                    f"{np.mean([s.q_real for s in ok]):.2f}",
                    f"{np.mean([s.q_synthesized for s in ok]):.2f}",
                    f"{np.max([s.ratio for s in ok]):.3f}",
                    f"{sum(s.q_synthesized < s.m_only for s in ok)}/{len(studies)}",
                    f"{max(s.ratio for s in exact.values()):.3f}",
                )
            )
    header = [
        "camera",
        "model",
        "chart ΔE00 mean",
        "chart ΔE00 worst",
        "held-out M only",
        "Q real",
        "Q synth.",
        "worst ratio",
        "Q synth. beats M",
        "worst ratio, exact w_avg",
    ]
    return markdown_table(header, rows)


def _spiky_table(stage, seeds, held_out, camera):
    from ocio_vp.simulator.stage import environment_spectrum

    rows = []
    for label, env in _spiky().items():
        studies = _study(stage, {label: env}, _synthesizer(camera), seeds, held_out)
        given = _study(
            stage,
            {label: env},
            _synthesizer(camera, spectrum_of=environment_spectrum(stage, env)),
            seeds,
            held_out,
        )[label]
        s = studies[label]
        warned = _warned(stage, env, camera)
        if isinstance(s, str):
            q = f"{given.q_synthesized:.2f} ({given.ratio:.2f}x)"
            rows.append(
                (
                    label,
                    _light(stage, env),
                    warned,
                    "refused",
                    f"{given.m_only:.2f}",
                    f"{given.q_real:.2f}",
                    "refused",
                    q,
                )
            )
            continue
        rows.append(
            (
                label,
                _light(stage, env),
                warned,
                f"{s.chart_delta_E:.2f}",
                f"{s.m_only:.2f}",
                f"{s.q_real:.2f}",
                f"{s.q_synthesized:.2f} ({s.ratio:.2f}x)",
                f"{given.q_synthesized:.2f} ({given.ratio:.2f}x)",
            )
        )
    header = [
        "environment",
        "light (CCT, Duv)",
        "off-locus warning",
        "chart ΔE00 (auto)",
        "held-out M only",
        "Q real",
        "Q synth. (auto)",
        "Q synth. (spectrum given)",
    ]
    return markdown_table(header, rows)


def _warned(stage, env, camera) -> str:
    from ocio_vp.simulator.stage import camera_rgb, environment_spectrum
    from ocio_vp.synthesis import estimate_illuminant

    w = camera_rgb(stage, environment_spectrum(stage, env))
    try:
        estimate = estimate_illuminant(w, camera)
    except ValueError:
        return "refused"
    return "no" if not estimate.warnings else "yes"


def run(quick: bool = False) -> str:
    from ocio_vp.simulator import paper_stage
    from ocio_vp.simulator.truth import held_out_reflectances
    from ocio_vp.synthesis import camera_from_dataset

    seeds = 3 if quick else 10
    stage = paper_stage()
    camera = camera_from_dataset(stage.camera_name)
    held_out = held_out_reflectances(stage.chart_name)["rawtoaces"]
    main, studies = _main_table(stage, _natural(), _synthesizer(camera), seeds, held_out)
    subset = "the 4 quick-mode illuminants" if quick else "the natural illuminants above"
    met = all(
        s.ratio <= 1.10 and s.q_real < s.m_only and s.q_synthesized < s.m_only
        for s in studies.values()
    )
    return "\n".join(
        [
            "## Synthesized target charts (target-chart): accuracy against a photographed chart",
            "",
            f"Paper stage (Nikon 5100 (NPL), 630/525/460 nm LEDs, ColorChecker N Ohta). Q by "
            f"least squares (eq. 5) from the real and from the synthesized chart, {NOISE:.1%} "
            f"multiplicative noise on [SL], [SRL]_j, the real chart and w_avg, {seeds} seeds; "
            f"mean ΔE2000 of the {len(held_out)} RAW to ACES training reflectances that are not "
            "on the chart, lit by the wall, through the camera's fitted XYZ matrix. Chart ΔE00: the noise-free "
            "synthesized chart against the real one. `auto` estimate, spectral camera. Last "
            "column: the same with w_avg exact (a rendered HDRI has no measurement noise; a real "
            "chart lets Q absorb a w_avg error, a synthesized chart inherits it).",
            "",
            main,
            "",
            f"Done-when criterion (every natural illuminant within 10% and both beat M): "
            f"**{'met' if met else 'NOT met'}**.",
            "",
            f"### Choice of the base spectrum ({subset}, means over them)",
            "",
            _methods_table(stage, max(2, seeds // 2), held_out, camera, quick),
            "",
            f"### Camera model: spectral sensitivities vs a stated gamut ({subset})",
            "",
            "The gamut is the camera's own 3x3 XYZ -> camera matrix, least-squares on the "
            "training reflectances under D65 (what a manufacturer's gamut is); both rows judge "
            "Q with the true camera.",
            "",
            _camera_table(max(2, seeds // 2), held_out, quick),
            "",
            "### Spiky and off-locus lights: RGB alone cannot tell the spectrum",
            "",
            _spiky_table(stage, max(2, seeds // 2), held_out, camera),
        ]
    )
