"""The names the command line and the library share (``ocio_vp.choices``) are the library's."""

from __future__ import annotations

from ocio_vp import choices
from ocio_vp.calibration.equations import BLACK_LEVEL_METHODS
from ocio_vp.correction.registry import Q_SOLVE_METHODS
from ocio_vp.exports import EXPORT_TARGETS, SHOW_TARGETS
from ocio_vp.footage.apply import OPTIMIZATIONS
from ocio_vp.wall import WALL_ENCODINGS, WallEncoding


def test_every_choice_is_the_librarys():
    assert tuple(Q_SOLVE_METHODS) == choices.Q_METHODS
    assert choices.LINEAR_METHODS == {n for n, r in Q_SOLVE_METHODS.items() if r.linear}
    assert choices.DEFAULT_METHOD in choices.Q_METHODS
    assert tuple(BLACK_LEVEL_METHODS) == choices.BLACK_LEVEL_METHODS
    assert WALL_ENCODINGS is choices.WALL_ENCODINGS  # defined once
    assert {WallEncoding(name).ocio_encoding for name in WALL_ENCODINGS} == {
        "scene-linear", "sdr-video", "hdr-video",
    }  # fmt: skip
    assert tuple(EXPORT_TARGETS) == choices.ENVIRONMENT_TARGETS  # a writer for each
    assert SHOW_TARGETS is choices.SHOW_TARGETS  # defined once
    assert (*EXPORT_TARGETS, "all", *SHOW_TARGETS) == choices.EXPORT_TARGETS
    assert tuple(OPTIMIZATIONS) == choices.OPTIMIZATIONS


def test_the_default_base_config_is_the_show_configs_and_loads():
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio.show import DEFAULT_BASE_CONFIG

    assert choices.DEFAULT_BASE_CONFIG == DEFAULT_BASE_CONFIG
    OCIO.Config.CreateFromFile(choices.DEFAULT_BASE_CONFIG).validate()


def test_the_module_needs_no_numpy():
    import subprocess
    import sys

    code = "import sys, ocio_vp.choices; print('numpy' in sys.modules)"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "False"
