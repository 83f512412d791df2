"""Record.to_dict: which unknown keys a block writes back."""

from __future__ import annotations

from ocio_vp.formats.records import Record


class _Block(Record):
    def __init__(self, extra: dict | None, hidden: dict) -> None:
        self.value, self.present = 1.0, ("value",)
        self.extra, self._extra = extra, hidden


def test_an_empty_extra_is_used_not_passed_over():
    # ``extra`` is used whenever it is not None, even empty; ``_extra`` only stands in for None
    assert _Block({}, {"value": 2.0}).to_dict()["value"] == 1.0
    assert _Block(None, {"value": 2.0}).to_dict()["value"] == 2.0
