"""Reading YAML/JSON documents and other input files with bounded work.

A small or odd input (a FIFO, a huge file, deep nesting, an alias bomb, duplicate keys, an
integer too long for a float64, a YAML tag beyond plain data) is refused with an
:class:`~ocio_vp.errors.InputError` before it can make ocio-vp hang or exhaust memory (limits:
docs/measurements.md). A YAML document holds JSON's values only
(:data:`~ocio_vp.formats.jsontypes.JsonValue`): a date and an integer key are kept as text.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from pathlib import Path

import yaml
from yaml.composer import Composer
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.resolver import Resolver

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.jsontypes import JsonObject, JsonValue

try:  # libyaml's scanner and parser are much faster; the composer below stays in Python.
    from yaml._yaml import CParser

    _PARSERS: tuple[type, ...] = (CParser,)
except ImportError:  # pragma: no cover - PyYAML built without libyaml
    from yaml.parser import Parser
    from yaml.reader import Reader
    from yaml.scanner import Scanner

    _PARSERS = (Reader, Scanner, Parser)

__all__ = [
    "MAX_DEPTH",
    "MAX_DOCUMENT_BYTES",
    "MAX_YAML_VALUES",
    "check_regular_file",
    "parse_document",
    "read_bounded",
    "read_document",
]

#: Largest YAML/JSON input file ocio-vp reads (measurements, capture, solution files).
MAX_DOCUMENT_BYTES = 16 * 1024 * 1024
#: Deepest nesting of lists/mappings in a document.
MAX_DEPTH = 64
#: Most values (scalars, lists and mappings, aliases expanded) in one YAML document.
MAX_YAML_VALUES = 200_000
#: Longest integer literal (digits); a float64 holds at most ~1.8e308.
MAX_INT_DIGITS = 309


class _LimitError(yaml.YAMLError):
    """A bound of this module was exceeded (reported like a YAML syntax error)."""

    def __init__(self, problem: str, mark: yaml.Mark | None = None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.problem_mark = mark


class _BoundedLoader(Composer, *_PARSERS, SafeConstructor, Resolver):  # type: ignore[misc]
    """SafeLoader semantics with depth, size, alias-expansion and duplicate-key limits.

    The parser (libyaml's when available) produces events without recursion; the composer,
    which is recursive, is PyYAML's own Python one with the limits added.
    """

    def __init__(self, stream: str) -> None:
        _PARSERS[0].__init__(self, stream)  # type: ignore[misc]  # the mixins' own __init__
        for base in _PARSERS[1:]:
            base.__init__(self)  # type: ignore[misc]
        Composer.__init__(self)
        SafeConstructor.__init__(self)
        Resolver.__init__(self)
        self._depth = 0
        self._values = 0

    def compose_node(self, parent: yaml.Node | None, index: int) -> yaml.Node | None:
        mark = self.peek_event().start_mark
        self._depth += 1
        self._values += 1
        if self._depth > MAX_DEPTH:
            raise _LimitError(f"nested deeper than {MAX_DEPTH} levels", mark)
        if self._values > MAX_YAML_VALUES:
            raise _LimitError(f"more than {MAX_YAML_VALUES} values (use JSON for more)", mark)
        alias = self.check_event(yaml.AliasEvent)  # checked where it was defined
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= 1
        if isinstance(node, yaml.MappingNode) and not alias:
            _check_keys(node)
        return node

    def construct_document(self, node: yaml.Node) -> JsonValue:
        _check_expansion(node)
        return super().construct_document(node)

    def construct_timestamp_text(self, node: yaml.ScalarNode) -> str:
        return str(node.value)

    def construct_not_json(self, node: yaml.Node) -> None:
        raise _LimitError(
            f"{node.tag.rsplit(':', 1)[-1]} values are not supported", node.start_mark
        )

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        text = str(node.value)
        if sum(c.isalnum() for c in text) > MAX_INT_DIGITS:
            raise _LimitError(
                f"integer of {len(text)} characters is too large for a number", node.start_mark
            )
        return super().construct_yaml_int(node)


_BoundedLoader.add_constructor("tag:yaml.org,2002:int", _BoundedLoader.construct_yaml_int)
# A date stays the text it was written as (what JSON gives for the same value).
_BoundedLoader.add_constructor(
    "tag:yaml.org,2002:timestamp", _BoundedLoader.construct_timestamp_text
)
for _tag in ("binary", "set", "omap", "pairs"):
    _BoundedLoader.add_constructor(f"tag:yaml.org,2002:{_tag}", _BoundedLoader.construct_not_json)


def _check_keys(node: yaml.MappingNode) -> None:
    """Refuse duplicate keys and keys that are not text (``1:``, ``null:``, ``yes:``)."""
    seen: dict[tuple[str, str], int] = {}
    for key_node, _ in node.value:
        if not isinstance(key_node, yaml.ScalarNode) or key_node.tag.endswith(":merge"):
            continue
        if key_node.tag.endswith(":int"):  # read as its text, as JSON has every key
            key_node.tag = "tag:yaml.org,2002:str"
        elif not key_node.tag.endswith(":str"):
            raise _LimitError(f"key {excerpt(key_node.value)} is not text", key_node.start_mark)
        ident = (key_node.tag, key_node.value)
        line = key_node.start_mark.line + 1
        if ident in seen:
            raise _LimitError(
                f"duplicate key {excerpt(key_node.value)} (first at line {seen[ident]})",
                key_node.start_mark,
            )
        seen[ident] = line


def _check_expansion(root: yaml.Node) -> None:
    """Refuse a node graph whose alias-expanded size exceeds :data:`MAX_YAML_VALUES`."""
    sizes: dict[int, int] = {}
    active: set[int] = set()

    def size(node: yaml.Node, depth: int) -> int:
        ident = id(node)
        if ident in sizes:
            return sizes[ident]
        if ident in active or depth > MAX_DEPTH:
            raise _LimitError("an alias refers to itself or nests too deep", node.start_mark)
        active.add(ident)
        total = 1
        if isinstance(node, yaml.SequenceNode):
            children = node.value
        elif isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        else:
            children = []
        for child in children:
            total += size(child, depth + 1)
            if total > MAX_YAML_VALUES:
                raise _LimitError(
                    f"aliases expand to more than {MAX_YAML_VALUES} values", node.start_mark
                )
        active.discard(ident)
        sizes[ident] = total
        return total

    size(root, 0)


def _json_object(pairs: list[tuple[str, JsonValue]]) -> JsonObject:
    out: JsonObject = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"duplicate key {excerpt(key)}")
        out[key] = value
    return out


def _json_int(text: str) -> int:
    if len(text) > MAX_INT_DIGITS:
        raise ValueError(f"integer of {len(text)} digits is too large for a number")
    return int(text)


def check_regular_file(path: str | os.PathLike[str], *, source: object = None) -> os.stat_result:
    """``os.stat`` of ``path`` if it is a regular file, else :class:`InputError`.

    FIFOs, devices and sockets are refused *before* opening: reading them can block forever
    (a FIFO nobody writes) or never end (``/dev/zero``).
    """
    source = path if source is None else source
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise InputError("file not found", source=source) from None
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror}", source=source) from None
    if stat.S_ISDIR(info.st_mode):
        raise InputError("is a folder, expected a file", source=source)
    if not stat.S_ISREG(info.st_mode):
        raise InputError(
            "is not a regular file (a FIFO, device or socket); give a file", source=source
        )
    return info


def read_bounded(
    path: str | os.PathLike[str], *, limit: int = MAX_DOCUMENT_BYTES, source: object = None
) -> bytes:
    """The bytes of the regular file ``path``, refusing files over ``limit`` bytes."""
    source = path if source is None else source
    info = check_regular_file(path, source=source)
    too_big = f"is over the {limit // (1024 * 1024)} MiB limit for this kind of file"
    if info.st_size > limit:
        raise InputError(f"{too_big} ({info.st_size} bytes)", source=source)
    try:
        # Non-blocking open: a FIFO swapped in after the check cannot block the open.
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        with os.fdopen(fd, "rb") as handle:
            if not stat.S_ISREG(os.fstat(handle.fileno()).st_mode):
                raise InputError("is not a regular file", source=source)
            data = handle.read(limit + 1)
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror}", source=source) from None
    if len(data) > limit:
        raise InputError(too_big, source=source)
    return data


def parse_document(raw: bytes, *, json_format: bool, source: object) -> JsonValue:
    """Parse YAML (or JSON when ``json_format``) bytes under this module's limits."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError("not a UTF-8 text file", source=source) from None
    if json_format:
        return _parse_json(text, source)
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(error, "problem", None) or "syntax error"
        if isinstance(error, ConstructorError) and "unhashable" in str(problem):
            problem = "a key that is a list or mapping"
        raise InputError(f"invalid YAML{where}: {problem}", source=source) from None
    except (ValueError, OverflowError, RecursionError) as error:
        raise InputError(f"invalid YAML: {excerpt(str(error), 60)}", source=source) from None
    finally:
        loader.dispose()


def _parse_json(text: str, source: object) -> JsonValue:
    try:
        return json.loads(text, object_pairs_hook=_json_object, parse_int=_json_int)
    except json.JSONDecodeError as error:
        raise InputError(
            f"invalid JSON at line {error.lineno}: {error.msg}", source=source
        ) from None
    except RecursionError:
        raise InputError("invalid JSON: nested too deep", source=source) from None
    except ValueError as error:
        raise InputError(f"invalid JSON: {error}", source=source) from None


def read_document(path: str | Path) -> tuple[JsonValue, str]:
    """Read a YAML or JSON file; returns the parsed data and the sha256 of its bytes.

    JSON is recognised by the ``.json`` suffix; anything else is read as YAML (JSON is valid
    YAML, but the JSON parser is faster and has no YAML-specific limits).

    Raises
    ------
    InputError
        When the file is missing, not a regular file, over :data:`MAX_DOCUMENT_BYTES`, not
        UTF-8, not valid YAML/JSON, or beyond one of this module's limits.
    """
    raw = read_bounded(path)
    data = parse_document(raw, json_format=Path(path).suffix.lower() == ".json", source=path)
    return data, hashlib.sha256(raw).hexdigest()
