"""ocio_vp.ocio.softclip: the soft clip as every host gets it, checked against the numpy closed
form (:mod:`ocio_vp.wall.softclip`) over drive -0.25 .. the drive of 16x content white: OCIO's
processors of the written config (both wall colour spaces, each signal encoding, every panel
type, the show config), its explicit inverse, and Resolve's CLF through oiiotool."""

from __future__ import annotations

import copy
import dataclasses
import shutil

import numpy as np
import PyOpenColorIO as OCIO
import pytest
import yaml
from conftest import make_measurements_dict
from test_exports_resolve import _oiiotool_clf

from benchmarks.panel_solves import three_types
from ocio_vp.calibration.headroom import content_scale
from ocio_vp.cli import main
from ocio_vp.exports import export_solutions
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.writer import write_environment
from ocio_vp.pipeline import solve_environment
from ocio_vp.wall.encoding import encode, with_wall_encoding
from ocio_vp.wall.softclip import INVERSE_CAP, forward, inverse, with_soft_clip

SAMPLE = "sample_configs/paper_stage/warm_white_led/solution.json"
REFERENCE = "Camera Native Linear"
OUTER, INNER = "LED Wall - Outer Frustum", "LED Wall - Inner Frustum"
TOLERANCE = 1e-4
KNEE = 0.7


def drives(solution, n: int = 3000, seed: int = 0) -> np.ndarray:
    """Drive per channel uniform in [-0.25, 16x content white's drive] plus the knee and 1.0."""
    top = 16 * content_scale(solution).worst_drive
    rng = np.random.default_rng(seed)
    edges = np.array([[-0.25] * 3, [KNEE] * 3, [1.0] * 3, [top] * 3])
    return np.concatenate([edges, rng.uniform(-0.25, top, (n, 3))])


def content_for(drive: np.ndarray, matrix, offset=None) -> np.ndarray:
    """The camera RGB whose drive through ``matrix`` (+ ``offset``) is ``drive``."""
    shifted = drive - (0.0 if offset is None else np.asarray(offset))
    return np.linalg.solve(np.asarray(matrix, dtype=np.float64), shifted.T).T


def run(config: OCIO.Config, src: str, dst: str, rgb: np.ndarray, context=None) -> np.ndarray:
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    context = config.getCurrentContext() if context is None else context
    config.getProcessor(context, src, dst).getDefaultCPUProcessor().applyRGB(out)
    return out.astype(np.float64)


def wall_matrices(solution):
    return {OUTER: (solution.M, None), INNER: (solution.N, solution.black_level_offset)}


@pytest.mark.parametrize("encoding", ["linear", "gamma2.4", "pq"])
def test_config_follows_the_closed_form_in_both_wall_spaces(encoding, tmp_path):
    """Content -> wall signal: M (or N + offset), the soft clip, the encoding; within 1e-4 of
    numpy over the whole drive range, and the inverse returns the drive (below the cap)."""
    solution = with_soft_clip(with_wall_encoding(load_solution(SAMPLE), encoding), KNEE)
    write_environment(solution, tmp_path)
    config = OCIO.Config.CreateFromFile(str(tmp_path / "config.ocio"))
    d = drives(solution)
    for space, (matrix, offset) in wall_matrices(solution).items():
        want = forward(d, KNEE)  # a linear wall without LUT passes negative drive on
        if encoding != "linear":  # an encoded one sends it as black
            want = encode(np.clip(want, 0, None), encoding, peak_nits=1000.0)
        got = run(config, REFERENCE, space, content_for(d, matrix, offset))
        assert np.abs(got - want).max() < TOLERANCE, (space, np.abs(got - want).max())
        if encoding == "linear":
            # the drive's tolerance in content units: through the matrix's inverse
            gain = float(np.abs(np.linalg.inv(np.asarray(matrix))).sum(axis=1).max())
            back = run(config, space, REFERENCE, want)
            kept = np.all(want <= INVERSE_CAP, axis=1)
            np.testing.assert_allclose(
                back[kept], content_for(d[kept], matrix, offset), atol=TOLERANCE * gain
            )
            full = run(config, space, REFERENCE, np.array([[1.0, 1.0, 1.0], [4.0, 1.0, 0.5]]))
            capped = inverse(np.array([[INVERSE_CAP] * 3, [INVERSE_CAP, INVERSE_CAP, 0.5]]), KNEE)
            np.testing.assert_allclose(
                full, content_for(capped, matrix, offset), atol=TOLERANCE * gain
            )
    assert (
        f"soft clip of each channel's drive from {KNEE:g}"
        in config.getColorSpace(OUTER).getDescription()
    )


def test_without_the_option_the_config_is_unchanged(tmp_path):
    solution = load_solution(SAMPLE)
    for name, written in (("a", solution), ("b", with_soft_clip(solution, None))):
        (tmp_path / name).mkdir()
        write_environment(written, tmp_path / name)
    assert (tmp_path / "a" / "config.ocio").read_bytes() == (
        tmp_path / "b" / "config.ocio"
    ).read_bytes()
    assert "LogCamera" not in (tmp_path / "a" / "config.ocio").read_text()


def test_every_panel_type_is_soft_clipped(panel_stage_and_measurements, tmp_path):
    """Each panel type's colour spaces, its own linearity LUT included: the soft-clipped config
    at drive d equals the same config without the clip at drive f(d) (the clip comes right
    after the matrix), and a type without a LUT gives f(d) itself."""
    _, m = panel_stage_and_measurements
    m = three_types(m)
    solution = solve_environment(m, m.environments[0], method="least-squares")
    solution = with_wall_encoding(solution, "linear")
    configs = {}
    for name, knee in (("plain", None), ("clipped", KNEE)):
        (tmp_path / name).mkdir()
        written = write_environment(with_soft_clip(solution, knee), tmp_path / name)
        configs[name] = OCIO.Config.CreateFromFile(str(tmp_path / name / "config.ocio"))
    d = drives(written)
    checked = 0
    for panel in written.panels.values():
        assert panel.linearity.soft_clip.knee == KNEE
        spaces = {panel.ocio.out_of_frustum: (panel.M, None)}
        if panel.in_frustum and panel.N is not None:
            spaces[panel.ocio.in_frustum] = (panel.N, panel.black_level_offset)
        for space, (matrix, offset) in spaces.items():
            got = run(configs["clipped"], REFERENCE, space, content_for(d, matrix, offset))
            want = run(configs["plain"], REFERENCE, space,
                       content_for(forward(d, KNEE), matrix, offset))  # fmt: skip
            assert np.abs(got - want).max() < TOLERANCE, space
            if panel.linearity.lut is None:
                assert np.abs(got - forward(d, KNEE)).max() < TOLERANCE, space
            checked += 1
    assert checked >= 4


def test_resolve_clf_through_oiiotool(tmp_path):
    if shutil.which("oiiotool") is None:
        pytest.skip("oiiotool is not on PATH")
    solution = with_soft_clip(load_solution(SAMPLE), KNEE)
    folder = tmp_path / solution.environment
    folder.mkdir()
    write_environment(solution, folder)
    export_solutions([folder], targets=["resolve"], cube_size=9)
    resolve = folder / "exports" / "resolve"
    d = drives(solution, n=400)
    for stem, (matrix, offset) in zip(
        ("wall_out_of_frustum", "wall_in_frustum"), wall_matrices(solution).values(), strict=True
    ):
        text = (resolve / f"{stem}.clf").read_text()
        assert 'style="cameraLogToLin"' in text
        got = _oiiotool_clf(resolve / f"{stem}.clf", content_for(d, matrix, offset), tmp_path)
        assert np.abs(got - forward(d, KNEE)).max() < TOLERANCE, stem


def test_show_config_carries_it(tmp_path):
    """One environment with a camera gamut through ``export --target show``: ACEScg -> the
    wall spaces of the show config against numpy (ACEScg -> camera from the config's own
    linear spaces, then M or N + offset and the closed form)."""
    document = make_measurements_dict(seed=4, environments=1)
    document["stage"]["camera_colorspace"] = "ARRI Wide Gamut 4"
    (tmp_path / "stage.yaml").write_text(yaml.safe_dump(document))
    args = ["solve", str(tmp_path / "stage.yaml"), "--out", str(tmp_path / "calib"),
            "--method", "least-squares", "--soft-clip", str(KNEE)]  # fmt: skip
    assert main(args) == 0
    assert main(["export", str(tmp_path / "calib"), "--target", "show",
                 "--out", str(tmp_path / "x")]) == 0  # fmt: skip
    (env,) = [p for p in (tmp_path / "calib").iterdir() if p.is_dir()]
    solution = load_solution(env)
    own = OCIO.Config.CreateFromFile(str(env / "config.ocio"))
    config = OCIO.Config.CreateFromFile(str(tmp_path / "x" / "show" / "config.ocio"))
    context = copy.deepcopy(config.getCurrentContext())
    d = drives(solution, n=500)
    for space, (matrix, offset) in wall_matrices(solution).items():
        aces = run(own, REFERENCE, "ACEScg", content_for(d, matrix, offset))
        got = run(config, "ACEScg", space, aces, context)
        error = np.abs(got - forward(d, KNEE))
        assert error.max() < TOLERANCE, (space, error.max())
    assert dataclasses.asdict(content_scale(solution))["soft_clip"] == KNEE
