"""Host agreement: ``ocio-vp apply`` against the config's own processor, per method and light.

Part of ``python -m benchmarks.bench_accuracy`` (its "Host agreement" section of
docs/accuracy.md). Each solve is written by the product's own writer
(:func:`ocio_vp.ocio.writer.write_environment`, what ``solve`` runs) into a temporary folder and
read back as ``apply`` reads it (:func:`ocio_vp.footage.apply.load_post_correction`); then the
same pixels go through

- ``apply``: the pixel transform ``ocio-vp apply`` runs (:func:`ocio_vp.footage.apply.pixel_transform`:
  the exact model for a non-linear Q, the config's processor for a 3x3), and
- the config: the written config's ``Stage Footage`` -> reference processor
  (:func:`ocio_vp.footage.apply.cpu_processor`), what Nuke, Resolve and Unreal see through OCIO,

both on float32 buffers as footage is. The pixels span what footage holds: the held-out
reflectances lit by the wall at 1, 4 and 16 times their exposure (highlights up to 16x white),
the narrow-band emitters at 0.25-16x the scene white's luminance, and values near black with
negatives. The figures are ΔE2000 between the two outputs (the stage camera's RGB -> XYZ
matrix, the scene's white at Y = 1) over the pixels CIELAB defines (L* >= 0 in both: a narrow-band
blue emitter or a near-black pixel can fall below through the camera's matrix, where ΔE2000 is
no perceptual figure), target 0.5 at the 99th percentile and 2 at worst; and for every pixel the
config's largest channel miss in % of the pixel's largest channel, shown without a target.
Because it writes every config (3D LUT bakes for non-linear models) it runs on a subset
(:func:`hosts_config`); the section says which.
"""

from __future__ import annotations

import tempfile
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks import markdown_table

__all__ = [
    "PROTECT",
    "WorstPixel",
    "cielab_defined",
    "host_agreement",
    "hosts_config",
    "hosts_section",
]

#: The label of ``--method auto --protect-emitters`` beside the registry's methods.
PROTECT = "auto --protect-emitters"
P99_TARGET, WORST_TARGET = 0.5, 2.0
#: The relative miss's floor (of the white's largest channel): near-black pixels do not divide
#: by 0. The relative miss is shown for every pixel, those CIELAB does not define included; it
#: has no target of its own (the issue's target is ΔE2000).
RELATIVE_FLOOR = 1e-3


def hosts_config(quick: bool):
    """(cameras, LED sets, environments, noise, seeds) of the host-agreement subset."""
    from benchmarks.accuracy_beyond import DEFAULT_LEDS, REPORT
    from ocio_vp.simulator.data import ENVIRONMENTS

    if quick:
        return REPORT.cameras[:1], (DEFAULT_LEDS,), ("direct_sun", "high_pressure_sodium"), 0.005, 1
    cameras = (REPORT.cameras[0], REPORT.cameras[-1])
    return cameras, (DEFAULT_LEDS,), tuple(ENVIRONMENTS), 0.005, 1


#: The kinds of pixel, in :func:`_pixels`' order.
KINDS = ("reflectances 1x", "reflectances 4x-16x", "emitters 0.25x-16x", "near black")


def _pixels(stage, env: str, solution, reflectances: np.ndarray):
    """((n, 3) float32 camera RGB spanning footage (module docstring), (n,) kind indices)."""
    from ocio_vp.simulator.extremes import emitters_in_scene
    from ocio_vp.simulator.stage import camera_rgb
    from ocio_vp.simulator.truth import held_out_colours

    lit, _ = held_out_colours(stage, env, M=solution.M, w_avg=solution.w_avg,
                              reflectances=reflectances)  # fmt: skip
    emitters = camera_rgb(stage, emitters_in_scene(stage, env))
    top = float(np.max(lit[-1]))
    near_black = np.random.default_rng(3).uniform(-0.005, 0.02, (200, 3)) * top
    parts = (lit, np.vstack([4 * lit, 16 * lit]), np.vstack([emitters, 4 * emitters]), near_black)
    kinds = np.concatenate([np.full(len(p), k) for k, p in enumerate(parts)])
    return np.vstack(parts).astype(np.float32), kinds


def _outputs(directory: Path, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(apply's output, the config processor's output) for ``pixels``."""
    from ocio_vp.footage.apply import (
        OcioTransform,
        cpu_processor,
        load_post_correction,
        pixel_transform,
    )

    pc = load_post_correction(directory)
    applied = np.ascontiguousarray(pixels[None])
    configured = applied.copy()
    pixel_transform(pc)(applied)
    OcioTransform(cpu_processor(pc))(configured)
    return applied[0].astype(np.float64), configured[0].astype(np.float64)


def _lab(x: np.ndarray, matrix: np.ndarray, white: np.ndarray) -> np.ndarray:
    """CIELAB of camera RGB ``x`` through ``matrix``, the scene white at Y = 1 its reference."""
    import colour

    white_xyz = white @ matrix.T
    scale = 1.0 / white_xyz[1]
    return np.asarray(colour.XYZ_to_Lab(x @ matrix.T * scale, colour.XYZ_to_xy(white_xyz * scale)))


def cielab_defined(applied: np.ndarray, configured: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Pixels CIELAB defines in both outputs: L* >= 0, that is Y >= 0 through ``matrix``."""
    return ((applied @ matrix.T)[:, 1] >= 0) & ((configured @ matrix.T)[:, 1] >= 0)


@dataclass(frozen=True)
class WorstPixel:
    """A cell's worst pixel, and what the model does there: its kind (:data:`KINDS`), its
    luminance relative to the scene white's, ``apply``'s and the config's outputs (camera RGB)
    and, where the model is (or holds) a bounded root-polynomial, the pixel's gauge in its
    chart's domain, the fade's (start, end) and the polynomial's weight there; with the emitter
    protection, its weight there (1: the inner model, 0: the identity)."""

    camera: str
    delta_e: float
    kind: str
    luminance: float
    applied: tuple[float, float, float]
    configured: tuple[float, float, float]
    lightness: tuple[float, float]
    gauge: float | None = None
    fade: tuple[float, float] | None = None
    weight: float | None = None
    protection: float | None = None

    def miss(self) -> tuple[str, float]:
        """(channel, relative miss) of the channel the config misses most (of those above 1 %
        of the pixel's largest)."""
        a, c = np.asarray(self.applied), np.asarray(self.configured)
        relative = np.abs(c - a) / np.maximum(np.abs(a), 1e-300)
        relative[np.abs(a) < 0.01 * np.abs(a).max()] = 0.0
        k = int(np.argmax(relative))
        return "RGB"[k], float(relative[k])

    def describe(self) -> str:
        channel, relative = self.miss()
        text = (
            f"{self.kind} at {self.luminance:.2g}x the white's luminance ({self.camera}): "
            f"ΔE2000 {self.delta_e:.2f}, the config {100 * relative:.2g} % off `apply` in "
            f"{channel}"
        )
        if min(self.lightness) < 0:
            text += (
                f"; its L* {self.lightness[0]:.3g} (`apply`) and {self.lightness[1]:.3g} (config) "
                "through the camera's matrix: no colour CIELAB defines (L* >= 0), so its "
                "ΔE2000 is no perceptual figure"
            )
        if self.protection is not None:
            text += f"; the emitter protection's weight {self.protection:.2g}"
        if self.gauge is None or self.fade is None or self.weight is None:
            return text
        place = "inside" if self.fade[0] < self.gauge < self.fade[1] else "outside"
        return (
            f"{text}; gauge {self.gauge:.2f}, {place} the fade from {self.fade[0]:g} to "
            f"{self.fade[1]:g} (the polynomial's weight {self.weight:.2g})"
        )


def _worst_pixel(camera, solution, pixels, kinds, applied, configured, errors, matrix, white):
    from ocio_vp.model.correction import ProtectedCorrection, RootPolynomialCorrection

    i = int(np.argmax(errors))
    luminance = float((applied[i] @ matrix.T)[1] / (white @ matrix.T)[1])
    polynomial = solution.correction
    x = pixels[i : i + 1].astype(np.float64)
    place: dict = {}
    if isinstance(polynomial, ProtectedCorrection):
        place["protection"] = float(polynomial.weight(x)[0])
        polynomial = polynomial.inner
    if isinstance(polynomial, RootPolynomialCorrection) and polynomial.domain is not None:
        place |= {
            "gauge": float(polynomial.domain.gauge(x)[0]),
            "fade": tuple(polynomial.fade),
            "weight": float(polynomial.weight(x)[0]),
        }
    lightness = (
        float(_lab(applied[i], matrix, white)[0]),
        float(_lab(configured[i], matrix, white)[0]),
    )
    return WorstPixel(
        camera, float(errors[i]), KINDS[int(kinds[i])], luminance,
        tuple(applied[i].tolist()), tuple(configured[i].tolist()), lightness, **place,
    )  # fmt: skip


def _one(stage, measurements, env, method: str, reflectances):
    """(ΔE2000 per pixel, pixel kinds, the worst pixel, whether CIELAB defines the pixel: L* >= 0
    in both outputs) of one cell on one stage."""
    from ocio_vp.metrics import camera_delta_E_2000
    from ocio_vp.ocio.writer import write_environment
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import camera_rgb, environment_spectrum
    from ocio_vp.simulator.truth import camera_matrix

    protect = method == PROTECT
    solution = solve_environment(
        measurements, env, method="auto" if protect else method, protect_emitters=protect
    )
    pixels, kinds = _pixels(stage, env.name, solution, reflectances)
    with tempfile.TemporaryDirectory(prefix="ocio_vp_hosts_") as folder:
        write_environment(solution, Path(folder))
        applied, configured = _outputs(Path(folder), pixels.copy())
    white = camera_rgb(stage, environment_spectrum(stage, env.name))
    matrix = camera_matrix(stage)
    errors = camera_delta_E_2000(applied, configured, camera_to_xyz=matrix, white=white)
    defined = cielab_defined(applied, configured, matrix)
    worst = _worst_pixel(
        stage.camera_name, solution, pixels, kinds, applied, configured,
        np.where(defined, errors, -np.inf), matrix, white,
    )  # fmt: skip
    return errors, kinds, relative_miss(applied, configured, white), worst, defined


def relative_miss(applied: np.ndarray, configured: np.ndarray, white: np.ndarray) -> np.ndarray:
    """The config's largest channel miss against ``apply``, in % of the pixel's largest channel
    (at least :data:`RELATIVE_FLOOR` of the white's largest): defined for every pixel."""
    scale = np.maximum(np.abs(applied).max(axis=1), RELATIVE_FLOOR * float(np.max(white)))
    return 100.0 * np.abs(configured - applied).max(axis=1) / scale


def host_agreement(
    quick: bool, methods: Sequence[str], progress: Callable[[str], None] | None = None
) -> tuple[dict, dict, dict, float]:
    """({(method, environment): (ΔE2000, pixel kind, relative miss %, CIELAB defines the pixel)
    arrays},
    {(method, environment): refused reason}, {(method, environment): its worst pixel}, seconds)."""
    import time

    from benchmarks.bench_accuracy import GENERAL_SETS, Results, _simulate
    from ocio_vp.errors import InputError
    from ocio_vp.simulator.stage import spectral_stage
    from ocio_vp.simulator.truth import held_out_reflectances, noisy_measurements

    start = time.perf_counter()
    cameras, led_sets, environments, noise, seeds = hosts_config(quick)
    sets = held_out_reflectances("ColorChecker N Ohta")
    reflectances = np.vstack([sets[name] for name in GENERAL_SETS])
    errors: dict = defaultdict(list)
    refused: dict = {}
    worsts: dict[tuple[str, str], WorstPixel] = {}
    for camera in cameras:
        for leds in led_sets:
            stage = spectral_stage(camera=camera, leds=leds)
            clean = _simulate(stage, environments, Results())
            for seed in range(seeds):
                m = noisy_measurements(clean, noise, np.random.default_rng([seed, 31]))
                for env in m.environments:
                    for method in (*methods, PROTECT):
                        key = (method, env.name)
                        try:
                            *cell, worst, defined = _one(stage, m, env, method, reflectances)
                        except InputError as error:
                            refused[key] = error.problem
                            continue
                        errors[key].append((*cell, defined))
                        if key not in worsts or worst.delta_e > worsts[key].delta_e:
                            worsts[key] = worst
            if progress:
                progress(f"hosts: {camera} done")
    pooled = {
        k: tuple(np.concatenate(parts) for parts in zip(*v, strict=True)) for k, v in errors.items()
    }
    return pooled, refused, worsts, time.perf_counter() - start


def _cell(errors: np.ndarray) -> str:
    return f"{np.percentile(errors, 99):.2f} / {np.max(errors):.2f}"


def _misses(delta_e: np.ndarray) -> bool:
    """Whether a cell misses the target (ΔE2000 over the pixels CIELAB defines)."""
    return bool(np.percentile(delta_e, 99) > P99_TARGET or np.max(delta_e) > WORST_TARGET)


def hosts_section(quick: bool, methods: Sequence[str], progress=None) -> str:
    errors, refused, worsts, seconds = host_agreement(quick, methods, progress)
    cameras, led_sets, environments, noise, seeds = hosts_config(quick)
    names = [*methods, PROTECT]
    rows, relative_rows, misses, explained = [], [], [], []
    for env in environments:
        cells, relative_cells = [], []
        for method in names:
            if (method, env) not in errors:
                cells.append("refused" if (method, env) in refused else "-")
                relative_cells.append(cells[-1])
                continue
            e, _, relative, defined = errors[(method, env)]
            cells.append(_cell(e[defined]))
            relative_cells.append(_cell(relative))
            if _misses(e[defined]):
                misses.append(f"`{method}` / {env}")
                if method in ("auto", PROTECT):
                    explained.append(f"- `{method}` / {env}: {worsts[(method, env)].describe()}.")
        rows.append((env, *cells))
        relative_rows.append((env, *relative_cells))
    header = ["environment", *[f"`{m}`" for m in names]]
    table, relative_table = markdown_table(header, rows), markdown_table(header, relative_rows)
    by_kind = []
    for method in names:
        pairs = [errors[(method, env)] for env in environments if (method, env) in errors]
        if not pairs:
            continue
        e, k = np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])
        d = np.concatenate([p[3] for p in pairs])
        by_kind.append(
            (f"`{method}`", *[_cell(e[(k == i) & d]) if np.any((k == i) & d) else "-"
                              for i in range(len(KINDS))])
        )  # fmt: skip
    kinds_table = markdown_table(["method", *KINDS], by_kind)
    leds = "; ".join(", ".join(f"{p:g}/{w:g}" for p, w in s) for s in led_sets)
    return "\n".join(
        [
            "## Host agreement: `apply` against the config's processor",
            "",
            "This section alone: `python -m benchmarks.bench_accuracy --hosts-only --out "
            "docs/accuracy.md` (replaces only this section; a few minutes).",
            "",
            "Each solve written by the product's writer (`ocio_vp.ocio.writer.write_environment`) "
            "and read back as `apply` reads it; the same float32 pixels through `apply`'s pixel "
            "transform (the exact model for a non-linear Q) and through the written config's "
            "`Stage Footage` processor (what hosts see). Pixels: the held-out reflectances lit "
            "by the wall at 1x, 4x and 16x, the narrow-band emitters at 0.25x-16x the scene "
            "white, 200 values near black with negatives. Cells: ΔE2000 between the two "
            "outputs over the pixels CIELAB defines (L* >= 0 in both through the camera's "
            f"matrix), 99th percentile / worst (target {P99_TARGET:g} / {WORST_TARGET:g}); "
            "below, for every pixel (those CIELAB does not define included), the config's "
            "largest channel miss in % of the pixel's largest channel, with no target of its "
            "own. "
            f"Subset (every config is written and baked): cameras {', '.join(cameras)}; LEDs "
            f"{leds} nm; {100 * noise:g}% noise, {seeds} seed; {seconds:.0f} s.",
            "",
            table,
            "",
            "The config's largest channel miss against `apply`, % of the pixel's largest channel "
            f"(at least {RELATIVE_FLOOR:g} of the white's), every pixel, 99th percentile / worst:",
            "",
            relative_table,
            "",
            "Outside the target: " + (", ".join(misses) + "." if misses else "none."),
            "",
            *(
                [
                    "The default's cells outside the target, at their worst pixel: its kind and "
                    "luminance, how far the config is from `apply` there and, where the model "
                    "holds a bounded root-polynomial, the pixel's gauge (where its colour lies in "
                    "the chart's domain: 1 on the hull's edge) against the fade (where the model "
                    "blends the polynomial into its 3x3; the blend creases along the rays through "
                    "the hull's corners, which the LUT's cells cross diagonally). A miss of the "
                    "same relative size weighs more ΔE2000 the brighter the pixel.",
                    "",
                    *explained,
                    "",
                ]
                if explained
                else []
            ),
            "By kind of pixel, ΔE2000 over the pixels CIELAB defines, every environment above pooled "
            "(99th percentile / worst):",
            "",
            kinds_table,
        ]
    )
