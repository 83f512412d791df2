"""Reading YAML and JSON: one value type (JsonValue) whichever of the two a file is."""

from __future__ import annotations

import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.documents import parse_document


def _yaml(text: str):
    return parse_document(text.encode(), json_format=False, source="f.yaml")


def _json(text: str):
    return parse_document(text.encode(), json_format=True, source="f.json")


class TestOneValueType:
    def test_a_date_is_kept_as_the_text_json_would_hold(self):
        assert _yaml("taken: 2026-12-07\n") == _json('{"taken": "2026-12-07"}')
        assert _yaml("taken: 2026-12-07\n") == {"taken": "2026-12-07"}

    def test_an_integer_key_is_its_text_as_in_json(self):
        # sequence.yaml keys validation.pulled by chart index
        assert _yaml("pulled: {3: 0.5, 17: 0.25}\n") == _json('{"pulled": {"3": 0.5, "17": 0.25}}')

    @pytest.mark.parametrize("key", ["null", "yes", "1.5", "~"])
    def test_other_keys_that_are_not_text_are_refused(self, key):
        with pytest.raises(
            InputError, match=r"f\.yaml: invalid YAML at line 2: key .* is not text"
        ):
            _yaml(f"a: 1\n{key}: 2\n")

    @pytest.mark.parametrize(
        "value", ["!!binary aGVsbG8=", "!!set {a, b}", "!!omap [{a: 1}]", "!!pairs [{a: 1}]"]
    )
    def test_yaml_only_types_are_refused(self, value):
        with pytest.raises(
            InputError, match=r"invalid YAML at line 1: \w+ values are not supported"
        ):
            _yaml(f"a: {value}\n")

    def test_quoted_keys_and_values_are_text(self):
        assert _yaml("'1': '2026-12-07'\n") == {"1": "2026-12-07"}
