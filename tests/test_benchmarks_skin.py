"""The skin benchmark's machinery (benchmarks.skin_eval): its ΔE against colour-science's, its
ratios, and where its held-out data lives."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from benchmarks import replace_section
from benchmarks.skin_eval import (
    REFERENCE,
    TUNING_LED_SETS,
    Variant,
    evaluate,
    held_out_skin,
    summarise,
)

ROOT = Path(__file__).resolve().parents[1]
CAMERA = "Nikon 5100 (NPL)"


@pytest.fixture(scope="module")
def small():
    """Least squares and white-preserving, one camera, one LED set, two environments, no noise."""
    return evaluate(
        variant_list=[Variant(REFERENCE, REFERENCE), Variant("wp", "white-preserving")],
        environments=["d65", "incandescent"],
        cameras=[CAMERA],
        led_sets=TUNING_LED_SETS[:1],
        noise=0.0,
    )


def test_skin_delta_e_is_colour_sciences_ciede2000_of_the_stage(small) -> None:
    """Recompute one solve's skin ΔE2000 from the spectra with colour-science directly."""
    import colour

    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import (
        camera_rgb,
        environment_spectrum,
        simulate_measurements,
        spectral_stage,
    )
    from ocio_vp.skin_data import training_skin

    stage = spectral_stage(camera=CAMERA, leds=TUNING_LED_SETS[0])
    measurements = simulate_measurements(["d65", "incandescent"], stage=stage)
    env = measurements.environment("incandescent")
    solution = solve_environment(measurements, env, method="least-squares")
    skin = training_skin().reflectances
    light = environment_spectrum(stage, "incandescent")
    emitted = stage.leds @ np.clip(solution.M @ solution.w_avg, 0, None)
    corrected = camera_rgb(stage, skin * emitted) @ solution.Q.T
    target = camera_rgb(stage, skin * light)
    # Camera RGB -> XYZ: the least-squares fit of the camera to the CIE 1931 observer
    # (ocio_vp.metrics.camera_to_xyz_matrix), the scene white at Y = 1.
    from ocio_vp.metrics import camera_to_xyz_matrix

    matrix = camera_to_xyz_matrix(stage.camera)
    white = camera_rgb(stage, light) @ matrix.T
    scale = 1 / white[1]
    xy = colour.XYZ_to_xy(white * scale)
    expected = colour.delta_E(
        colour.XYZ_to_Lab(target @ matrix.T * scale, xy),
        colour.XYZ_to_Lab(corrected @ matrix.T * scale, xy),
        method="CIE 2000",
    )
    row = next(r for r in small.rows if r.variant == REFERENCE and r.environment == "incandescent")
    np.testing.assert_allclose(row.skin, expected, rtol=1e-9, atol=1e-9)
    assert row.bands == training_skin().bands


def test_ratios_are_to_least_squares_on_the_same_solves(small) -> None:
    ls, wp = summarise(small, REFERENCE), summarise(small, "wp")
    assert ls.skin_ratio == 1.0 and ls.cells_lost == 0 and ls.cells == 2
    rows = {(r.variant, r.environment): r for r in small.rows}
    for env in ("d65", "incandescent"):
        expected = rows[("wp", env)].skin_mean / rows[(REFERENCE, env)].skin_mean
        assert wp.by_environment_ratio[env] == pytest.approx(expected, rel=1e-12)
    mine = np.mean([rows[("wp", e)].skin_mean for e in ("d65", "incandescent")])
    theirs = np.mean([rows[(REFERENCE, e)].skin_mean for e in ("d65", "incandescent")])
    assert wp.skin_ratio == pytest.approx(mine / theirs, rel=1e-12)
    assert wp.cells_lost == sum(
        rows[("wp", e)].skin_mean > 1.02 * rows[(REFERENCE, e)].skin_mean
        for e in ("d65", "incandescent")
    )
    # Per band: the pooled samples of that band, both methods.
    band = "light"
    mask = np.array(rows[("wp", "d65")].bands) == band
    pooled = [
        np.concatenate([rows[(v, e)].skin[mask] for e in ("d65", "incandescent")])
        for v in ("wp", REFERENCE)
    ]
    assert wp.by_band_ratio[band] == pytest.approx(pooled[0].mean() / pooled[1].mean(), rel=1e-12)


def test_the_held_out_skin_is_outside_the_package() -> None:
    assert held_out_skin().split == "held-out"
    assert not list((ROOT / "ocio_vp").rglob("skin_held_out*"))
    for path in (ROOT / "ocio_vp").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "from benchmarks" not in text and "import benchmarks" not in text, path


def test_replace_section_replaces_only_its_own_section() -> None:
    document = "# Accuracy\n\nintro\n\n## A\nold a\n\n### a1\nx\n\n## B\nb\n"
    assert (
        replace_section(document, "## A\nnew a\n")
        == "# Accuracy\n\nintro\n\n## A\nnew a\n\n## B\nb\n"
    )
    assert replace_section(document, "## C\nc\n") == document + "\n## C\nc\n"
    assert replace_section("", "## C\nc") == "## C\nc\n"
    last = replace_section(document, "## B\nnew b\n")
    assert last.endswith("## B\nnew b\n") and "old a" in last
