"""Typed records of ``solution.json``: small frozen dataclasses whose fields are a block's keys,
in file order. :func:`read_record` converts each JSON value to its field's type, so a record
holds the same types after a solve and after a load (a wrong type is an InputError naming its
key); :meth:`Record.to_dict` writes a loaded record back with the keys its file had.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Mapping
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.checker import Validator
from ocio_vp.formats.jsontypes import JsonObject, JsonValue

__all__ = [
    "MAX_VALUE",
    "Figures",
    "Record",
    "finite_array",
    "floats",
    "json_object",
    "json_value",
    "optional_array",
    "read_record",
    "read_value",
]

#: Largest magnitude a solved matrix or vector read back may have (far beyond any stage).
MAX_VALUE = 1e30

R = TypeVar("R")


class Record:
    """Mixin for a frozen dataclass that is a block of ``solution.json``.

    ``OMIT_NONE`` names the fields a fresh record leaves out of its file when they are None. A
    record read from a file remembers its keys (``present``) and the keys this version does not
    know (``extra``) outside its fields, so equality compares values only.
    """

    OMIT_NONE: ClassVar[tuple[str, ...]] = ()

    def to_dict(self) -> dict[str, Any]:
        """The block as written: its keys in file order, values as they are (numpy kept)."""
        extra = getattr(self, "extra", None)
        extra = dict((getattr(self, "_extra", None) if extra is None else extra) or {})
        present = getattr(self, "present", None)
        if present is None:
            present = getattr(self, "_present", None)
        if present is None:
            names = [f.name for f in dataclasses.fields(self) if f.name not in _HIDDEN]  # type: ignore[arg-type]
            keys = [n for n in names if n not in self.OMIT_NONE or getattr(self, n) is not None]
            present = (*keys, *extra)
        return {k: extra[k] if k in extra else getattr(self, k) for k in present}


class Figures(Record):
    """Mixin for a record of measured figures kept as files keep them
    (:func:`ocio_vp.metrics.as_recorded`: ``DIGITS`` significant digits, 0 below rounding), so
    that a solve and a load hold the same digits and none of them is machine noise.
    ``FIGURES`` names the fields so kept (None: every float field)."""

    DIGITS: ClassVar[int] = 6
    FIGURES: ClassVar[tuple[str, ...] | None] = None

    def __post_init__(self) -> None:
        from ocio_vp.metrics import as_recorded

        names = self.FIGURES or [f.name for f in dataclasses.fields(self)]  # type: ignore[arg-type]
        for name in names:
            value = getattr(self, name)
            if isinstance(value, float):
                object.__setattr__(self, name, as_recorded(value, self.DIGITS))


#: Fields a record may have that are not keys of its block.
_HIDDEN = ("extra", "present")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def read_record(cls: type[R], data: object, key: str) -> R:
    """``data`` (a JSON mapping) as a ``cls`` record; ``key`` names the block in errors."""
    if not isinstance(data, Mapping):
        raise InputError(f"expected a mapping, got {excerpt(data)}", key=key)
    hints = _hints(cls)  # type: ignore[arg-type]  # a class is hashable
    fields = {f.name: f for f in dataclasses.fields(cls) if f.name not in _HIDDEN}  # type: ignore[arg-type]
    values = {}
    for name, field in fields.items():
        if name in data:
            values[name] = read_value(data[name], hints[name], f"{key}.{name}")
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            raise InputError(f"missing key {name!r}", key=key)
    extra = {k: v for k, v in data.items() if k not in fields}
    names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    if "extra" in names:
        values["extra"] = extra
    if "present" in names:
        values["present"] = tuple(data)
    try:
        record = cls(**values)
    except InputError as error:
        raise InputError(error.problem, key=f"{key}.{error.key}" if error.key else key) from None
    except (TypeError, ValueError) as error:
        raise InputError(f"malformed ({excerpt(str(error), 60)})", key=key) from None
    if "present" not in names:
        object.__setattr__(record, "_present", tuple(data))
        object.__setattr__(record, "_extra", extra)
    return record


def read_value(value: object, hint: Any, key: str) -> Any:
    """``value`` from JSON converted to the type ``hint`` (InputError naming ``key`` if not)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        others = [a for a in args if a is not type(None)]
        if len(others) == 1:
            return read_value(value, others[0], key)
        for other in others:  # e.g. float | str: the first that reads it
            try:
                return read_value(value, other, key)
            except InputError:
                continue
        raise InputError(f"unexpected value {excerpt(value)}", key=key)
    if dataclasses.is_dataclass(hint):
        return read_record(hint, value, key)  # type: ignore[arg-type]
    reader = _SCALARS.get(hint)
    if reader is not None:
        return reader(value, key)
    if origin in (list, tuple) and isinstance(value, list):
        if origin is tuple and (len(args) != 2 or args[1] is not Ellipsis):
            if len(value) != len(args):
                raise InputError(f"expected {len(args)} values, got {len(value)}", key=key)
            return tuple(
                read_value(v, a, f"{key}[{i}]")
                for i, (v, a) in enumerate(zip(value, args, strict=True))
            )
        item = args[0] if args else Any
        out = [read_value(v, item, f"{key}[{i}]") for i, v in enumerate(value)]
        return out if origin is list else tuple(out)
    if origin in (dict, Mapping) and isinstance(value, Mapping):
        item = args[1] if args else Any
        return {str(k): read_value(v, item, f"{key}.{k}") for k, v in value.items()}
    raise InputError(f"unexpected value {excerpt(value)}", key=key)


def floats(array: ArrayLike) -> JsonValue:
    """``array`` as (nested) lists of plain floats, as YAML and JSON write it."""
    return np.asarray(array, dtype=np.float64).tolist()


def finite_array(
    data: Mapping[str, object], name: str, shape: tuple[int, ...], within: str = ""
) -> np.ndarray:
    """``data[name]`` (a JSON list) as a finite float64 array of ``shape``, no entry beyond
    :data:`MAX_VALUE`; else InputError naming the key (``within.name``).

    The old call ``finite_array(value, shape, key)`` fails at once with a TypeError saying so."""
    if not isinstance(name, str) or not isinstance(data, Mapping):
        raise TypeError(
            "finite_array(value, shape, key) is now finite_array(data, name, shape, within): "
            "pass the mapping holding the value and the value's key"
        )
    value, key = data.get(name), f"{within}.{name}" if within else name
    try:
        array = np.asarray(value if isinstance(value, list) else (), dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        array = np.zeros(0)
    if array.shape != shape or not np.all(np.isfinite(array)) or np.any(abs(array) > MAX_VALUE):
        what = {(3, 3): "3x3 matrix", (3,): "[r, g, b]"}.get(shape, f"array of shape {shape}")
        raise InputError(f"expected a finite {what}", key=key)
    return array


def optional_array(
    data: Mapping[str, object], name: str, shape: tuple[int, ...], within: str = ""
) -> np.ndarray | None:
    """:func:`finite_array`, or None where ``data[name]`` is missing or null."""
    return None if data.get(name) is None else finite_array(data, name, shape, within)


def _float(value: object, key: str) -> float:
    """A number; JSON's "inf"/"-inf" text (how solution.json writes an infinite one) too."""
    if isinstance(value, str) and value in ("inf", "-inf"):
        return float(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a number, got {excerpt(value)}", key=key)
    return float(value)


def _str(value: object, key: str) -> str:
    if not isinstance(value, str):
        raise InputError(f"expected text, got {excerpt(value)}", key=key)
    return value


def _array(value: object, key: str) -> np.ndarray:
    """A float64 array; null entries (how a NaN is written) become NaN, "inf" text infinite."""
    if not isinstance(value, list):
        raise InputError(f"expected a list of numbers, got {excerpt(value)}", key=key)
    try:
        array = np.array(_numbers(value), dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"expected a list of numbers, got {excerpt(value)}", key=key) from None
    if array.dtype != np.float64 or array.ndim == 0:
        raise InputError(f"expected a list of numbers, got {excerpt(value)}", key=key)
    return array


def _numbers(value: object) -> object:
    if isinstance(value, list):
        return [_numbers(v) for v in value]
    if value is None:
        return float("nan")
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise TypeError(value)
    return value if not isinstance(value, str) else float(value)


_SCALARS: dict[Any, Any] = {
    float: _float,
    int: lambda value, key: Validator().whole(value, (key,), None),
    bool: lambda value, key: Validator().flag(value, (key,)),
    str: _str,
    np.ndarray: _array,
}


def json_object(mapping: Mapping[str, Any]) -> JsonObject:
    """``mapping`` as a JSON object (its values converted by :func:`json_value`)."""
    return {str(k): json_value(v) for k, v in mapping.items()}


def json_value(value: Any) -> JsonValue:
    """``value`` as JSON types (numpy values and records converted). A non-finite float is
    written as null (NaN) or the string "inf"/"-inf": only cond_Q of a singular Q should ever be
    one (docs/stability.md; tests/test_pipeline.py and benchmarks/sweep.py look for any other).
    """
    if isinstance(value, np.ndarray):
        return json_value(value.tolist())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        to_dict = getattr(value, "to_dict", None)
        return json_value(to_dict() if to_dict else dataclasses.asdict(value))
    if isinstance(value, Mapping):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_value(v) for v in value]
    if isinstance(value, (np.floating, float)):
        number = float(value)
        if not np.isfinite(number):
            return None if np.isnan(number) else ("inf" if number > 0 else "-inf")
        return number
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
