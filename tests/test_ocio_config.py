"""The written OCIO config, checked by meaning: colours pushed through OCIO's own processors."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import colour
import numpy as np
import PyOpenColorIO as OCIO
import pytest
from conftest import make_measurements_dict

from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.ocio import config as oc
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements
from ocio_vp.wall.encoding import with_wall_encoding

COLOURS = np.random.default_rng(7).uniform(-0.2, 4.0, size=(64, 3))  # HDR and negative too


def _apply(processor: OCIO.Processor, rgb: np.ndarray) -> np.ndarray:
    cpu = processor.getDefaultCPUProcessor()
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu.applyRGB(out)
    return out.astype(np.float64)


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> tuple[Path, list]:
    data = make_measurements_dict(seed=11)
    data["stage"]["camera_colorspace"] = "ARRI Wide Gamut 4"
    solutions = solve_measurements(measurements_from_dict(data), method="least-squares")
    out = tmp_path_factory.mktemp("calib")
    return out, write_solutions(solutions, out)


def _close(actual: np.ndarray, matrix: np.ndarray, offset=None) -> None:
    """OCIO's CPU path is float32: allow 1e-6 of the terms' magnitude, |matrix| |c| + |offset|."""
    offset = np.zeros(3) if offset is None else offset
    expected = COLOURS @ matrix.T + offset
    scale = np.abs(COLOURS) @ np.abs(matrix).T + np.abs(offset)
    assert np.all(np.abs(actual - expected) <= 1e-6 * scale + 1e-9), np.max(
        np.abs(actual - expected) / scale
    )


def test_processors_match_numpy(written) -> None:
    out, solutions = written
    for s in solutions:
        config = OCIO.Config.CreateFromFile(str(out / s.environment / "config.ocio"))
        # float32 processing: compare with a tolerance relative to the values' size.
        outer = _apply(config.getProcessor(oc.REFERENCE, oc.OUT_OF_FRUSTUM), COLOURS)
        _close(outer, s.M)
        inner = _apply(config.getProcessor(oc.REFERENCE, oc.IN_FRUSTUM), COLOURS)
        _close(inner, s.N, s.black_level_offset)
        footage = _apply(config.getProcessor(oc.POST_CORRECTION_COLORSPACE, oc.REFERENCE), COLOURS)
        _close(footage, s.Q)
        named = config.getNamedTransform(oc.POST_CORRECTION)
        q = _apply(config.getProcessor(named.getTransform(OCIO.TRANSFORM_DIR_FORWARD)), COLOURS)
        _close(q, s.Q)
        view = _apply(
            config.getProcessor(
                oc.REFERENCE, oc.DISPLAY, oc.VIEW_INNER, OCIO.TRANSFORM_DIR_FORWARD
            ),
            COLOURS,
        )
        _close(view, s.N, s.black_level_offset)


def test_working_spaces_use_colour_science_matrices(written) -> None:
    out, solutions = written
    config = OCIO.Config.CreateFromFile(str(out / solutions[0].environment / "config.ocio"))
    to_camera = colour.matrix_RGB_to_RGB(
        colour.RGB_COLOURSPACES["ACEScg"],
        colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"],
        chromatic_adaptation_transform="CAT02",
    )
    _close(_apply(config.getProcessor("ACEScg", oc.REFERENCE), COLOURS), to_camera)
    assert config.getRoleColorSpace("aces_interchange") == "ACES2065-1"


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
def test_ociocheck_passes(written) -> None:
    out, solutions = written
    for s in solutions:
        result = subprocess.run(
            ["ociocheck", "--iconfig", str(out / s.environment / "config.ocio")],
            capture_output=True,
            text=True,
            check=False,
        )
        assert result.returncode == 0, result.stdout + result.stderr
        assert "Validation: passed" in result.stdout or "passed" in result.stdout.lower()


def test_profile_version_and_descriptions(written) -> None:
    out, solutions = written
    s = solutions[0]
    text = (out / s.environment / "config.ocio").read_text()
    assert text.startswith("ocio_profile_version: 2.1")
    config = OCIO.Config.CreateFromFile(str(out / s.environment / "config.ocio"))
    inner = config.getColorSpace(oc.IN_FRUSTUM).getDescription()
    assert s.environment in inner and "black-level offset" in inner
    assert s.measurements_sha256 is None or s.measurements_sha256[:16] in inner
    assert sorted(config.getViews(oc.DISPLAY)) == sorted([oc.VIEW_INNER, oc.VIEW_OUTER, "Raw"])


def test_xyz_interchange_matches_colour_science(written) -> None:
    # Independent path: colour.RGB_to_XYZ with CAT02 adaptation to D65.
    out, solutions = written
    config = OCIO.Config.CreateFromFile(str(out / solutions[0].environment / "config.ocio"))
    assert config.getRoleColorSpace("cie_xyz_d65_interchange") == "CIE-XYZ-D65"
    got = _apply(config.getProcessor(oc.REFERENCE, "CIE-XYZ-D65"), COLOURS)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    expected = colour.RGB_to_XYZ(
        COLOURS,
        colour.RGB_COLOURSPACES["ARRI Wide Gamut 4"],
        d65,
        chromatic_adaptation_transform="CAT02",
    )
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize(
    ("wall", "encoding"),
    [(None, "scene-linear"), ("gamma2.4", "sdr-video"), ("pq", "hdr-video")],
)
def test_wall_colorspace_encoding_follows_the_wall_signal(written, wall, encoding) -> None:
    import dataclasses

    _, solutions = written
    solution = dataclasses.replace(solutions[0], linearity=None)
    if wall is not None:
        solution = with_wall_encoding(solution, wall)
    config = oc.build_config(solution)
    for name in (oc.OUT_OF_FRUSTUM, oc.IN_FRUSTUM):
        assert config.getColorSpace(name).getEncoding() == encoding


# --------------------------------------------------------------------------------------------
# Every processor of every exported file, with the installed OCIO: the invariants that
# benchmarks/ocio_compat.py checks across OCIO 2.2-2.6 (there also against each other).


@pytest.fixture(scope="module")
def exported_matrix(tmp_path_factory) -> list[Path]:
    """The demo's sodium environment (rank-1 Q) and a PQ wall with a linearity LUT, solved and
    exported to every target through the command line."""
    import yaml

    from benchmarks.ocio_compat import add_ramps
    from ocio_vp.cli import main

    root = tmp_path_factory.mktemp("compat")
    # Matrices only: auto's rank-1 Q for sodium, least squares for the PQ wall (auto's
    # root-polynomial elsewhere would make LUTs, tested in test_ocio_root_polynomial). The
    # demo's stage file is the committed sample (tests/test_simulator_samples.py keeps it so).
    stage = Path(__file__).resolve().parent.parent / "sample_configs" / "paper_stage.yaml"
    sodium = ["solve", str(stage), "--out", str(root / "auto"), "--environment", "sodium_vapour"]
    assert main(sodium) == 0
    ramps = root / "ramps.yaml"
    ramps.write_text(yaml.safe_dump(add_ramps(yaml.safe_load(stage.read_text()))))
    args = ["solve", str(ramps), "--out", str(root / "pq"), "--wall-encoding", "pq"]
    assert main([*args, "--environment", "incandescent", "--method", "least-squares"]) == 0
    folders = [root / "auto" / "sodium_vapour", root / "pq" / "incandescent"]
    assert main(["export", *map(str, folders)]) == 0
    return folders


def test_every_processor_is_bounded_finite_and_has_a_shader(exported_matrix):
    from benchmarks.ocio_compat import test_inputs
    from benchmarks.ocio_compat_worker import run

    results, problems, count, slowest = run(test_inputs(), exported_matrix)
    assert problems == [] and slowest[0] > 0
    assert count > 300 and len(results) > 100
    for values in results.values():
        assert np.abs(values).max() <= 1e6


def test_singular_q_has_a_bounded_inverse(exported_matrix):
    """Sodium's Q is rank 1: reference -> Stage Footage used to return ~1e17 for (1, 1, 1).
    The inverse direction is the truncated pseudo-inverse (numpy's pinv at the same cutoff)."""
    config = OCIO.Config.CreateFromFile(str(exported_matrix[0] / "config.ocio"))
    Q = np.array(json.loads((exported_matrix[0] / "solution.json").read_text())["Q"])
    assert np.linalg.matrix_rank(Q, tol=np.linalg.norm(Q, 2) / 1e3) == 1
    rgb = np.array([[1.0, 1.0, 1.0], [16.0, -1.0, 16.0], [0.18, 0.2, 0.1]])
    got = _apply(config.getProcessor(oc.REFERENCE, oc.POST_CORRECTION_COLORSPACE), rgb)
    want = rgb @ np.linalg.pinv(Q, rcond=1e-3).T
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)
    named = config.getNamedTransform(oc.POST_CORRECTION)
    inverse = config.getProcessor(named.getTransform(OCIO.TRANSFORM_DIR_INVERSE))
    np.testing.assert_allclose(_apply(inverse, rgb), want, rtol=1e-5, atol=1e-5)
    # the forward direction is still Q exactly
    forward = _apply(config.getProcessor(oc.POST_CORRECTION_COLORSPACE, oc.REFERENCE), rgb)
    np.testing.assert_allclose(forward, rgb @ Q.T, rtol=1e-5, atol=1e-6)


def test_negative_drive_is_black_before_the_pq_curve(exported_matrix):
    """Content whose in-frustum drive has a negative channel is shown as that channel at black:
    making the drive more negative changes nothing (OCIO 2.4+ mirrors negatives through the
    PQ builtin, 2.2/2.3 clamp them; the explicit clamp makes both give the same numbers)."""
    folder = exported_matrix[1]
    N = np.array(json.loads((folder / "solution.json").read_text())["N"])
    config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
    processor = config.getProcessor(oc.REFERENCE, oc.IN_FRUSTUM)
    content = np.array([[-0.05, 0.1, 0.2], [0.3, -0.02, 0.05]])
    drive = content @ N.T
    assert drive[0, 0] < 0 and drive[1, 1] < 0
    more_negative = content - 0.5 * np.linalg.solve(N, np.eye(3)[:, :2]).T  # drive - 0.5 e_k
    signal = _apply(processor, content)
    np.testing.assert_allclose(_apply(processor, more_negative), signal, atol=1e-6)
    assert signal.min() >= 0


def test_every_clf_is_academy_clf_v3(exported_matrix):
    colour_clf_io = pytest.importorskip("colour_clf_io", reason="colour-clf-io not installed")
    clfs = [p for folder in exported_matrix for p in folder.rglob("*.clf")]
    assert len(clfs) == 9  # 3 Resolve CLFs each; the PQ wall sidecar in the solve + 2 copies
    for clf in clfs:
        assert 'xmlns="urn:AMPAS:CLF:v3.0"' in clf.read_text()
        assert colour_clf_io.read_clf(clf.read_bytes()) is not None


# --------------------------------------------------------------------------------------------
# Both directions of every colorspace and named transform, given explicitly


@pytest.fixture(scope="module")
def every_kind(tmp_path_factory, exported_matrix) -> list[OCIO.Config]:
    """Configs of every kind of post-correction: a matrix, the identity, a rank-deficient
    matrix, a root-polynomial (and one with no inverse, under sodium), an emitter-protected
    matrix; and a PQ wall with a linearity LUT."""
    from ocio_vp.formats.measurements import with_camera_colorspace
    from ocio_vp.ocio import write_solutions
    from ocio_vp.pipeline import solve_environment
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("rgb_led_white", "sodium_vapour", "direct_sun"))
    # a camera gamut: the camera's log spaces, ACEScct and the Q look join the config
    m_gamut = with_camera_colorspace(m, "ARRI Wide Gamut 4", key="camera_colorspace")
    runs = [
        ("direct_sun", {"method": "least-squares"}),
        ("rgb_led_white", {"method": "auto"}),
        ("sodium_vapour", {"method": "auto"}),
        ("direct_sun", {"method": "root-polynomial"}),
        ("sodium_vapour", {"method": "root-polynomial"}),
        ("direct_sun", {"method": "least-squares", "protect_emitters": True}),
        ("direct_sun", {"method": "root-polynomial", "gamut": True}),
    ]
    configs = []
    for i, (env, options) in enumerate(runs):
        out = tmp_path_factory.mktemp(f"kind{i}")
        source = m_gamut if options.pop("gamut", False) else m
        write_solutions([solve_environment(source, source.environment(env), **options)], out)
        configs.append(OCIO.Config.CreateFromFile(str(out / env / "config.ocio")))
    pq = exported_matrix[1] / "config.ocio"
    return [*configs, OCIO.Config.CreateFromFile(str(pq))]


def _leaves(transform, inverted=False):
    """Every transform inside ``transform`` with whether it runs inverted."""
    flip = inverted ^ (transform.getDirection() == OCIO.TRANSFORM_DIR_INVERSE)
    if isinstance(transform, OCIO.GroupTransform):
        for child in transform:
            yield from _leaves(child, flip)
    else:
        yield transform, flip


def _holds_a_3d_lut(config, transform) -> bool:
    if isinstance(transform, OCIO.Lut3DTransform):
        return True
    if not isinstance(transform, OCIO.FileTransform):
        return False
    path = Path(config.getWorkingDir()) / config.getSearchPath() / transform.getSrc()
    return "<LUT3D" in path.read_text(encoding="utf-8")


def _inverts_no_lut3d(config, transform) -> bool:
    return not any(inverted and _holds_a_3d_lut(config, t) for t, inverted in _leaves(transform))


def _one_way_is_analytic(config, transform) -> bool:
    """A direction OCIO may invert by itself: nothing in it is a 3D LUT (matrices, curves,
    ranges and 1D LUTs invert exactly or by a quick table)."""
    return not any(_holds_a_3d_lut(config, t) for t, _ in _leaves(transform))


def test_every_direction_is_explicit_and_no_lut3d_is_inverted(every_kind):
    """Every colorspace carrying the post-correction or the wall, and every named transform,
    gives both directions; any other colorspace or look given one way holds no 3D LUT (OCIO
    inverts the rest exactly: matrices, curves, 1D LUTs); and no direction asks OCIO to invert
    a 3D LUT (a search: ~230 s for a 65^3 cube in OCIO 2.6). Each direction builds."""
    for config in every_kind:
        for space in config.getColorSpaces():
            there = space.getTransform(OCIO.COLORSPACE_DIR_FROM_REFERENCE)
            back = space.getTransform(OCIO.COLORSPACE_DIR_TO_REFERENCE)
            if there is None and back is None:
                continue
            name = space.getName()
            if name in (oc.POST_CORRECTION_COLORSPACE, oc.IN_FRUSTUM, oc.OUT_OF_FRUSTUM):
                assert there is not None and back is not None, name
            given = [t for t in (there, back) if t is not None]
            if len(given) == 1:
                assert _one_way_is_analytic(config, given[0]), name
            assert all(_inverts_no_lut3d(config, t) for t in given), name
            for src, dst in ((name, oc.REFERENCE), (oc.REFERENCE, name)):
                config.getProcessor(src, dst).getDefaultCPUProcessor()
        for named in config.getNamedTransforms():
            for direction in (OCIO.TRANSFORM_DIR_FORWARD, OCIO.TRANSFORM_DIR_INVERSE):
                transform = named.getTransform(direction)
                assert transform is not None, (named.getName(), direction)
                assert _inverts_no_lut3d(config, transform)
                config.getProcessor(named, direction).getDefaultCPUProcessor()
        for look in config.getLooks():
            given = [t for t in (look.getTransform(), look.getInverseTransform()) if t is not None]
            if len(given) == 1:  # the identity Q's look: nothing to invert
                assert _one_way_is_analytic(config, given[0]), look.getName()
            assert all(_inverts_no_lut3d(config, t) for t in given), look.getName()
