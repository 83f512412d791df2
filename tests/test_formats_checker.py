"""The typed field reader every hand-written file goes through: one rule, one message each."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.checker import Validator

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
        (lambda: CTX.size([1, 2, 3], KEY), "expected [width, height] in pixels, got a list of 3"),
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
