"""Resolve export, checked by independent readers: ``ociochecklut`` (OCIO's CLI) on each CLF,
colour-science's ``read_LUT`` on each baked ``.cube``, and ``gcc`` compiling the DCTL inside a
small C harness that defines Resolve's DCTL types. Expected values: numpy ``Q c``, ``M c``,
``N c + offset`` from solution.json."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import oracle_correction
from test_exports_unreal import run_tool, solve_to

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.exports import export_solutions
from ocio_vp.exports.resolve import render_dctl
from ocio_vp.formats.solution import load_solution

COLOURS = np.array(
    [
        [0.18, 0.18, 0.18],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.9, 0.4, 0.05],
        [4.0, 2.5, 7.0],
        [0.0, 0.0, 0.0],
    ]
)


def exact(stem: str, solution) -> np.ndarray:
    """The exact transform of each exported file, in numpy (paper eq. 5, 8, Section 3.4)."""
    if stem == "post_correction_Q":
        return COLOURS @ solution.Q.T
    if stem == "wall_out_of_frustum":
        return COLOURS @ solution.M.T
    return COLOURS @ solution.in_frustum_matrix.T + solution.in_frustum_offset


STEMS = ("post_correction_Q", "wall_out_of_frustum", "wall_in_frustum")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    dirs = solve_to(tmp_path_factory.mktemp("resolve") / "solved")
    export_solutions(dirs, targets=["resolve"], cube_size=17)
    return dirs


class TestClf:
    @pytest.mark.parametrize("stem", STEMS)
    def test_ociochecklut(self, exported, stem):
        solution = load_solution(exported[1])
        clf = exported[1] / "exports" / "resolve" / f"{stem}.clf"
        expected = exact(stem, solution)
        for rgb, want in zip(COLOURS, expected, strict=True):
            result = run_tool("ociochecklut", str(clf), *(f"{v!r}" for v in rgb))
            assert result.returncode == 0, result.stderr
            got = np.array([float(v) for v in result.stdout.split()[-3:]])
            # ociochecklut prints 7 significant digits.
            np.testing.assert_allclose(got, want, rtol=2e-6, atol=1e-6)

    def test_offset_is_in_the_matrix(self, exported):
        text = (exported[1] / "exports" / "resolve" / "wall_in_frustum.clf").read_text()
        assert '<Array dim="3 4">' in text  # 3x4: matrix with offset (CLF spec, Matrix node)


def read_manifest(folder: Path) -> dict:
    return json.loads((folder / "manifest.json").read_text())


class TestCube:
    @pytest.mark.parametrize("stem", STEMS)
    def test_colour_reads_cube_within_reported_error(self, exported, stem):
        import colour

        folder = exported[0] / "exports" / "resolve"
        entry = read_manifest(folder)["files"][f"{stem}_17.cube"]["accuracy"]
        assert entry["cube_size"] == 17 and entry["input_range"] == [-0.25, 16.0]
        assert 0 <= entry["max_error"] <= entry["limit"] == pytest.approx(1 / 1023)
        lut = colour.io.read_LUT(str(folder / f"{stem}_17.cube"))
        want = exact(stem, load_solution(exported[0]))
        error = np.abs(lut.apply(COLOURS) - want) / np.maximum(1, np.abs(want))
        # colour evaluates in float64 and OCIO (which measured the report) in float32.
        assert error.max() <= entry["max_error"] + 1e-6, (error.max(), entry)

    def test_identity_is_still_a_3d_cube(self, tmp_path):
        """A transform without crosstalk still gets the documented 3D LUT (OCIO's own baker
        writes a 1D-only cube for it)."""
        import colour
        import PyOpenColorIO as OCIO

        from ocio_vp.exports.cube import fit_cube

        identity = OCIO.Config.CreateRaw().getProcessor(OCIO.MatrixTransform())
        result = fit_cube(identity, tmp_path / "i.cube", size=9, input_range=(-0.25, 16.0))
        assert result.path is not None and result.errors.max_error < 1e-5
        text = result.path.read_text()
        assert "LUT_3D_SIZE 9" in text and "LUT_1D_SIZE" in text
        rgb = np.random.default_rng(2).uniform(-0.25, 16.0, size=(500, 3))
        np.testing.assert_allclose(colour.io.read_LUT(str(result.path)).apply(rgb), rgb,
                                   rtol=1e-5, atol=1e-5)  # fmt: skip

    def test_reported_error_is_real(self, tmp_path):
        """For a curve (gamma 2.4 wall encoding) a coarse bake is visibly inexact: the
        measured error says so, colour-science's reading of the cube stays within it, and
        fit_cube refuses to keep the file."""
        import colour
        import PyOpenColorIO as OCIO

        from ocio_vp.exports.cube import bake_cube, cube_error, fit_cube

        processor = OCIO.Config.CreateRaw().getProcessor(
            OCIO.ExponentTransform(value=[2.4, 2.4, 2.4, 1.0], direction=OCIO.TRANSFORM_DIR_INVERSE)
        )
        cube = bake_cube(processor, tmp_path / "g.cube", size=9, input_range=(0.0, 1.0))
        report = cube_error(processor, cube, input_range=(0.0, 1.0))
        assert report.max_error > 1e-3
        rgb = np.random.default_rng(1).uniform(size=(2000, 3))
        error = np.abs(colour.io.read_LUT(str(cube)).apply(rgb) - rgb ** (1 / 2.4)).max()
        assert 1e-3 < error <= report.max_error + 1e-5
        refused = fit_cube(processor, tmp_path / "r.cube", size=9, input_range=(0.0, 1.0))
        assert refused.path is None and "over the limit" in refused.reason
        assert not list(tmp_path.glob("r*.cube")) and not list(tmp_path.glob(".*trial*"))

    def test_cli_prints_errors(self, exported, tmp_path, capsys):
        assert (
            main(["export", str(exported[0]), "--target", "resolve", "--out", str(tmp_path)]) == 0
        )
        out = capsys.readouterr().out
        # one line per target: the Resolve file for footage (a linear Q: its cube) and where
        # the rest is; every file's accuracy is in the manifest
        assert len(out.splitlines()) == 1, out
        manifest = read_manifest(tmp_path / "env_0" / "resolve")
        worst = manifest["files"]["post_correction_Q_33.cube"]["accuracy"]["max_error"]
        assert worst <= 1 / 1023 and manifest["resolve_file"]["file"] == "post_correction_Q_33.cube"
        assert (
            f"the Resolve file for footage: post_correction_Q_33.cube (worst error {worst:.2g} "
            in out
        )
        assert "wall_in_frustum_33.cube" in manifest["files"]

    def test_bad_cube_size_exits_2(self, exported, tmp_path, capsys):
        code = main(["export", str(exported[0]), "--out", str(tmp_path / "o"), "--cube-size", "1"])
        assert code == 2
        assert "--cube-size" in capsys.readouterr().err
        assert not (tmp_path / "o").exists()

    def test_bad_range(self, exported):
        with pytest.raises(InputError, match="LO < HI"):
            export_solutions(exported[:1], targets=["resolve"], cube_range=(1.0, 1.0))


HARNESS = r"""
#include <stdio.h>
#include <stdlib.h>
#define __DEVICE__ static
typedef struct { float x, y, z; } float3;
static float3 make_float3(float x, float y, float z) { float3 v = {x, y, z}; return v; }
#include "%s"
int main(int argc, char **argv) {
    for (int i = 1; i + 2 < argc; i += 3) {
        float3 o = transform(1, 1, 0, 0, strtof(argv[i], 0), strtof(argv[i + 1], 0),
                             strtof(argv[i + 2], 0));
        printf("%%.9g %%.9g %%.9g\n", o.x, o.y, o.z);
    }
    return 0;
}
"""


#: DCTL's math functions, as C99's (the root-polynomial DCTL uses _powf).
MATH_HARNESS = (
    "#include <math.h>\n#define _powf powf\n#define _fminf fminf\n#define _fmaxf fmaxf\n"
    "#define _log2f log2f\n" + HARNESS
)


def compile_dctl(dctl: Path, tmp_path: Path, harness: str = HARNESS) -> Path:
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not on PATH")
    source = tmp_path / "harness.c"
    source.write_text(harness % dctl.resolve())
    binary = tmp_path / "harness"
    result = subprocess.run(
        [
            "gcc",
            "-std=c99",
            "-Wall",
            "-Werror",
            "-Wno-unused-parameter",
            "-o",
            str(binary),
            str(source),
            "-lm",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return binary


def run_dctl(binary: Path, colours: np.ndarray) -> np.ndarray:
    args = [f"{v!r}" for v in colours.astype(np.float32).astype(float).ravel()]
    result = subprocess.run([str(binary), *args], capture_output=True, text=True, check=True)
    return np.array([[float(v) for v in line.split()] for line in result.stdout.splitlines()])


class TestDctl:
    def test_full_float_precision(self, exported):
        solution = load_solution(exported[0])
        text = (exported[0] / "exports" / "resolve" / "post_correction_Q.dctl").read_text()
        literals = re.findall(r"(-?[0-9.]+(?:e[-+]?\d+)?)f \* p_[RGB]", text)
        values = np.array([float(v) for v in literals]).reshape(3, 3)
        # Every coefficient is the float32 nearest to Q (9 significant digits round-trip).
        np.testing.assert_array_equal(values.astype(np.float32), solution.Q.astype(np.float32))

    def test_compiles_and_matches_numpy(self, exported, tmp_path):
        solution = load_solution(exported[0])
        binary = compile_dctl(
            exported[0] / "exports" / "resolve" / "post_correction_Q.dctl", tmp_path
        )
        got = run_dctl(binary, COLOURS)
        np.testing.assert_allclose(got, COLOURS @ solution.Q.T, rtol=1e-6, atol=1e-6)

    def test_offset_variant(self, tmp_path):
        """The same template with an offset (the in-frustum form N c + offset)."""
        rng = np.random.default_rng(3)
        matrix, offset = rng.normal(size=(3, 3)), rng.normal(size=3) * 0.01
        dctl = tmp_path / "m.dctl"
        dctl.write_text(
            render_dctl(
                title="t", stage="s", environment="e", description="d", matrix=matrix, offset=offset
            )
        )
        got = run_dctl(compile_dctl(dctl, tmp_path), COLOURS)
        np.testing.assert_allclose(got, COLOURS @ matrix.T + offset, rtol=1e-6, atol=2e-6)


def test_root_polynomial_dctl_is_the_model(tmp_path):
    """A root-polynomial Q: the DCTL computes the model itself (gcc-compiled, float32), equal
    to colour-science's expansion @ C^T, black to black, negatives finite; the manifest says
    what the DCTL holds and, for the cube, either its measured accuracy or why it is absent."""
    (folder,) = solve_to(tmp_path / "solved", environments=1, method="root-polynomial")
    export_solutions([folder], targets=["resolve"], cube_size=17)
    resolve = folder / "exports" / "resolve"
    block = json.loads((folder / "solution.json").read_text())["post_correction"]
    colours = np.vstack([COLOURS, [[-0.01, 0.02, 0.0], [1e-8, 2e-8, 0.0], [-1.0, -1.0, -1.0]]])
    got = run_dctl(
        compile_dctl(resolve / "post_correction_Q.dctl", tmp_path, MATH_HARNESS), colours
    )
    x = colours.astype(np.float32).astype(np.float64)
    expected = oracle_correction(block, x)
    scale = np.abs(expected).max(axis=1, keepdims=True)
    assert np.all(np.isfinite(got))
    assert np.all(np.abs(got - expected) <= 1e-5 * scale)
    assert np.array_equal(got[6], np.zeros(3))  # black
    manifest = json.loads((resolve / "manifest.json").read_text())
    assert "root-polynomial" in manifest["files"]["post_correction_Q.dctl"]["accuracy"]
    cube = "post_correction_Q_17.cube"
    assert cube in manifest["files"] or "post_correction_Q.clf" in manifest["not_written"][cube]


# --------------------------------------------------------------------------------------------
# A non-linear Q in every Resolve file, over the camera range footage spans


@pytest.fixture(scope="module")
def model_exports(tmp_path_factory):
    """A root-polynomial (incandescent) and an emitter-protected (direct sun) solve of the
    simulator's paper stage, written and exported to Resolve."""
    from ocio_vp.ocio import write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    stage = paper_stage()
    m = simulate_measurements(["incandescent", "direct_sun"], stage=stage)
    cases = {
        "root-polynomial": ("incandescent", {"method": "root-polynomial"}),
        "protected": ("direct_sun", {"method": "auto", "protect_emitters": True}),
    }
    out = {}
    for case, (env, options) in cases.items():
        root = tmp_path_factory.mktemp(case.replace("-", "_"))
        (solution,) = write_solutions([solve_environment(m, m.environment(env), **options)], root)
        export_solutions([root / env], targets=["resolve"], cube_size=17)
        out[case] = stage, solution, root / env / "exports" / "resolve"
    return out


def _oiiotool_clf(clf: Path, rgb: np.ndarray, tmp_path: Path) -> np.ndarray:
    """``clf`` applied by oiiotool (OpenImageIO's own OpenColorIO build) to a float EXR row."""
    import OpenImageIO as oiio

    if shutil.which("oiiotool") is None:
        pytest.skip("oiiotool is not on PATH")
    src, dst = tmp_path / "in.exr", tmp_path / "out.exr"
    pixels = np.ascontiguousarray(rgb, dtype=np.float32).reshape(1, -1, 3)
    image = oiio.ImageOutput.create(str(src))
    image.open(str(src), oiio.ImageSpec(pixels.shape[1], 1, 3, "float"))
    image.write_image(pixels)
    image.close()
    result = run_tool("oiiotool", str(src), "--ociofiletransform", str(clf), "-d", "float",
                      "-o", str(dst))  # fmt: skip
    assert result.returncode == 0, result.stderr
    return oiio.ImageBuf(str(dst)).get_pixels(oiio.FLOAT).reshape(-1, 3).astype(np.float64)


@pytest.mark.parametrize("case", ["root-polynomial", "protected"])
def test_clf_and_dctl_agree_with_the_model_over_the_camera_range(model_exports, case, tmp_path):
    """Resolve's CLF (the config's LUT chain) through oiiotool, and the DCTL (the model itself)
    compiled by gcc, against the exact model (conftest's independent implementation) on the
    simulator's camera range: both within 0.5 ΔE2000 (p99) and 2 (worst), the DCTL within
    float32 rounding. The manifest gives the CLF's measured agreement and names the DCTL."""
    from ocio_vp.model.footage_range import agreement
    from ocio_vp.simulator.truth import stage_footage_range

    stage, solution, resolve = model_exports[case]
    block = json.loads((resolve.parent.parent / "solution.json").read_text())["post_correction"]
    footage = stage_footage_range(stage, solution.environment, solution)
    exact = lambda rgb: oracle_correction(block, rgb)  # noqa: E731
    clf = agreement(footage, exact, lambda x: _oiiotool_clf(resolve / "post_correction_Q.clf",
                                                            x, tmp_path))  # fmt: skip
    assert clf.within(0.5, 2.0), clf
    binary = compile_dctl(resolve / "post_correction_Q.dctl", tmp_path, MATH_HARNESS)
    dctl = agreement(footage, exact, lambda x: run_dctl(binary, x))
    assert dctl.within(0.01, 0.05), dctl
    manifest = json.loads((resolve / "manifest.json").read_text())
    carriage = manifest["post_correction"]
    assert carriage["kind"] == solution.correction.kind
    assert "post_correction_Q.dctl" in carriage["note"]
    accuracy = manifest["files"]["post_correction_Q.clf"]["accuracy"]
    assert accuracy["delta_E_2000_vs_model"]["worst"]["all"] <= 2.0
    # no cube of a non-linear Q meets the limit here: the DCTL is named as the Resolve file
    assert "post_correction_Q_17.cube" in manifest["not_written"]
    assert manifest["resolve_file"]["file"] == "post_correction_Q.dctl"
