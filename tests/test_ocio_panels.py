"""ocio_vp.ocio.panels: each panel type's colour spaces in the config, checked through OCIO's own
processors against the solve's matrices, the panel's measured response (its linearity LUT must
undo it) and colour-science's PQ."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import PyOpenColorIO as OCIO
import pytest

from benchmarks.panel_solves import ceiling_response, three_types
from ocio_vp.formats.linearity import WallEncodingBlock
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.panels import panel_labels
from ocio_vp.ocio.writer import write_environment
from ocio_vp.pipeline import solve_environment
from ocio_vp.wall.encoding import with_wall_encoding

REFERENCE = "Camera Native Linear"


@pytest.fixture(scope="module")
def written(panel_stage_and_measurements, tmp_path_factory):
    _, m = panel_stage_and_measurements
    m = three_types(m)
    out = {}
    for method in ("least-squares", "root-polynomial"):
        folder = tmp_path_factory.mktemp(method)
        solution = solve_environment(m, m.environments[0], method=method)
        write_environment(with_wall_encoding(solution, "linear"), folder)
        out[method] = folder
    return out


def processor(folder, a, b):
    config = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
    return config.getProcessor(a, b).getDefaultCPUProcessor()


def apply(folder, a, b, rgb):
    cpu = processor(folder, a, b)
    return np.array([cpu.applyRGB([float(v) for v in c]) for c in rgb])


COLOURS = np.random.default_rng(0).uniform(0.02, 0.6, (40, 3))


def test_every_type_has_its_colour_spaces_and_views(written):
    solution = load_solution(written["least-squares"])
    config = OCIO.Config.CreateFromFile(str(written["least-squares"] / "config.ocio"))
    names = {p.name: p.ocio for p in solution.panels.values()}
    assert names["ceiling"].to_dict() == {
        "out_of_frustum": "LED Ceiling - Outer Frustum",
        "view_out_of_frustum": "Ceiling Outer Frustum",
    }
    assert names["floor"].in_frustum == "LED Floor - Inner Frustum"
    assert names["wall"].out_of_frustum == "LED Wall - Outer Frustum"  # unchanged names
    for panel in names.values():
        for space in (panel.out_of_frustum, panel.in_frustum):
            if space is not None:
                assert config.getColorSpace(space) is not None
    views = list(config.getViews("LED Wall"))
    assert {"Ceiling Outer Frustum", "Floor Outer Frustum", "Floor Inner Frustum"} <= set(views)


@pytest.mark.skipif(shutil.which("ociocheck") is None, reason="ociocheck not on PATH")
@pytest.mark.parametrize("method", ["least-squares", "root-polynomial"])
def test_the_config_passes_ociocheck(written, method):
    result = subprocess.run(
        ["ociocheck", "--iconfig", str(written[method] / "config.ocio")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_floor_shows_the_background_through_its_own_n(written):
    solution = load_solution(written["least-squares"])
    floor = solution.panels["floor"]
    got = apply(written["least-squares"], REFERENCE, "LED Floor - Inner Frustum", COLOURS)
    assert np.allclose(got, COLOURS @ floor.N.T + floor.black_level_offset, atol=2e-6)
    got = apply(written["least-squares"], REFERENCE, "LED Floor - Outer Frustum", COLOURS)
    assert np.allclose(got, COLOURS @ floor.M.T, atol=2e-6)


def test_a_non_linear_q_shows_the_floor_through_m_q_inverse(written):
    solution = load_solution(written["root-polynomial"])
    floor = solution.panels["floor"]
    content = np.asarray(solution.diagnostics.charts.target)  # the bake's gamut
    got = apply(written["root-polynomial"], REFERENCE, "LED Floor - Inner Frustum", content)
    pre = solution.correction.inverse(content)
    # The baked Q^-1 (docs/root_polynomial.md: under 0.1% of each colour in the chart's gamut).
    assert np.all(
        np.abs(got - floor.black_level_offset - pre @ floor.M.T)
        <= 2e-3 * np.abs(pre @ floor.M.T).max(axis=1, keepdims=True)
    )
    wall = apply(written["root-polynomial"], REFERENCE, "LED Wall - Inner Frustum", content)
    # The same Q^-1 as the wall's inner frustum, then each type's own M and offset.
    to_floor = floor.M @ np.linalg.inv(solution.M)
    wall_pre = wall - solution.black_level_offset
    assert np.allclose(wall_pre @ to_floor.T + floor.black_level_offset, got, rtol=1e-4, atol=1e-5)


def test_the_ceiling_gets_its_own_m_linearity_lut_and_pq_signal(written):
    import colour

    solution = load_solution(written["least-squares"])
    ceiling = solution.panels["ceiling"]
    assert ceiling.linearity.wall_encoding == WallEncodingBlock("pq", 1500.0)
    assert ceiling.linearity.lut.file.startswith("luts/")
    assert (written["least-squares"] / ceiling.linearity.lut.file).is_file()
    assert solution.linearity is None or solution.linearity.lut is None  # the wall's
    signal = apply(written["least-squares"], REFERENCE, "LED Ceiling - Outer Frustum", COLOURS)
    # Decode PQ (colour-science), then the ceiling's own response: the linear drive M c.
    pre = colour.models.eotf_ST2084(signal) / 1500.0
    seen = np.stack([ceiling_response(pre[:, k], k) for k in range(3)], axis=1)
    drive = np.clip(COLOURS @ ceiling.M.T, 0.0, None)  # the wall's tail: negative drive is black
    assert np.allclose(seen, drive, rtol=5e-3, atol=5e-4)


def test_the_other_types_spaces_build_fast_both_ways(written):
    import time

    for name in ("LED Ceiling - Outer Frustum", "LED Floor - Outer Frustum"):
        for a, b in ((REFERENCE, name), (name, REFERENCE)):
            start = time.perf_counter()
            processor(written["root-polynomial"], a, b)
            assert time.perf_counter() - start < 1.0


def test_labels_never_repeat_or_read_wall():
    labels = panel_labels(["main", "Wall", "ceiling", "CEILING", "wild_wall"], "main")
    assert labels == {
        "main": "Wall",
        "Wall": "Panel Wall",
        "ceiling": "Panel ceiling",
        "CEILING": "Panel CEILING",
        "wild_wall": "Wild Wall",
    }
    assert len(set(labels.values())) == len(labels)
