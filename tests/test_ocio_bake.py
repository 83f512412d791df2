"""A non-linear post-correction in the written OCIO config (ocio_vp/ocio/bake.py's LUT chains).

Independent checks: OCIO's own processor (and ``ociochecklut``) evaluates the written files;
the exact model is conftest's ``oracle_correction`` (colour-science's root-polynomial
expansion, the domain's gauge by bisection, the fades written out there); the camera range
footage spans is the simulator's (surfaces lit by the wall with noise, near black, highlights
to 16x white, narrow-band emitters and the wall's primaries).
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import oracle_correction

from ocio_vp.model import correction_to_dict
from ocio_vp.ocio import (
    IN_FRUSTUM,
    POST_CORRECTION,
    POST_CORRECTION_COLORSPACE,
    REFERENCE,
    build_config,
    write_solutions,
)
from ocio_vp.ocio.bake import AGREEMENT_P99, AGREEMENT_WORST, LUT_SIZE

CASES = {
    "root-polynomial": ("incandescent", {"method": "root-polynomial"}),
    "protected": ("direct_sun", {"method": "auto", "protect_emitters": True}),
    # joint lights with its own M: the in-frustum chain inverts Q for the calibrated [SL]
    "joint": ("direct_sun", {"method": "joint", "protect_emitters": True}),
    # sodium vapour: the root-polynomial's 3x3 is rank-deficient, so N is not solved and the
    # model has no inverse; the config must still carry the model forward
    "no-inverse": ("sodium_vapour", {"method": "root-polynomial"}),
}


@pytest.fixture(scope="module")
def stage():
    from ocio_vp.simulator.stage import paper_stage

    return paper_stage()


@pytest.fixture(scope="module")
def written(tmp_path_factory, stage):
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import simulate_measurements

    m = simulate_measurements(sorted({env for env, _ in CASES.values()}), stage=stage)
    out = {}
    for case, (env, options) in CASES.items():
        solution = solve_environment(m, m.environment(env), **options)
        folder = tmp_path_factory.mktemp(case.replace("-", "_"))
        (solution,) = write_solutions([solution], folder)
        out[case] = solution, OCIO.Config.CreateFromFile(str(folder / env / "config.ocio"))
    return out


def _model(solution):
    """The solution's post-correction, applied by the tests' independent implementation."""
    block = correction_to_dict(solution.correction)
    return lambda rgb: oracle_correction(block, rgb)


def _processor(config, src, dst):
    cpu = config.getProcessor(src, dst).getDefaultCPUProcessor()

    def apply(rgb):
        pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
        cpu.applyRGB(pixels)
        return pixels.astype(np.float64)

    return apply


def _sidecar(solution, config, index=0):
    folder = config.getWorkingDir()
    return f"{folder}/{solution.diagnostics.post_correction_ocio.files[index]}"


@pytest.mark.parametrize("case", ["root-polynomial", "protected"])
def test_the_config_agrees_with_the_model_over_the_camera_range(written, stage, case):
    """Stage Footage -> reference against the exact model, ΔE2000 over every set of the
    simulator's camera range: within the limits the hosts are held to (p99 and worst)."""
    from ocio_vp.model.footage_range import agreement
    from ocio_vp.simulator.truth import stage_footage_range

    solution, config = written[case]
    footage = stage_footage_range(stage, solution.environment, solution)
    measured = agreement(
        footage, _model(solution), _processor(config, POST_CORRECTION_COLORSPACE, REFERENCE)
    )
    assert measured.within(AGREEMENT_P99, AGREEMENT_WORST), measured


def test_the_chain_is_the_matrix_where_the_model_is(written):
    """Where the root-polynomial has faded to its 3x3 (far from the chart: saturated colours,
    at any exposure from 1/64 to 64 times white) the chain is that matrix to float precision
    (and the LUT's rounding, 2^-13 stop); where the emitter protection leaves a pixel alone it
    is the identity. (Near black, inside the log's linear segment, neighbouring nodes take
    every direction, so there the chain is only close: the agreement test measures it.)"""
    solution, config = written["root-polynomial"]
    correction = solution.correction
    rng = np.random.default_rng(3)
    x = rng.dirichlet([0.2, 0.2, 0.2], 8000) * np.exp2(rng.uniform(-6, 6, (8000, 1)))
    # well past the fade (the LUT's cells around them hold the matrix too)
    x = x[correction.domain.gauge(x) > correction.fade[1] + 1.0]
    assert len(x) > 1000
    got = _processor(config, POST_CORRECTION_COLORSPACE, REFERENCE)(x)
    want = x @ correction.fallback.T
    assert np.all(np.abs(got - want).max(axis=1) <= 2e-4 * np.abs(want).max(axis=1))

    solution, config = written["protected"]
    bright = rng.dirichlet([0.3, 0.3, 0.3], 4000) * np.exp2(rng.uniform(1, 8, (4000, 1)))
    bright = bright[
        solution.correction.domain.brightness(bright) > 2 * solution.correction.bright[1]
    ]
    assert len(bright) > 1000
    got = _processor(config, POST_CORRECTION_COLORSPACE, REFERENCE)(bright)
    assert np.all(np.abs(got - bright).max(axis=1) <= 2e-4 * np.abs(bright).max(axis=1))


def test_recorded_agreement_is_what_the_config_does(written):
    """solution.json's agreement (quoted in the descriptions and the exports) is measured on
    the config's own processor: recomputed here from the calibration, it is the same."""
    from ocio_vp.metrics import sample_camera_to_xyz
    from ocio_vp.model.footage_range import agreement, calibration_footage_range

    for solution, config in written.values():
        charts = solution.diagnostics.charts
        white = solution.diagnostics.white_patch
        footage = calibration_footage_range(
            lit_chart=charts.lit_baseline, white_patch=white,
            target_white=charts.target[white], SL=solution.SL,
            camera_to_xyz=sample_camera_to_xyz(),
        )  # fmt: skip
        measured = agreement(
            footage, _model(solution), _processor(config, POST_CORRECTION_COLORSPACE, REFERENCE)
        )
        recorded = solution.diagnostics.post_correction_ocio.agreement
        np.testing.assert_allclose(measured.p99["all"], recorded.p99["all"], rtol=1e-3)
        np.testing.assert_allclose(measured.worst["all"], recorded.worst["all"], rtol=1e-3)
        description = config.getColorSpace(POST_CORRECTION_COLORSPACE).getDescription()
        assert f"within {recorded.p99['all']:.2g} ΔE2000 (p99)" in description


def _content(solution, n, rng, exposures=(0.01, 4.0)):
    chart = np.asarray(solution.diagnostics.charts.target)
    mix = rng.dirichlet(np.full(len(chart), 0.3), n) @ chart
    return mix / mix.max() * rng.uniform(*exposures, (n, 1))


@pytest.mark.parametrize("case", ["root-polynomial", "protected", "joint"])
def test_in_frustum_round_trip_through_the_config(written, case):
    """Content -> the config's in-frustum drive (OCIO) -> the wall [SL] -> the exact model:
    the content again, within 0.5 ΔE2000 (p99) and 2 (worst), content in the chart's gamut
    from 1 % to 4x its white. The 3x3 approximation the config used before is worse."""
    from ocio_vp.metrics import delta_E_2000, sample_camera_to_xyz

    solution, config = written[case]
    model = _model(solution)
    c = _content(solution, 3000, np.random.default_rng(7))
    drive = _processor(config, REFERENCE, IN_FRUSTUM)(c) - solution.in_frustum_offset
    seen = model(drive @ np.asarray(solution.SL).T)
    white = np.asarray(solution.diagnostics.charts.target)[18]
    de = delta_E_2000(seen, c, camera_to_xyz=sample_camera_to_xyz(), white=white)
    assert np.percentile(de, 99) <= AGREEMENT_P99 and de.max() <= AGREEMENT_WORST
    seen_3x3 = model((c @ np.asarray(solution.N).T) @ np.asarray(solution.SL).T)
    de_3x3 = delta_E_2000(seen_3x3, c, camera_to_xyz=sample_camera_to_xyz(), white=white)
    assert de_3x3.mean() > 2 * de.mean()


def test_both_directions_of_the_post_correction_are_the_model(written):
    """reference -> Stage Footage (and the named transform inverted) is the baked Q^-1: the
    exact model maps its output back to the content. OCIO is never left to invert the Q LUT."""
    solution, config = written["root-polynomial"]
    c = _content(solution, 2000, np.random.default_rng(10), (0.05, 4.0))
    for apply in (
        _processor(config, REFERENCE, POST_CORRECTION_COLORSPACE),
        _named_inverse(config),
    ):
        back = _model(solution)(apply(c))
        assert (np.abs(back - c).max(axis=1) / c.max(axis=1)).max() < 2e-3


def _named_inverse(config):
    named = config.getNamedTransform(POST_CORRECTION)
    cpu = config.getProcessor(named, OCIO.TRANSFORM_DIR_INVERSE).getDefaultCPUProcessor()

    def apply(rgb):
        pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
        cpu.applyRGB(pixels)
        return pixels.astype(np.float64)

    return apply


def test_a_model_without_inverse_is_still_carried(written):
    """Sodium vapour, root-polynomial: N is not solved and the model has no inverse. The
    config still carries the model (not its 3x3) from footage to the reference; the other
    direction is a bounded stand-in its description marks as NOT the model's inverse."""
    solution, config = written["no-inverse"]
    assert solution.N is None and not solution.correction.invertible
    assert len(solution.diagnostics.post_correction_ocio.files) == 1
    lit = np.asarray(solution.diagnostics.charts.lit_baseline)
    x = lit * np.exp2(np.random.default_rng(4).uniform(-3, 1, (len(lit), 1)))
    got = _processor(config, POST_CORRECTION_COLORSPACE, REFERENCE)(x)
    want = _model(solution)(x)
    relative = np.abs(got - want).max(axis=1) / np.abs(want).max(axis=1)
    relative_3x3 = np.abs(x @ solution.Q.T - want).max(axis=1) / np.abs(want).max(axis=1)
    assert np.median(relative) < 0.02 and np.median(relative_3x3) > 10 * np.median(relative)
    description = config.getColorSpace(POST_CORRECTION_COLORSPACE).getDescription()
    assert "NOT PROVIDED as the model's inverse" in description
    back = _processor(config, REFERENCE, POST_CORRECTION_COLORSPACE)(want)
    assert np.all(np.isfinite(back)) and np.abs(back).max() < 1e6


def test_no_config_carries_a_3x3_for_a_model(written):
    """build_config without the LUT files of a non-linear Q refuses (it would silently carry
    the 3x3 where ocio-vp apply runs the model)."""
    for solution, _ in written.values():
        with pytest.raises(ValueError, match="needs its LUT files"):
            build_config(solution)


def test_finite_everywhere(written):
    probe = np.random.default_rng(8).uniform(-1.0, 16.0, (20000, 3))
    probe = np.vstack([probe, probe * 1e-6, probe * 1e3, np.zeros((1, 3))])
    for _solution, config in written.values():
        pairs = [(POST_CORRECTION_COLORSPACE, REFERENCE), (REFERENCE, POST_CORRECTION_COLORSPACE)]
        pairs.append((REFERENCE, IN_FRUSTUM))
        for src, dst in pairs:
            assert np.all(np.isfinite(_processor(config, src, dst)(probe))), (src, dst)


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
def test_ociocheck_accepts_the_configs(written):
    for _solution, config in written.values():
        path = f"{config.getWorkingDir()}/config.ocio"
        result = subprocess.run(["ociocheck", "--iconfig", path], capture_output=True, text=True)
        assert result.returncode == 0 and "ERROR" not in result.stdout + result.stderr


@pytest.mark.skipif(shutil.which("ociochecklut") is None, reason="ociochecklut not on PATH")
def test_ociochecklut_reads_the_q_sidecar(written):
    """OCIO's own LUT checker evaluates the written Q file: the exact model's values (within
    1 %, and near black within 1e-4 of white: under 0.5 ΔE2000), black stays black, noise
    below black stays finite."""
    solution, config = written["root-polynomial"]
    model = _model(solution)
    lit = np.asarray(solution.diagnostics.charts.lit_baseline)
    for rgb in [lit[0], lit[13], lit[18] * 8, lit[5] * 1e-3, [-0.001, 0.002, 0.0005]]:
        result = subprocess.run(
            ["ociochecklut", _sidecar(solution, config), *(f"{v:.9g}" for v in rgb)],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        got = np.array(result.stdout.split()[-3:], dtype=float)
        ref = model(np.asarray(rgb, dtype=float))
        assert np.abs(got - ref).max() <= 1e-2 * np.abs(ref).max() + 1e-4 * lit[18].max()
    black = subprocess.run(
        ["ociochecklut", _sidecar(solution, config), "0", "0", "0"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    assert np.all(np.abs(np.array(black.stdout.split()[-3:], dtype=float)) < 1e-6)


def _lut3d_numbers(clf_text: str) -> np.ndarray:
    body = clf_text.split("<LUT3D", 1)[1].split("<Array", 1)[1]
    return np.array(body.split(">", 1)[1].split("</Array>", 1)[0].split(), dtype=np.float64)


def test_sidecars_are_clf_v3_and_read_back_as_written(written):
    """Every sidecar holds only CLF v3 process nodes (Matrix, Log, LUT1D, LUT3D: what Resolve
    and OCIO's CLF writer take); OCIO parses it and its own CLF writer gives back the same 3D
    LUT, number for number. Past the last scale node the cube holds one clamp slice (a copy
    of the last) and zeros, which the chain never reaches."""
    for solution, config in written.values():
        for index, _ in enumerate(solution.diagnostics.post_correction_ocio.files):
            text = Path(_sidecar(solution, config, index)).read_text(encoding="utf-8")
            nodes = set(re.findall(r"<(\w+)[ >]", text.split("<ProcessList", 1)[1]))
            assert nodes - {"Description", "Array", "LogParams"} <= {
                "Matrix", "Log", "LUT1D", "LUT3D"
            }, nodes  # fmt: skip
            assert 'compCLFversion="3.0"' in text
            ours = _lut3d_numbers(text)
            group = (
                OCIO.Config.CreateRaw()
                .getProcessor(OCIO.FileTransform(src=_sidecar(solution, config, index)))
                .createGroupTransform()
            )
            theirs = _lut3d_numbers(group.write(formatName="Academy/ASC Common LUT Format"))
            assert ours.shape == theirs.shape == (LUT_SIZE**3 * 3,)
            np.testing.assert_array_equal(ours, theirs)
            slices = ours.reshape(LUT_SIZE, LUT_SIZE**2, 3)
            used = int(np.flatnonzero(np.any(slices != 0, axis=(1, 2)))[-1])
            np.testing.assert_array_equal(slices[used], slices[used - 1])


def test_auto_d50_emitters_agree_between_apply_and_the_config():
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
    from benchmarks.accuracy_hosts import _outputs, cielab_defined, hosts_config
    from benchmarks.bench_accuracy import Results, _simulate
    from ocio_vp.metrics import camera_delta_E_2000
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
    errors = camera_delta_E_2000(applied, configured, camera_to_xyz=matrix, white=white)
    defined = cielab_defined(applied, configured, matrix)
    assert defined.sum() >= 2 * len(pixels) // 3  # the blue emitters (420-470 nm) are not
    assert errors[defined].max() <= AGREEMENT_WORST, f"worst ΔE2000 {errors[defined].max():.2f}"
    large = np.abs(applied) >= 0.01 * np.abs(applied).max(axis=1, keepdims=True)
    miss = np.abs(configured - applied)[large] / np.abs(applied)[large]
    assert miss.max() < 0.01, f"largest relative miss {miss.max():.3%}"


def test_the_inverse_refuses_content_with_no_light():
    # d96a980 failed on an empty .min() here; a silent box around neutral would hide it.
    from ocio_vp.errors import InputError
    from ocio_vp.ocio.bake import inverse_chain

    with pytest.raises(InputError, match="no target chart colour has light"):
        inverse_chain(None, -np.ones((4, 3)))  # type: ignore[arg-type]
