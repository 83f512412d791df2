"""The host-agreement cell docs/accuracy.md reported outside its target for the default once
the skin work merged: ``auto`` on the Sony ILCE-7SM2 (rawtoaces) stage under D50, 0.5 % noise,
seed 0, built as :mod:`benchmarks.accuracy_hosts` builds it.

Its worst pixel (docs/accuracy.md, host agreement, describes it) is a bright narrow-band blue
emitter that the skin-anchored Q maps to a colour of negative luminance through the stage
camera's 3x3: CIELAB does not define it, and ΔE2000 there is no perceptual figure. The config's
miss on it is real but small: its direction lies inside the root-polynomial's fade to its 3x3,
beside the crease that the domain's polygon puts along the ray through the hull's blue corner,
which the LUT's cells cross diagonally. The test holds the cell's emitters to the hosts' target
where CIELAB defines them, and every emitter to a relative miss below 1 % in each channel (those
above 1 % of the pixel's largest).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

WORST_TARGET = 2.0  # ΔE2000, benchmarks/accuracy_hosts.py's target
RELATIVE_MISS = 0.01


def test_auto_d50_emitters_agree_between_apply_and_the_config():
    from benchmarks.accuracy_hosts import _delta_e, _lab, _outputs, hosts_config
    from benchmarks.bench_accuracy import Results, _simulate
    from ocio_vp.ocio.writer import write_environment
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.extremes import emitters_in_scene
    from ocio_vp.simulator.stage import camera_rgb, environment_spectrum, spectral_stage
    from ocio_vp.simulator.truth import camera_matrix, noisy_measurements

    cameras, led_sets, environments, noise, _ = hosts_config(False)
    stage = spectral_stage(camera="Sony ILCE-7SM2 (rawtoaces)", leds=led_sets[0])
    assert stage.camera_name in cameras
    clean = _simulate(stage, environments, Results())
    m = noisy_measurements(clean, noise, np.random.default_rng([0, 31]))
    solution = solve_environment(m, m.environment("d50"), method="auto")
    emitters = camera_rgb(stage, emitters_in_scene(stage, "d50"))
    pixels = np.vstack([emitters, 4 * emitters]).astype(np.float32)
    with tempfile.TemporaryDirectory(prefix="ocio_vp_crease_") as folder:
        write_environment(solution, Path(folder))
        applied, configured = _outputs(Path(folder), pixels.copy())
    matrix, white = camera_matrix(stage), camera_rgb(stage, environment_spectrum(stage, "d50"))
    errors = _delta_e(applied, configured, matrix, white)
    defined = (_lab(applied, matrix, white)[:, 0] >= 0) & (
        _lab(configured, matrix, white)[:, 0] >= 0
    )
    assert defined.sum() >= 2 * len(pixels) // 3  # the blue emitters (420-470 nm) are not
    assert errors[defined].max() <= WORST_TARGET, f"worst ΔE2000 {errors[defined].max():.2f}"
    large = np.abs(applied) >= 0.01 * np.abs(applied).max(axis=1, keepdims=True)
    miss = np.abs(configured - applied)[large] / np.abs(applied)[large]
    assert miss.max() < RELATIVE_MISS, f"largest relative miss {miss.max():.3%}"
