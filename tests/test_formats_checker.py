"""The typed field reader every hand-written file goes through: one rule, one message each."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import make_measurements_dict

from ocio_vp.errors import InputError
from ocio_vp.formats.checker import Validator
from ocio_vp.formats.fixtures import parse_fixtures
from ocio_vp.formats.measurements import measurements_from_dict
from ocio_vp.formats.panels import PanelType, parse_panel_values
from ocio_vp.formats.wall_state import parse_wall_state

CTX = Validator("f.yaml")
KEY = ("a", 0, "b")


@pytest.mark.parametrize(
    ("read", "message"),
    [
        (lambda: CTX.whole(True, KEY), "expected a whole number >= 0, got True"),
        (lambda: CTX.whole(0, KEY, 1, 512), "expected a whole number 1..512, got 0"),
        (lambda: CTX.whole(1.5, KEY, None), "expected a whole number, got 1.5"),
        (lambda: CTX.flag("no", KEY), "expected true or false, got str 'no'"),
        (lambda: CTX.choice("x", KEY, ("p", "q")), "expected one of p, q, got 'x'"),
        (lambda: CTX.choice(3, KEY, ("p",), what="kind"), "unknown kind 3; expected one of: p"),
        (
            lambda: CTX.items([], KEY, "texts"),
            "expected a non-empty list of texts, got a list of 0",
        ),
        (lambda: CTX.items({}, KEY, empty=True), "expected a list, got dict {}"),
        (lambda: CTX.text("a\nb", KEY), "expected one line of text"),
        (lambda: CTX.size([1, 2, 3], KEY), "expected [width, height]"),
        (lambda: CTX.size([0, 2], KEY), "[0]: expected a whole number >= 1, got 0"),
        (lambda: CTX.matrix([[1, 2]], KEY, (2, 2), "a 2x2 matrix"), "expected a 2x2 matrix"),
        (lambda: CTX.mapping({"nme": 1}, KEY, ("name",)), "unknown key (did you mean 'name'?)"),
        (lambda: CTX.mapping({}, KEY, ("name",)), "missing required key 'name'"),
        (lambda: CTX.wall_encoding("PQ", KEY), "unknown encoding 'PQ'; expected one of: linear"),
    ],
)
def test_each_rule_names_the_file_the_key_and_the_problem(read, message):
    with pytest.raises(InputError) as error:
        read()
    text = str(error.value)
    assert text.startswith("f.yaml: a[0].b") and message in text and "\n" not in text


def test_a_lit_chart_counts_patches_like_its_red_chart_or_the_one_named():
    red = [[0.1, 0.2, 0.3]] * 4
    block = {"red": red, "green": red, "blue": red[:3]}
    with pytest.raises(
        InputError, match=r"lit_chart\.blue: has 3 patches, expected 4 like lit_chart\.red"
    ):
        CTX.lit_chart(block, ("lit_chart",), None)
    block["blue"] = red
    SRL = CTX.lit_chart(block, ("lit_chart",), None)
    assert SRL.shape == (4, 3, 3) and np.all(SRL[:, :, 2] == red)
    with pytest.raises(InputError, match=r"expected 5 like panels\[0\]\.lit_chart\.red"):
        CTX.lit_chart(block, ("panels", 1, "lit_chart"), 5, "panels[0].lit_chart.red")


def test_unique_names_say_where_the_first_one_is():
    seen: dict[str, int] = {}
    assert CTX.unique_name("wall", ("panels", 0), seen) == "wall"
    with pytest.raises(
        InputError, match=r"panels\[1\]\.name: duplicate name 'wall' \(also panels\[0\]\)"
    ):
        CTX.unique_name("wall", ("panels", 1), seen)


def _dmx(**patch):
    dmx = {"universe": 1, "address": 1, "mode": "8-bit"} | patch
    chart = [[0.5, 0.5, 0.5]] * 2
    fixture = {
        "name": "a",
        "channels": ["red"],
        "reference_drive": 1.0,
        "lit_chart": {"red": chart},
    }
    return parse_fixtures(CTX, [fixture | {"dmx": dmx}], 2)


def _white_reflectance(value):
    data = make_measurements_dict(environments=1)
    data["stage"]["white_reflectance"] = value
    return measurements_from_dict(data, source="f.yaml")


def _w_avg(value):
    panels = tuple(PanelType(n, True, np.eye(3), np.ones((2, 3, 3))) for n in ("wall", "ceiling"))
    return parse_panel_values(CTX, value, ("environments", 0, "w_avg"), panels)


# Each file's refusals read as they did before the files shared these rules (6e08b78's texts).
@pytest.mark.parametrize(
    ("read", "message"),
    [
        (lambda: _dmx(address=0), "fixtures[0].dmx.address: expected an integer 1..512, got 0"),
        (
            lambda: _dmx(universe=-1),
            "fixtures[0].dmx.universe: expected an integer 0..63999, got -1",
        ),
        (
            lambda: _dmx(mode="RGBW"),
            "fixtures[0].dmx.mode: expected one of ['8-bit', '16-bit'], got 'RGBW'",
        ),
        (
            lambda: parse_wall_state(CTX, {"pattern_size": [1, 2, 3]}, ("stage",)),
            "stage.pattern_size: expected [width, height] in pixels, got [1, 2, 3]",
        ),
        (
            lambda: parse_wall_state(CTX, {"pattern_size": [0, 5]}, ("stage",)),
            "stage.pattern_size: expected [width, height] in pixels, got [0, 5]",
        ),
        (
            lambda: _white_reflectance(1.5),
            "stage.white_reflectance: expected at most 1, got 1.5",
        ),
        (
            lambda: _w_avg({"wall": [1, 1, 1], "ceiling": [1, 1, 1], "roof": [1, 1, 1]}),
            "environments[0].w_avg.roof: unknown panel type; panel types: wall, ceiling",
        ),
    ],
)
def test_messages_read_as_before(read, message):
    with pytest.raises(InputError) as error:
        read()
    assert str(error.value) == f"f.yaml: {message}"
