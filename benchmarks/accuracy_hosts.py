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
negatives. The figure is ΔE2000 between the two outputs (the stage camera's RGB -> XYZ matrix,
the scene's white at Y = 1); the issue's target is 0.5 at the 99th percentile and 2 at worst.
Because it writes every config (3D LUT bakes for non-linear models) it runs on a subset
(:func:`hosts_config`); the section says which.
"""

from __future__ import annotations

import tempfile
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from benchmarks import markdown_table

__all__ = ["PROTECT", "host_agreement", "hosts_config", "hosts_section"]

#: The label of ``--method auto --protect-emitters`` beside the registry's methods.
PROTECT = "auto --protect-emitters"
P99_TARGET, WORST_TARGET = 0.5, 2.0


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


def _delta_e(a: np.ndarray, b: np.ndarray, matrix: np.ndarray, white: np.ndarray) -> np.ndarray:
    import colour

    white_xyz = white @ matrix.T
    scale = 1.0 / white_xyz[1]
    xy = colour.XYZ_to_xy(white_xyz * scale)
    lab = [colour.XYZ_to_Lab(x @ matrix.T * scale, xy) for x in (a, b)]
    return np.asarray(colour.delta_E(*lab, method="CIE 2000"))


def _one(stage, measurements, env, method: str, reflectances) -> tuple[np.ndarray, np.ndarray]:
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
        applied, configured = _outputs(Path(folder), pixels)
    white = camera_rgb(stage, environment_spectrum(stage, env.name))
    return _delta_e(applied, configured, camera_matrix(stage), white), kinds


def host_agreement(
    quick: bool, methods: Sequence[str], progress: Callable[[str], None] | None = None
) -> tuple[dict, dict, float]:
    """({(method, environment): (ΔE2000, pixel kind) arrays}, {(method, environment): refused
    reason}, seconds)."""
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
    for camera in cameras:
        for leds in led_sets:
            stage = spectral_stage(camera=camera, leds=leds)
            clean = _simulate(stage, environments, Results())
            for seed in range(seeds):
                m = noisy_measurements(clean, noise, np.random.default_rng([seed, 31]))
                for env in m.environments:
                    for method in (*methods, PROTECT):
                        try:
                            errors[(method, env.name)].append(_one(stage, m, env, method,
                                                                   reflectances))  # fmt: skip
                        except InputError as error:
                            refused[(method, env.name)] = error.problem
            if progress:
                progress(f"hosts: {camera} done")
    pooled = {
        k: (np.concatenate([e for e, _ in v]), np.concatenate([kind for _, kind in v]))
        for k, v in errors.items()
    }
    return pooled, refused, time.perf_counter() - start


def _cell(errors: np.ndarray) -> str:
    return f"{np.percentile(errors, 99):.2f} / {np.max(errors):.2f}"


def hosts_section(quick: bool, methods: Sequence[str], progress=None) -> str:
    errors, refused, seconds = host_agreement(quick, methods, progress)
    cameras, led_sets, environments, noise, seeds = hosts_config(quick)
    names = [*methods, PROTECT]
    rows, misses = [], []
    for env in environments:
        cells = []
        for method in names:
            if (method, env) not in errors:
                cells.append("refused" if (method, env) in refused else "-")
                continue
            e = errors[(method, env)][0]
            cells.append(_cell(e))
            if np.percentile(e, 99) > P99_TARGET or np.max(e) > WORST_TARGET:
                misses.append(f"`{method}` / {env}")
        rows.append((env, *cells))
    table = markdown_table(["environment", *[f"`{m}`" for m in names]], rows)
    by_kind = []
    for method in names:
        pairs = [errors[(method, env)] for env in environments if (method, env) in errors]
        if not pairs:
            continue
        e, k = np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])
        by_kind.append((f"`{method}`", *[_cell(e[k == i]) for i in range(len(KINDS))]))
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
            f"outputs, 99th percentile / worst (target {P99_TARGET:g} / {WORST_TARGET:g}). "
            f"Subset (every config is written and baked): cameras {', '.join(cameras)}; LEDs "
            f"{leds} nm; {100 * noise:g}% noise, {seeds} seed; {seconds:.0f} s.",
            "",
            table,
            "",
            "Outside the target: " + (", ".join(misses) + "." if misses else "none."),
            "",
            "By kind of pixel, every environment above pooled (99th percentile / worst):",
            "",
            kinds_table,
        ]
    )
