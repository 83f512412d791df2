"""Unreal export and the configs it ships, checked by OCIO's and OIIO's own command-line tools.

Independent sources: ``ociocheck`` (OCIO's validator, parses every transform), ``oiiotool``
(OpenImageIO with its own bundled OCIO) and colour-science's ``matrix_RGB_to_RGB`` for the
working-space conversion; the expected pixels are plain numpy ``M c``, ``N c + offset``, ``Q c``.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import make_measurements_dict
from exr_helpers import write_exr

from ocio_vp.exports import export_solutions
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.formats.solution import load_solution
from ocio_vp.ocio.config import IN_FRUSTUM, OUT_OF_FRUSTUM, POST_CORRECTION, REFERENCE
from ocio_vp.ocio.writer import write_solutions
from ocio_vp.pipeline import solve_measurements

TOL = 1e-5  # the bar for oiiotool vs numpy


def solve_to(
    folder: Path,
    *,
    camera_colorspace: str | None = None,
    environments: int = 2,
    method: str | None = None,
):
    data = make_measurements_dict(environments=environments)
    if camera_colorspace:
        data["stage"]["camera_colorspace"] = camera_colorspace
    measurements = measurements_from_dict(data, source="test")
    options = {} if method is None else {"method": method}
    write_solutions(solve_measurements(measurements, **options), folder)
    return [folder / f"env_{i}" for i in range(environments)]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("unreal")
    dirs = solve_to(root / "solved")
    export_solutions(dirs, targets=["unreal"])
    return dirs


def run_tool(*args: str) -> subprocess.CompletedProcess:
    if shutil.which(args[0]) is None:
        pytest.skip(f"{args[0]} is not on PATH")
    return subprocess.run(args, capture_output=True, text=True, timeout=60, check=False)


class TestUnrealFiles:
    def test_layout(self, exported):
        folder = exported[0] / "exports" / "unreal"
        assert sorted(p.name for p in folder.iterdir()) == [
            ".ocio-vp-output",  # lets a later export replace the folder
            ".ocio-vp-source.json",  # the solution it was made from (a re-solve names it stale)
            "UNREAL.md",
            "config",
            "env_0.ocioz",
            "ocio_vp_setup.py",
            "unreal_ocio.json",
        ]

    @pytest.mark.parametrize("index", [0, 1])
    def test_ociocheck_config_and_archive(self, exported, index, tmp_path):
        folder = exported[index] / "exports" / "unreal"
        result = run_tool("ociocheck", "--iconfig", str(folder / "config" / "config.ocio"))
        assert result.returncode == 0, result.stdout + result.stderr
        # The config inside the archive, extracted with zipfile (not with OCIO).
        with zipfile.ZipFile(folder / f"env_{index}.ocioz") as archive:
            archive.extractall(tmp_path)
        result = run_tool("ociocheck", "--iconfig", str(tmp_path / "config.ocio"))
        assert result.returncode == 0, result.stdout + result.stderr
        result = run_tool("ociocheck", "--iconfig", str(folder / f"env_{index}.ocioz"))
        assert result.returncode == 0, result.stdout + result.stderr

    def test_reexport_is_byte_identical(self, exported, tmp_path):
        """Fixed timestamps, permissions and member order: the same config, the same bytes."""
        first = (exported[0] / "exports" / "unreal" / "env_0.ocioz").read_bytes()
        export_solutions(exported[:1], targets=["unreal"], out=tmp_path / "again")
        again = (tmp_path / "again" / "env_0" / "unreal" / "env_0.ocioz").read_bytes()
        assert again == first
        with zipfile.ZipFile(tmp_path / "again" / "env_0" / "unreal" / "env_0.ocioz") as zf:
            assert zf.namelist()[0] == "config.ocio"
            assert {info.date_time for info in zf.infolist()} == {(1980, 1, 1, 0, 0, 0)}

    def test_mapping(self, exported):
        folder = exported[0] / "exports" / "unreal"
        mapping = json.loads((folder / "unreal_ocio.json").read_text())
        # Property paths and enum values as in Epic's nDisplay API reference (UE 5.2+).
        slots = {a["property"]: a for a in mapping["assignments"]}
        viewports = slots["StageSettings.ViewportOCIO.AllViewportsOCIOConfiguration"]
        camera = slots["CameraSettings.CameraOCIO.AllNodesOCIOConfiguration"]
        cards = slots["StageSettings.Lightcard.LightcardOCIO.LightcardOCIOMode"]
        assert (viewports["source"], viewports["destination"]) == (REFERENCE, OUT_OF_FRUSTUM)
        assert viewports["set"] == {
            "bIsEnabled": True,
            "ColorConfiguration.SourceColorSpace": REFERENCE,
            "ColorConfiguration.DestinationColorSpace": OUT_OF_FRUSTUM,
        }
        assert (camera["source"], camera["destination"]) == (REFERENCE, IN_FRUSTUM)
        assert camera["owner"] == "UDisplayClusterICVFXCameraComponent"
        assert cards["enum"] == "EDisplayClusterConfigurationViewportLightcardOCIOMode"
        assert cards["value"] == "nDisplay"
        assert cards["destination"] == OUT_OF_FRUSTUM
        assert mapping["config"] == "config/config.ocio"
        assert (folder / mapping["config"]).is_file() and (folder / mapping["ocioz"]).is_file()
        asset = mapping["configuration_asset"]
        assert asset["desired_color_spaces"] == [REFERENCE, OUT_OF_FRUSTUM, IN_FRUSTUM]
        assert asset["configuration_file"] == mapping["config"]
        assert {v["view"] for v in asset["desired_display_views"]} == {
            "Outer Frustum",
            "Inner Frustum",
        }
        text = (folder / "UNREAL.md").read_text()
        assert f"`{REFERENCE}`, `{OUT_OF_FRUSTUM}`, `{IN_FRUSTUM}`." in text
        for ui in ("All Viewports Color Configuration", "All Nodes Color Configuration"):
            assert ui in text
        assert mapping["post_correction_carriage"] is None  # a matrix: carried exactly
        assert "not a matrix" not in text

    def test_a_non_linear_q_says_how_it_is_carried(self, tmp_path):
        """A root-polynomial Q: UNREAL.md and unreal_ocio.json give the measured agreement of
        the config's LUT chains with the model (Q, and Q^-1 in the inner frustum) and name the
        exact alternatives."""
        from ocio_vp.ocio import write_solutions
        from ocio_vp.pipeline import solve_environment
        from ocio_vp.simulator.stage import paper_stage_measurements

        m = paper_stage_measurements(("incandescent",))
        (solution,) = write_solutions(
            [solve_environment(m, m.environments[0], method="root-polynomial")], tmp_path
        )
        folder = tmp_path / "incandescent"
        export_solutions([folder], targets=["unreal"])
        unreal = folder / "exports" / "unreal"
        carriage = json.loads((unreal / "unreal_ocio.json").read_text())["post_correction_carriage"]
        block = solution.diagnostics.post_correction_ocio
        assert carriage["kind"] == "root-polynomial"
        assert carriage["agreement"] == json.loads(json.dumps(block.agreement.to_dict()))
        text = (unreal / "UNREAL.md").read_text()
        assert "**The post-correction is not a matrix.**" in text and carriage["note"] in text
        worst = block.inverse_agreement.worst["all"]
        assert f"{worst:.2g} (worst) over the corrected camera range" in text

    def test_working_space_source(self, tmp_path):
        """With a named camera gamut the source is Unreal's Linear Rec.709; converting it to
        the outer wall must equal M . (Rec.709 -> camera) from colour-science."""
        import colour
        import PyOpenColorIO as OCIO

        camera = "ARRI Wide Gamut 4"
        dirs = solve_to(tmp_path / "solved", camera_colorspace=camera, environments=1)
        export_solutions(dirs, targets=["unreal"])
        folder = dirs[0] / "exports" / "unreal"
        mapping = json.loads((folder / "unreal_ocio.json").read_text())
        source = mapping["content_working_space"]
        assert source == "Linear Rec.709 (sRGB)"
        assert mapping["content_working_space_alternatives"] == ["ACEScg"]
        solution = load_solution(dirs[0])
        to_camera = colour.matrix_RGB_to_RGB(
            colour.RGB_COLOURSPACES["ITU-R BT.709"],
            colour.RGB_COLOURSPACES[camera],
            chromatic_adaptation_transform="CAT02",
        )
        config = OCIO.Config.CreateFromFile(str(folder / "config" / "config.ocio"))
        rgb = np.array([[0.2, 0.5, 0.8], [1.0, 0.0, 0.0], [0.0, 0.3, 0.0]], dtype=np.float32)
        out = rgb.copy()
        config.getProcessor(source, OUT_OF_FRUSTUM).getDefaultCPUProcessor().applyRGB(out)
        expected = rgb.astype(np.float64) @ (solution.M @ to_camera).T
        np.testing.assert_allclose(out, expected, atol=1e-5)


def _read_exr(path: Path) -> np.ndarray:
    oiio = pytest.importorskip("OpenImageIO")
    image = oiio.ImageInput.open(str(path))
    pixels = image.read_image(format=oiio.FLOAT)
    image.close()
    return np.asarray(pixels, dtype=np.float64)


class TestOiiotool:
    """oiiotool with its bundled OCIO applies the exported config like numpy does."""

    @pytest.fixture
    def image(self, tmp_path):
        rng = np.random.default_rng(7)
        rgb = rng.uniform(0.0, 1.5, size=(4, 5, 3))
        rgb[0, 0] = [1.0, 1.0, 1.0]
        rgb[0, 1] = [0.0, 0.0, 0.0]
        path = tmp_path / "in.exr"
        write_exr(path, rgb)
        return path, rgb.astype(np.float32).astype(np.float64)

    @pytest.mark.parametrize(
        ("args", "expected"),
        [
            (["--colorconvert", REFERENCE, OUT_OF_FRUSTUM], lambda s, c: c @ s.M.T),
            (
                ["--colorconvert", REFERENCE, IN_FRUSTUM],
                lambda s, c: c @ s.in_frustum_matrix.T + s.in_frustum_offset,
            ),
            (["--ocionamedtransform", POST_CORRECTION], lambda s, c: c @ s.Q.T),
            (["--colorconvert", "Stage Footage", REFERENCE], lambda s, c: c @ s.Q.T),
        ],
        ids=["out_of_frustum", "in_frustum", "Q_named", "Q_colorspace"],
    )
    def test_pixels(self, exported, image, tmp_path, args, expected):
        src, rgb = image
        solution = load_solution(exported[1])
        assert solution.black_level_offset is not None  # the offset path is exercised
        config = exported[1] / "exports" / "unreal" / "config" / "config.ocio"
        out = tmp_path / "out.exr"
        result = run_tool(
            "oiiotool", "--colorconfig", str(config), str(src), *args, "-d", "float", "-o", str(out)
        )
        assert result.returncode == 0, result.stdout + result.stderr
        np.testing.assert_allclose(_read_exr(out), expected(solution, rgb), rtol=0, atol=TOL)
