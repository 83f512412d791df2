"""A root-polynomial Q in the written OCIO config: the in-frustum round trip through the config.

Independent check: OCIO's own processor evaluates the written config (reference -> in-frustum
drive, camera -> reference for footage); the wall is simulated by [SL], and the exact forward
model (colour-science's root-polynomial expansion) closes the loop: Q([SL] N(c)) = c.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import oracle_correction

from ocio_vp.model import correction_to_dict
from ocio_vp.ocio import IN_FRUSTUM, POST_CORRECTION_COLORSPACE, REFERENCE, write_solutions
from ocio_vp.pipeline import solve_environment


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("incandescent",))
    solution = solve_environment(m, m.environments[0], method="root-polynomial")
    out = tmp_path_factory.mktemp("rp") / "out"
    (written_solution,) = write_solutions([solution], out)
    return written_solution, out / "incandescent" / "config.ocio"


def _model(solution):
    """The solution's post-correction, applied by the tests' independent implementation."""
    block = correction_to_dict(solution.correction)
    return lambda rgb: oracle_correction(block, rgb)


def _apply(config, src, dst, rgb):
    cpu = config.getProcessor(src, dst).getDefaultCPUProcessor()
    pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu.applyRGB(pixels)
    return pixels.astype(np.float64)


def _content(solution, n, rng, exposures=(0.05, 4.0)):
    chart = solution.diagnostics["charts"]["target"]
    mix = rng.dirichlet(np.full(len(chart), 0.3), n) @ chart
    return mix / mix.max() * rng.uniform(*exposures, (n, 1))


#: The stated limit (docs/root_polynomial.md): the bake's error is at most 0.1 % of each
#: colour's largest channel for content inside the target chart's gamut, at any exposure.
LIMIT = 0.001


def test_in_frustum_round_trip_through_the_config(written):
    solution, path = written
    config = OCIO.Config.CreateFromFile(str(path))
    model = _model(solution)
    rng = np.random.default_rng(7)
    # Down to 1e-4 of white: below, OCIO's float32 sum of the drive and the black-level offset
    # (~0.08) and its subtraction here lose more than the bake (5e-9 of 1e-6 is 0.5 %).
    c = np.vstack([_content(solution, 4000, rng), _content(solution, 1000, rng, (1e-4, 1e-2))])
    drive = _apply(config, REFERENCE, IN_FRUSTUM, c) - solution.in_frustum_offset
    seen = model(drive @ np.asarray(solution.SL).T)
    error = np.abs(seen - c).max(axis=1) / c.max(axis=1)
    assert error.max() < LIMIT
    # The 3x3 approximation the config used before is clearly worse.
    seen_3x3 = model((c @ np.asarray(solution.N).T) @ np.asarray(solution.SL).T)
    assert np.abs(seen_3x3 - c).max(axis=1).mean() > 3 * np.abs(seen - c).max(axis=1).mean()
    block = solution.diagnostics["root_polynomial_ocio"]
    assert block["bake_error"]["finite_on_minus1_to_16"]


def test_footage_q_and_finite_everywhere(written):
    solution, path = written
    config = OCIO.Config.CreateFromFile(str(path))
    model = _model(solution)
    rng = np.random.default_rng(8)
    x = np.linalg.solve(np.asarray(solution.Q), _content(solution, 2000, rng).T).T
    x = x[np.all(x >= 0, axis=1)]
    got = _apply(config, POST_CORRECTION_COLORSPACE, REFERENCE, x)
    ref = model(x)
    assert (np.abs(got - ref).max(axis=1) / ref.max(axis=1)).max() < LIMIT
    probe = rng.uniform(-1.0, 16.0, (20000, 3))
    for src, dst in ((POST_CORRECTION_COLORSPACE, REFERENCE), (REFERENCE, IN_FRUSTUM)):
        assert np.all(np.isfinite(_apply(config, src, dst, probe)))


def test_reference_to_footage_is_the_exact_inverse(written):
    """The other direction (a host converting reference -> Stage Footage, or applying the
    named transform inversely) is the baked Q^-1, checked against the model's own inverse, which
    the independent forward model maps back to the content: OCIO is never left to invert the Q
    LUT itself."""
    from ocio_vp.ocio import POST_CORRECTION

    solution, path = written
    config = OCIO.Config.CreateFromFile(str(path))
    c = _content(solution, 2000, np.random.default_rng(10))
    ref = solution.correction.inverse(c)
    np.testing.assert_allclose(_model(solution)(ref), c, rtol=1e-9, atol=1e-12)
    ref_max = np.abs(ref).max(axis=1)
    got = _apply(config, REFERENCE, POST_CORRECTION_COLORSPACE, c)
    assert (np.abs(got - ref).max(axis=1) / ref_max).max() < LIMIT
    named = config.getNamedTransform(POST_CORRECTION)
    cpu = config.getProcessor(named, OCIO.TRANSFORM_DIR_INVERSE).getDefaultCPUProcessor()
    pixels = np.ascontiguousarray(c, dtype=np.float32).copy()
    cpu.applyRGB(pixels)
    assert (np.abs(pixels - ref).max(axis=1) / ref_max).max() < LIMIT


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
def test_ociocheck_accepts_the_config(written):
    _, path = written
    result = subprocess.run(["ociocheck", "--iconfig", str(path)], capture_output=True, text=True)
    assert result.returncode == 0 and "ERROR" not in result.stdout + result.stderr


@pytest.mark.skipif(shutil.which("ociochecklut") is None, reason="ociochecklut not on PATH")
def test_ociochecklut_reads_the_q_sidecar(written):
    """OCIO's own LUT checker evaluates the written Q file on a few colours: the exact model's
    values within the stated limit, and black stays (effectively) black."""
    solution, path = written
    model = _model(solution)
    sidecar = path.parent / solution.diagnostics["root_polynomial_ocio"]["files"][0]
    x = np.linalg.solve(np.asarray(solution.Q), _content(solution, 4, np.random.default_rng(9)).T).T
    for rgb in [*x, x[0] * 1e-5, x[1] * 12]:
        result = subprocess.run(
            ["ociochecklut", str(sidecar), *(f"{v:.9g}" for v in rgb)],
            capture_output=True,
            text=True,
            check=True,
        )
        got = np.array(result.stdout.split()[-3:], dtype=float)
        ref = model(rgb)
        assert np.abs(got - ref).max() <= LIMIT * np.abs(ref).max()
    black = subprocess.run(
        ["ociochecklut", str(sidecar), "0", "0", "0"], capture_output=True, text=True, check=True
    )
    assert np.all(np.abs(np.array(black.stdout.split()[-3:], dtype=float)) < 1e-8)


def _lut3d_numbers(clf_text: str) -> np.ndarray:
    body = clf_text.split("<LUT3D", 1)[1].split("<Array", 1)[1]
    return np.array(body.split(">", 1)[1].split("</Array>", 1)[0].split(), dtype=np.float64)


def test_q_sidecar_lut_reads_back_as_written(written):
    """The 3D LUT's text (formatted slice by slice) is what OCIO reads: OCIO parses the written
    Q file and its own CLF writer gives back the same numbers. On the scale axis only the first
    cell holds values (the function is affine in scale) plus one slice of clamp; the rest is
    zeros, which the chain never reaches (the other tests go through the whole config)."""
    solution, path = written
    sidecar = path.parent / solution.diagnostics["root_polynomial_ocio"]["files"][0]
    text = sidecar.read_text(encoding="utf-8")
    ours = _lut3d_numbers(text)
    group = (
        OCIO.Config.CreateRaw()
        .getProcessor(OCIO.FileTransform(src=str(sidecar), interpolation=OCIO.INTERP_TETRAHEDRAL))
        .createGroupTransform()
    )
    theirs = _lut3d_numbers(group.write(formatName="Academy/ASC Common LUT Format"))
    size = solution.diagnostics["root_polynomial_ocio"]["lut_size"]
    assert ours.shape == theirs.shape == (size**3 * 3,)
    np.testing.assert_array_equal(ours, theirs)
    slices = ours.reshape(size, size * size, 3)
    np.testing.assert_array_equal(slices[2], slices[1])
    assert not np.any(slices[3:]) and np.any(slices[1])
    # one cell spans the whole scale range: docs/root_polynomial.md's exposures 2^-32..2^16,
    # 48 stops, in its 2^-16-stop steps, on every entry
    np.testing.assert_array_equal(slices[1] - slices[0], 48 * 2**16)
