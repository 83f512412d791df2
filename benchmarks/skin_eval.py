"""Skin on the simulated stage: every method judged on measured human skin, fast enough to tune.

:func:`evaluate` simulates stages (camera x LED set), photographs each broadband environment's
chart with noise, solves it through the product's own path
(:func:`ocio_vp.pipeline.solve_environment`) with every variant (a Q method, or a method with
solve options such as a skin priority) and judges the solution as
:mod:`benchmarks.bench_accuracy` does (:func:`ocio_vp.simulator.truth.held_out_errors`: the
samples lit by what the wall really emits, corrected, against the real light, ΔE2000 through
the camera's own RGB -> XYZ matrix) on:

- skin: measured human skin (:mod:`ocio_vp.skin_data`), per sample with its ITA band;
- general reflectances: the CIE 2017 colour evaluation samples (CES-99, as kept by
  :func:`ocio_vp.simulator.truth.held_out_reflectances`);
- emitters: the 95th percentile of ΔE2000 between Q(x) and x over the narrow-band emitters of
  :mod:`ocio_vp.simulator.extremes`;
- the in-frustum background: mean error of the displayed chart relative to white (through N and
  Q, :func:`ocio_vp.simulator.evaluate.evaluate_solution`).

Two halves that never mix:

- ``split="training"`` (for tuning rules and constants): the training skin, the tuning
  cameras (the rawtoaces ones and half the physlight ones) and three Gaussian LED sets;
- ``split="held-out"`` (for the published tables only): the held-out skin, the other half of
  the physlight cameras and LED sets no rule was chosen on (:data:`HELD_OUT_LEDS`).

``evaluate(quick=True)`` takes four cameras and one LED set (well under a minute for a few
variants). Rows are typed (:class:`SkinRow`); :func:`summarise` and friends reduce them.
"""

from __future__ import annotations

import dataclasses
import functools
import time
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "HELD_OUT_LEDS",
    "LOSS_MARGIN",
    "REFERENCE",
    "TUNING_LED_SETS",
    "Evaluation",
    "SkinRow",
    "Variant",
    "VariantSummary",
    "broadband_environments",
    "cameras_of",
    "evaluate",
    "held_out_skin",
    "paired_difference",
    "skin_set",
    "summarise",
    "variants",
]

HELD_OUT_FILE = Path(__file__).resolve().parent / "data" / "skin_held_out.json"

#: Gaussian stand-ins for a measured LED wall (peaks 632/524/468 nm, FWHM 16/32/20 nm: the
#: measured spectra the issue describes; no measured RGB LED panel spectra with a licence that
#: allows shipping them were found), and a second panel product: LED sets no rule is tuned on.
HELD_OUT_LEDS = (
    ((632.0, 16.0), (524.0, 32.0), (468.0, 20.0)),
    ((622.0, 17.0), (517.0, 32.0), (452.0, 22.0)),
)
#: The simulator's default LEDs, a broad set and a third product (those of
#: :mod:`benchmarks.accuracy_beyond`'s tuning half).
TUNING_LED_SETS = (
    ((630.0, 20.0), (525.0, 35.0), (460.0, 22.0)),
    ((620.0, 30.0), (530.0, 45.0), (465.0, 25.0)),
    ((625.0, 18.0), (528.0, 32.0), (455.0, 20.0)),
)
#: Noise on every photographed value (as bench_accuracy's middle level); one draw per stage.
NOISE = 0.005
REFERENCE = "least-squares"


@dataclass(frozen=True)
class Variant:
    """One way to solve: a label for the tables, a Q method, and extra solve options.

    ``measured``: when not empty, the solve is given the stage's true LED spectra and camera
    sensitivities (the ``spectra`` solve option; the location light estimated from the target
    chart): what a stage engineer who measured the panels and the camera would pass.
    """

    label: str
    method: str
    options: tuple[tuple[str, object], ...] = ()
    measured: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class SkinRow:
    """One (variant, stage, environment) solve judged: per-sample ΔE2000 on skin (with each
    sample's ITA band) and on general reflectances, the emitters' p95 and the background."""

    variant: str
    camera: str
    leds: str
    environment: str
    model: str
    skin: np.ndarray
    bands: tuple[str, ...]
    general: np.ndarray
    emitters_p95: float
    background: float
    seconds: float

    @property
    def skin_mean(self) -> float:
        return float(np.mean(self.skin))

    @property
    def general_mean(self) -> float:
        return float(np.mean(self.general))


@dataclass
class Evaluation:
    """Every row of a run, and what could not be run (stage or solve refused, and why)."""

    rows: list[SkinRow] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    split: str = "training"
    cameras: tuple[str, ...] = ()
    led_sets: tuple = ()
    environments: tuple[str, ...] = ()
    seconds: float = 0.0


def broadband_environments() -> tuple[str, ...]:
    """The simulator's environments but sodium (low, high pressure) and the LEDs' own white."""
    from ocio_vp.simulator.data import ENVIRONMENTS

    return tuple(name for name, spec in ENVIRONMENTS.items() if spec.broadband)


def held_out_skin():
    """The HELD-OUT skin (:class:`ocio_vp.skin_data.SkinSet`): for the published tables only."""
    return _held_out_skin(HELD_OUT_FILE.read_text(encoding="utf-8"))


@functools.lru_cache(maxsize=1)
def _held_out_skin(text: str):
    from ocio_vp.skin_data import load_skin_file

    return load_skin_file(text)


def skin_set(split: str):
    """The skin of one half: ``'training'`` or ``'held-out'``."""
    from ocio_vp.skin_data import training_skin

    if split == "training":
        return training_skin()
    if split == "held-out":
        return held_out_skin()
    raise ValueError(f"split must be 'training' or 'held-out', got {split!r}")


def cameras_of(split: str) -> tuple[str, ...]:
    """The cameras of one half (tuning: the rawtoaces file's and the physlight tuning half)."""
    import json
    from importlib import resources

    from ocio_vp.skin_data import physlight_camera_names
    from ocio_vp.spectra import VENDORED_CAMERAS

    if split == "held-out":
        return physlight_camera_names("held-out")
    text = resources.files("ocio_vp").joinpath(VENDORED_CAMERAS).read_text(encoding="utf-8")
    return (*json.loads(text)["cameras"], *physlight_camera_names("tuning"))


def variants(methods: Iterable[str] | None = None) -> tuple[Variant, ...]:
    """Every Q method of the registry (or ``methods``), then ``auto`` with a skin priority when
    the solver has one (a ``priority`` solve option), so the tables grow with the solver."""
    from ocio_vp.correction.registry import Q_SOLVE_METHODS
    from ocio_vp.pipeline import SolveOptions

    names = tuple(methods) if methods is not None else tuple(Q_SOLVE_METHODS)
    out = [Variant(name, name) for name in names]
    fields = {f.name for f in dataclasses.fields(SolveOptions)}
    if methods is None and "priority" in fields:
        skin = (("priority", "skin"),)
        out.append(Variant("auto, priority skin", "auto", skin))
        if "spectra" in fields:
            measured = (("spectra", "leds"), ("spectra", "camera"))
            out.append(Variant("auto, priority skin, measured spectra", "auto", skin, measured))
    return tuple(out)


def led_label(leds) -> str:
    return ", ".join(f"{p:g}/{w:g}" for p, w in leds)


def _judge(stage, measurements, env, variant: Variant, samples) -> SkinRow:
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.evaluate import evaluate_solution
    from ocio_vp.simulator.extremes import emitter_errors
    from ocio_vp.simulator.truth import camera_matrix, solution_held_out_errors

    skin, general = samples
    start = time.perf_counter()
    options = dict(variant.options)
    if variant.measured:  # the stage's true LED spectra and camera, the light estimated
        from ocio_vp.correction.skin_spectra import StageSpectra

        options["spectra"] = StageSpectra(stage.leds, stage.camera, {}, "the measured spectra")
    solution = solve_environment(measurements, env, method=variant.method, **options)
    seconds = time.perf_counter() - start

    def errors(reflectances):
        return solution_held_out_errors(stage, env.name, solution, reflectances).delta_E_2000

    emitted, _ = emitter_errors(
        stage, env.name, solution.correction.apply, camera_to_xyz=camera_matrix(stage)
    )
    return SkinRow(
        variant=variant.label,
        camera=stage.camera_name,
        leds=stage.led_description,
        environment=env.name,
        model=str(solution.diagnostics.model or variant.method),
        skin=errors(skin.reflectances),
        bands=skin.bands,
        general=errors(general),
        emitters_p95=float(np.percentile(emitted, 95)),
        background=float(np.mean(evaluate_solution(stage, solution).displayed)),
        seconds=seconds,
    )


def evaluate(
    methods: Iterable[str] | None = None,
    environments: Sequence[str] | None = None,
    *,
    split: str = "training",
    quick: bool = True,
    cameras: Sequence[str] | None = None,
    led_sets: Sequence | None = None,
    variant_list: Sequence[Variant] | None = None,
    noise: float = NOISE,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
    skin=None,
) -> Evaluation:
    """Solve and judge every (camera, LED set, environment, variant) of one half.

    ``methods`` (registry names; default all, plus the skin priority when the solver has it)
    or ``variant_list``; ``environments`` default :func:`broadband_environments`; ``cameras``
    and ``led_sets`` default to the half's (``quick``: its first four cameras, one LED set).
    Always includes least squares, the reference of every ratio. ``skin``: another
    :class:`ocio_vp.skin_data.SkinSet` to judge on instead of the half's.
    """
    from ocio_vp.errors import InputError
    from ocio_vp.simulator.stage import simulate_measurements, spectral_stage
    from ocio_vp.simulator.truth import held_out_reflectances, noisy_measurements

    start = time.perf_counter()
    chosen = tuple(variant_list) if variant_list is not None else variants(methods)
    if REFERENCE not in {v.label for v in chosen}:
        chosen = (Variant(REFERENCE, REFERENCE), *chosen)
    environments = tuple(environments or broadband_environments())
    leds_all = tuple(led_sets or (HELD_OUT_LEDS if split == "held-out" else TUNING_LED_SETS))
    if cameras is None:
        cameras = cameras_of(split)
        if quick:  # spread over the list: several makers
            cameras = cameras[:: max(1, len(cameras) // 4)][:4]
    cameras = tuple(cameras)
    if quick and led_sets is None:
        leds_all = leds_all[:1]
    samples = (skin or skin_set(split), held_out_reflectances()["cie2017"])
    out = Evaluation(split=split, cameras=cameras, led_sets=leds_all, environments=environments)
    for camera, leds in ((c, x) for c in cameras for x in leds_all):
        try:
            stage = spectral_stage(camera=camera, leds=leds)
            clean = simulate_measurements(list(environments), stage=stage)
        except InputError as error:
            out.skipped.append(f"{camera}, LEDs {led_label(leds)}: {error}")
            continue
        # The stage's own draw: the same noise whichever other stages or variants a run has.
        rng = np.random.default_rng([seed, zlib.crc32(f"{camera} {leds!r}".encode())])
        measurements = noisy_measurements(clean, noise, rng)
        for env in measurements.environments:
            for variant in chosen:
                try:
                    out.rows.append(_judge(stage, measurements, env, variant, samples))
                except InputError as error:
                    out.skipped.append(f"{camera} / {env.name} / {variant.label}: {error}")
        if progress:
            progress(f"{camera}, LEDs {led_label(leds)}")
    out.seconds = time.perf_counter() - start
    return out


# --------------------------------------------------------------------------------------------
# Reductions: every figure is a ratio to least squares on the same solves (same stage, same
# environment, same noise draw).

#: A method "loses" a camera or a cell when its mean skin ΔE2000 exceeds least squares' by more
#: than this fraction (the issue's 2 %).
LOSS_MARGIN = 0.02


@dataclass(frozen=True)
class VariantSummary:
    """One variant against least squares over the solves both have.

    ``skin`` / ``general``: mean ΔE2000 (skin, CES-99); ``*_ratio``: over least squares' on the
    same solves; ``by_environment`` / ``by_band`` / ``by_camera``: mean skin ΔE2000 per group,
    and ``*_ratio`` the same over least squares'; ``cameras_lost``: cameras whose mean skin
    ΔE2000 is more than :data:`LOSS_MARGIN` above least squares'; ``cells_lost`` of ``cells``
    (camera x LED set x environment solves) likewise; ``emitters_p95``: the mean over solves of
    each solve's emitter p95; ``background``: mean in-frustum error relative to white;
    ``models``: what the variant chose, share of solves; ``seconds``: mean solve time.
    """

    variant: str
    cells: int
    skin: float
    skin_ratio: float
    general: float
    general_ratio: float
    by_environment: dict[str, float]
    by_environment_ratio: dict[str, float]
    by_band: dict[str, float]
    by_band_ratio: dict[str, float]
    by_camera: dict[str, float]
    by_camera_ratio: dict[str, float]
    cameras_lost: int
    cells_lost: int
    emitters_p95: float
    background: float
    seconds: float
    models: dict[str, float]


def _key(row: SkinRow) -> tuple[str, str, str]:
    return (row.camera, row.leds, row.environment)


def _ratio(a: Sequence[float], b: Sequence[float]) -> float:
    return float(np.mean(a) / np.mean(b)) if len(a) and len(b) else float("nan")


def _groups(pairs) -> dict[str, dict[str, tuple[list, list]]]:
    """Per grouping (environment, band, camera): label -> (this variant's, least squares')."""
    out: dict[str, dict[str, tuple[list, list]]] = {"environment": {}, "band": {}, "camera": {}}
    for r, ref in pairs:
        for kind, label in (("environment", r.environment), ("camera", r.camera)):
            mine, theirs = out[kind].setdefault(label, ([], []))
            mine.append(r.skin_mean)
            theirs.append(ref.skin_mean)
        for band, a, b in zip(r.bands, r.skin, ref.skin, strict=True):
            mine, theirs = out["band"].setdefault(band, ([], []))
            mine.append(a)
            theirs.append(b)
    return out


def summarise(evaluation: Evaluation, variant: str) -> VariantSummary:
    """The figures of one variant (see :class:`VariantSummary`)."""
    reference = {_key(r): r for r in evaluation.rows if r.variant == REFERENCE}
    pairs = [
        (r, reference[_key(r)])
        for r in evaluation.rows
        if r.variant == variant and _key(r) in reference
    ]
    if not pairs:
        raise ValueError(f"no solves of {variant!r} beside {REFERENCE!r}")
    groups = _groups(pairs)
    means = {k: {g: float(np.mean(a)) for g, (a, _) in v.items()} for k, v in groups.items()}
    ratios = {k: {g: _ratio(a, b) for g, (a, b) in v.items()} for k, v in groups.items()}
    models: dict[str, int] = {}
    for r, _ in pairs:
        models[r.model] = models.get(r.model, 0) + 1
    return VariantSummary(
        variant=variant,
        cells=len(pairs),
        skin=float(np.mean([r.skin_mean for r, _ in pairs])),
        skin_ratio=_ratio([r.skin_mean for r, _ in pairs], [b.skin_mean for _, b in pairs]),
        general=float(np.mean([r.general_mean for r, _ in pairs])),
        general_ratio=_ratio(
            [r.general_mean for r, _ in pairs], [b.general_mean for _, b in pairs]
        ),
        by_environment=means["environment"],
        by_environment_ratio=ratios["environment"],
        by_band=means["band"],
        by_band_ratio=ratios["band"],
        by_camera=means["camera"],
        by_camera_ratio=ratios["camera"],
        cameras_lost=sum(v > 1 + LOSS_MARGIN for v in ratios["camera"].values()),
        cells_lost=sum(r.skin_mean > (1 + LOSS_MARGIN) * ref.skin_mean for r, ref in pairs),
        emitters_p95=float(np.mean([r.emitters_p95 for r, _ in pairs])),
        background=float(np.mean([r.background for r, _ in pairs])),
        seconds=float(np.mean([r.seconds for r, _ in pairs])),
        models={k: v / len(pairs) for k, v in models.items()},
    )


@dataclass(frozen=True)
class PairedDifference:
    """``variant`` minus ``other`` on one per-solve figure over the solves both have: the mean
    difference, its standard error, the solves where it is above 0 (worse) and below 0."""

    mean: float
    standard_error: float
    solves: int
    worse: int
    better: int


def paired_difference(
    evaluation: Evaluation, variant: str, other: str, figure: str
) -> PairedDifference:
    """:class:`PairedDifference` of a :class:`SkinRow` attribute (``background``,
    ``emitters_p95``, ``skin_mean``, ...) between two variants, solve by solve."""
    theirs = {_key(r): getattr(r, figure) for r in evaluation.rows if r.variant == other}
    d = np.array(
        [getattr(r, figure) - theirs[_key(r)] for r in evaluation.rows
         if r.variant == variant and _key(r) in theirs]
    )  # fmt: skip
    if len(d) < 2:
        raise ValueError(f"fewer than two solves of {variant!r} beside {other!r}")
    return PairedDifference(
        mean=float(d.mean()),
        standard_error=float(d.std(ddof=1) / np.sqrt(len(d))),
        solves=len(d),
        worse=int(np.sum(d > 0)),
        better=int(np.sum(d < 0)),
    )
