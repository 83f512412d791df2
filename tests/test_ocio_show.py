"""The show config: every environment on the ACES CG config, picked by ``VP_ENVIRONMENT``,
checked by meaning against each environment's own config (OCIO's processors on both)."""

from __future__ import annotations

import copy
import dataclasses
import shutil
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO
import pytest
import yaml
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.ocio import description, show

RNG = np.random.default_rng(3)
LINEAR = np.concatenate([RNG.uniform(0, 1, (400, 3)), RNG.uniform(-0.2, 8, (200, 3))])
LOG = RNG.uniform(0, 1, (400, 3))
#: The pairs the issue names (content -> wall, footage -> working space), linear and log.
PAIRS = (
    ("ACEScg", "LED Wall - Inner Frustum", LINEAR),
    ("ACEScg", "LED Wall - Outer Frustum", LINEAR),
    ("Stage Footage", "ACEScg", LINEAR),
    ("Stage Footage (LogC4)", "ACEScg", LOG),
)
# |show - own| / max(1, |own|): the show's chain takes one more float32 matrix step (through
# the base's ACES2065-1), which benchmarks/show_compat.py measures at 8.1e-6 at worst over OCIO
# 2.2-2.6 (docs/exports.md); 1e-4 is that with a margin for steeper root-polynomial LUTs.
TOLERANCE = 1e-4


def _run(config, context, src, dst, rgb) -> np.ndarray:
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    config.getProcessor(context, src, dst).getDefaultCPUProcessor().applyRGB(out)
    return out.astype(np.float64)


def _context(config: OCIO.Config, environment: str | None) -> OCIO.Context:
    context = copy.deepcopy(config.getCurrentContext())
    if environment is not None:
        context[show.CONTEXT_VARIABLE] = environment
    return context


@pytest.fixture(scope="module")
def solved(tmp_path_factory) -> Path:
    """Two environments with a camera gamut: one least-squares, one root-polynomial (LUTs)."""
    root = tmp_path_factory.mktemp("show")
    document = make_measurements_dict(seed=4)
    document["stage"]["camera_colorspace"] = "ARRI Wide Gamut 4"
    (root / "stage.yaml").write_text(yaml.safe_dump(document))
    assert (
        main(
            [
                "solve",
                str(root / "stage.yaml"),
                "--out",
                str(root / "ls"),
                "--method",
                "least-squares",
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "solve",
                str(root / "stage.yaml"),
                "--out",
                str(root / "rp"),
                "--method",
                "root-polynomial",
            ]
        )
        == 0
    )
    # one calibration folder holding both kinds: env_0 least squares, env_1 root-polynomial
    (root / "calib").mkdir()
    shutil.copytree(root / "ls" / "env_0", root / "calib" / "env_0")
    shutil.copytree(root / "rp" / "env_1", root / "calib" / "env_1")
    assert main(["export", str(root / "calib"), "--target", "show", "--out", str(root / "x")]) == 0
    return root


def _environments(calib: Path) -> list[show.ShowEnvironment]:
    return [
        show.ShowEnvironment(p.name, OCIO.Config.CreateFromFile(str(p / "config.ocio")))
        for p in sorted(calib.iterdir())
    ]


def test_show_config_has_what_a_pipeline_needs(solved):
    config = OCIO.Config.CreateFromFile(str(solved / "x" / "show" / "config.ocio"))
    config.validate()
    for name in ("ACEScg", "ACES2065-1", "LED Wall - Inner Frustum", "Stage Footage (LogC4)"):
        assert config.getColorSpace(name) is not None, name
    assert config.getRoleColorSpace("aces_interchange") == "ACES2065-1"
    assert config.getRoleColorSpace("cie_xyz_d65_interchange") == "CIE-XYZ-D65"
    log = config.getColorSpace(config.getRoleColorSpace("compositing_log"))
    assert log.getName() == "ACEScct" and log.getEncoding() == "log"
    views = list(config.getViews("sRGB - Display"))
    assert "ACES 1.0 - SDR Video" in views
    assert "ACES 1.0 - SDR Video" + show.FOOTAGE_VIEW_SUFFIX in views
    assert set(config.getViews("LED Wall")) == {"Outer Frustum", "Inner Frustum", "Raw"}
    assert config.getEnvironmentVarDefault(show.CONTEXT_VARIABLE) == "env_0"
    for env in ("env_0", "env_1"):
        assert config.getColorSpace(f"LED Wall - Inner Frustum [{env}]") is not None


def test_each_environment_equals_its_own_config(solved):
    """VP_ENVIRONMENT picks the environment; every pair within 1e-4 of its standalone config
    (relative above 1), the root-polynomial's LUT sidecars included."""
    config = OCIO.Config.CreateFromFile(str(solved / "x" / "show" / "config.ocio"))
    for env in ("env_0", "env_1"):
        own = OCIO.Config.CreateFromFile(str(solved / "calib" / env / "config.ocio"))
        for src, dst, rgb in PAIRS:
            want = _run(own, own.getCurrentContext(), src, dst, rgb)
            got = _run(config, _context(config, env), src, dst, rgb)
            error = np.abs(got - want) / np.maximum(1.0, np.abs(want))
            assert error.max() < TOLERANCE, (env, src, dst, error.max())
    # the default is the first environment
    own = OCIO.Config.CreateFromFile(str(solved / "calib" / "env_0" / "config.ocio"))
    want = _run(own, own.getCurrentContext(), "ACEScg", "LED Wall - Inner Frustum", LINEAR)
    got = _run(config, _context(config, None), "ACEScg", "LED Wall - Inner Frustum", LINEAR)
    np.testing.assert_allclose(got, want, rtol=TOLERANCE, atol=TOLERANCE)


@pytest.mark.parametrize(
    "base", [show.DEFAULT_BASE_CONFIG, "ocio://studio-config-v1.0.0_aces-v1.3_ocio-v2.1", "own"]
)
def test_a_base_read_into_data_builds_back_to_the_same_file(base, tmp_path):
    """OCIO's own writing of the base and of the config built from its data are the same bytes;
    looks whose transform has no record (CDL) stay as OCIO has them (first of their kind)."""
    if base == "own":
        config = OCIO.Config.CreateFromFile(show.DEFAULT_BASE_CONFIG)
        aces_look = config.getLook(config.getLookNames()[0])
        config.clearLooks()
        for name in ("Warm", "Cool"):
            cdl = OCIO.CDLTransform(slope=[1.1, 1.0, 0.9] if name == "Warm" else [0.9, 1.0, 1.1])
            config.addLook(OCIO.Look(name=name, processSpace="ACEScg", transform=cdl))
        config.addLook(aces_look)
    else:
        config = OCIO.Config.CreateFromFile(base)
    data, rest = description.split_config(config)
    assert data.opaque == (("Warm", "Cool") if base == "own" else ())
    assert len(data.looks) == 1
    assert description.build(data, start=rest).serialize() == config.serialize()


KEPT = ("sRGB - Display", "ACES2065-1", "ACEScct")  # the CG config's 2nd, 7th and 9th spaces


def _tampered_base() -> OCIO.Config:
    """The CG config with ``aces_interchange`` naming an alias of ACES2065-1, and :data:`KEPT`
    kept as OCIO objects (allocation variables: no record carries them)."""
    config = OCIO.Config.CreateFromFile(show.DEFAULT_BASE_CONFIG)
    for name in KEPT:
        cs = config.getColorSpace(name)
        cs.setAllocation(OCIO.ALLOCATION_LG2)
        cs.setAllocationVars([-8.0, 5.0, 0.00390625])
        config.addColorSpace(cs)  # replaces the space of that name, in its place
    config.setRole("aces_interchange", "aces2065_1")
    return config


@pytest.fixture(scope="module")
def tampered(solved, tmp_path_factory) -> tuple[OCIO.Config, OCIO.Config]:
    """The tampered base and the show of both environments on it (LUTs from the CG show)."""
    path = tmp_path_factory.mktemp("base") / "base.ocio"
    path.write_text(_tampered_base().serialize())
    config = show.build_show_config(_environments(solved / "calib"), str(path))
    config.setWorkingDir(str(solved / "x" / "show"))
    return OCIO.Config.CreateFromFile(str(path)), config


def test_a_base_keeps_its_order_with_kept_spaces_between(tampered):
    """Kept spaces stay where the base has them (not first), read back or in the show."""
    base, config = tampered
    data, rest = description.split_config(base)
    assert data.opaque == KEPT
    every = (OCIO.SEARCH_REFERENCE_SPACE_ALL, OCIO.COLORSPACE_ALL)
    names = [cs.getName() for cs in base.getColorSpaces(*every)]
    assert names.index("ACEScct") == 8
    assert description.build(data, start=rest).serialize() == base.serialize()
    assert [cs.getName() for cs in config.getColorSpaces(*every)][: len(names)] == names


def test_a_base_naming_aces_by_alias_or_kept_makes_the_same_show(solved, tampered):
    """The alias role and the kept ACES2065-1: every environment as in its own config, and
    every footage twin of the CG show on the kept sRGB - Display too."""
    _, config = tampered
    assert config.getRoleColorSpace("aces_interchange") == "aces2065_1"
    assert config.getColorSpace("ACES2065-1").getAllocationVars() == [-8.0, 5.0, 0.00390625]
    for env in ("env_0", "env_1"):
        own = OCIO.Config.CreateFromFile(str(solved / "calib" / env / "config.ocio"))
        for src, dst, rgb in PAIRS[::2]:
            want = _run(own, own.getCurrentContext(), src, dst, rgb)
            got = _run(config, _context(config, env), src, dst, rgb)
            error = np.abs(got - want) / np.maximum(1.0, np.abs(want))
            assert error.max() < TOLERANCE, (env, src, dst, error.max())
    cg = OCIO.Config.CreateFromFile(str(solved / "x" / "show" / "config.ocio"))
    views = list(cg.getViews("sRGB - Display"))
    assert sum(v.endswith(show.FOOTAGE_VIEW_SUFFIX) for v in views) >= 2
    assert list(config.getViews("sRGB - Display")) == views
    assert config.getSearchPath() == cg.getSearchPath() == "luts"


def test_a_kept_aces_space_without_a_record_is_refused(solved, tmp_path):
    base = _tampered_base()
    aces = base.getColorSpace("ACES2065-1")
    aces.setTransform(OCIO.CDLTransform(slope=[1.1, 1.0, 0.9]), OCIO.COLORSPACE_DIR_TO_REFERENCE)
    base.addColorSpace(aces)
    (tmp_path / "base.ocio").write_text(base.serialize())
    environments = _environments(solved / "calib")
    with pytest.raises(InputError, match=r"^--base-config: .*'ACES2065-1'"):
        show.build_show_config(environments, str(tmp_path / "base.ocio"))


def test_the_show_merge_is_data_and_the_base_wins():
    """Without OCIO: a name the base has keeps the base's element, the rest is added."""
    ap0 = description.ColourSpace("ACES2065-1", "ACES", "base's", aliases=("aces",))
    base = description.ConfigData(
        name="base", colour_spaces=[ap0], roles={"aces_interchange": "ACES2065-1"},
        search_path="", views=[description.View("d", "v", "ACES2065-1")],
    )  # fmt: skip
    overlay = description.ConfigData(
        name="show", colour_spaces=[dataclasses.replace(ap0, description="overlay's"),
        description.ColourSpace("aces", "x", "an alias"), description.ColourSpace("New", "x", "")],
        roles={"aces_interchange": "New", "scene_linear": "New"}, search_path="luts",
        views=[description.View("d", "v", "New"), description.View("e", "v", "New")],
    )  # fmt: skip
    merged = description.merge(base, overlay)
    assert [cs.description for cs in merged.colour_spaces] == ["base's", ""]
    assert merged.roles == {"aces_interchange": "ACES2065-1", "scene_linear": "New"}
    assert merged.search_path == "luts" and merged.name == "show"
    assert [(v.display, v.colour_space) for v in merged.views] == [
        ("d", "ACES2065-1"),
        ("e", "New"),
    ]


def test_show_data_is_a_function_of_data():
    """Without OCIO: a base display's view-transform view gets its footage twin (its Raw view,
    a data space, none), the active lists grow by the show's views, the inactive list keeps only
    names the config defines, the environment variable defaults to the first environment."""
    d = description
    base = d.ConfigData(
        colour_spaces=[d.ColourSpace("AP0", "", ""), d.ColourSpace("Raw", "", "", is_data=True),
                       d.ColourSpace("sRGB", "", "", display_referred=True)],
        roles={"aces_interchange": "AP0"},
        views=[d.View("", "Film", "<USE_DISPLAY_NAME>", "Film VT"), d.View("sRGB", "Raw", "Raw"),
               d.View("sRGB", "Film", "", shared=True)],
        active_views=("Film", "Raw"), inactive_colour_spaces=("sRGB", "Gone"),
    )  # fmt: skip
    camera = d.matrix([2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 1])
    own = d.ConfigData(
        colour_spaces=[d.ColourSpace(show.REFERENCE, "ocio-vp/Camera", "camera"),
                       d.ColourSpace("Stage Footage", "ocio-vp/Camera", "footage",
                                     to_reference=camera)],
        views=[d.View(show.DISPLAY, "Outer Frustum", "x"), d.View(show.DISPLAY, "Raw", "Raw")],
        active_views=("Raw", "Outer Frustum"),
    )  # fmt: skip
    envs = [show.EnvironmentData(name, own, camera) for name in ("a", "b")]
    data = show.show_data(base, envs, "base")
    names = [cs.name for cs in data.colour_spaces]
    assert names[:3] == ["AP0", "Raw", "sRGB"] and "Stage Footage [b]" in names
    assert names[-2:] == [show.REFERENCE, "Stage Footage"]  # picked by the context variable
    twin = d.View("sRGB", "Film" + show.FOOTAGE_VIEW_SUFFIX, "sRGB", "Film VT",
                  show.POST_CORRECTION_LOOK)  # fmt: skip
    assert [v for v in data.views if v.display == "sRGB"][-1] == twin
    assert [v.name for v in data.views if v.display == show.DISPLAY] == ["Raw", "Outer Frustum"]
    assert data.active_views == ("Film", "Raw", twin.name, "Outer Frustum")
    assert data.inactive_colour_spaces == ("sRGB",)
    assert data.environment == {show.CONTEXT_VARIABLE: "a"} and data.name == "ocio-vp_show"


def test_show_folder_loads_after_a_move(solved, tmp_path):
    moved = tmp_path / "elsewhere"
    shutil.copytree(solved / "x" / "show", moved)
    config = OCIO.Config.CreateFromFile(str(moved / "config.ocio"))
    got = _run(config, _context(config, "env_1"), "ACEScg", "LED Wall - Inner Frustum", LINEAR)
    assert np.all(np.isfinite(got))


def test_environment_without_a_camera_gamut_is_refused(tmp_path, capsys):
    (tmp_path / "stage.yaml").write_text(yaml.safe_dump(make_measurements_dict()))
    assert main(["solve", str(tmp_path / "stage.yaml"), "--out", str(tmp_path / "c")]) == 0
    capsys.readouterr()
    args = ["export", str(tmp_path / "c"), "--target", "show", "--out", str(tmp_path / "x")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--camera-colorspace NAME" in err
    assert "stage.camera_colorspace: NAME" in err  # the exact flag and key
    assert not (tmp_path / "x" / "show").exists()


def test_show_needs_out_and_a_base_with_aces(solved, tmp_path, capsys):
    capsys.readouterr()
    assert main(["export", str(solved / "calib"), "--target", "show"]) == 2
    assert "--out" in capsys.readouterr().err
    raw = tmp_path / "raw.ocio"
    raw.write_text(OCIO.Config.CreateRaw().serialize())
    with pytest.raises(InputError, match="aces_interchange"):
        show.load_base_config(str(raw))


def test_two_solutions_of_one_environment_are_refused(solved):
    environments = _environments(solved / "ls")[:1] * 2
    with pytest.raises(InputError, match="env_0"):
        show.build_show_config(environments)


def test_a_kept_base_element_s_aliases_are_taken_names():
    """Without OCIO: a kept base colour space's alias is a name the config defines, so an
    overlay element of that name is not added (OCIO's addColorSpace would replace the kept space
    by it) and an inactive
    name that is the alias stays in the inactive list."""
    d = description
    kept = d.Kept("Legacy", ("legacy",), OCIO.ColorSpace(name="Legacy"), 1)
    base = d.ConfigData(
        colour_spaces=[d.ColourSpace("AP0", "", "")], roles={"aces_interchange": "AP0"},
        kept=(kept,), inactive_colour_spaces=("legacy", "Gone"),
    )  # fmt: skip
    overlay = d.ConfigData(
        colour_spaces=[d.ColourSpace("legacy", "x", "overlay's"), d.ColourSpace("New", "x", "")]
    )
    assert [cs.name for cs in d.merge(base, overlay).colour_spaces] == ["AP0", "New"]
    camera = d.matrix([2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 1])
    own = d.ConfigData(
        colour_spaces=[d.ColourSpace(show.REFERENCE, "ocio-vp/Camera", "camera")],
        views=[d.View(show.DISPLAY, "Raw", show.REFERENCE)],
    )
    data = show.show_data(base, [show.EnvironmentData("a", own, camera)], "base")
    assert data.inactive_colour_spaces == ("legacy",)
    assert data.kept == (kept,) and "legacy" not in [cs.name for cs in data.colour_spaces]
