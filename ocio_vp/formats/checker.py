"""What the parsers of a file's sections need from the file's validator.

The measurements file's :class:`~ocio_vp.formats.measurements.Validator` checks values and
names the file and key path in every error; the modules of its sections (panels, fixtures, the
synthesis record, the wall state) and the capture file take it as ``ctx`` typed by this
protocol, so they need not import the module that imports them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.geometry import PanelGeometry
from ocio_vp.formats.jsontypes import JsonMapping, JsonValue

__all__ = ["Checker", "describe"]

Key = tuple[str | int, ...]


def describe(value: JsonValue) -> str:
    """What a wrong value is, for "expected ..., got ..." messages."""
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    if value is None:
        return "nothing"
    return f"{type(value).__name__} {excerpt(value)}"


class Checker(Protocol):
    """Checks values of a parsed document; every error names ``source`` and the key path."""

    source: str

    def error(self, key: Key, problem: str) -> InputError: ...

    def mapping(
        self, value: JsonValue, key: Key, required: tuple[str, ...], optional: tuple[str, ...] = ()
    ) -> Mapping[str, Any]: ...

    def calibration(
        self, value: JsonMapping, key: Key
    ) -> tuple[PanelGeometry | None, float | None]: ...

    def number(
        self,
        value: JsonValue,
        key: Key,
        *,
        minimum: float = 0.0,
        strict: bool = False,
        maximum: float = ...,
    ) -> float: ...

    def rgb(
        self, value: JsonValue, key: Key, *, minimum: float = 0.0, maximum: float = ...
    ) -> np.ndarray: ...

    def chart(self, value: JsonValue, key: Key, n: int | None) -> np.ndarray: ...

    def signal(self, values: np.ndarray, key: Key) -> np.ndarray: ...

    def name(self, value: JsonValue, key: Key) -> str: ...
