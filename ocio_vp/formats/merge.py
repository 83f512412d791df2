"""Several measurements files, one solve: the wall from one file, the charts from others.

Each file is validated on its own first (so an error names its file), then merged: ``stage``
key by key, ``primaries``/``lit_chart``/``ramps`` whole from the one file giving them,
``environments`` and ``fixtures`` joined by name; a key given twice must agree. The merged
document is validated as one file (docs/measurements.md).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.measurements import (
    REQUIRED_SECTIONS,
    Measurements,
    check_measurements_part,
    load_measurements,
    measurements_from_dict,
    read_document,
)

__all__ = ["load_measurement_files", "merge_measurement_documents"]

_WHOLE = ("primaries", "lit_chart", "ramps")
_BY_NAME = ("environments", "fixtures")


def _conflict(key: str, first: str, second: str) -> InputError:
    return InputError(
        f"also given in {first} with a different value; give it in one file only (or the same "
        "value in both)",
        source=second,
        key=key,
    )


def _merge_named(
    merged: JsonObject, owners: dict[str, str], section: str, items: JsonValue, source: str
) -> None:
    """Join list ``section`` by ``name``: new names appended, repeated ones must be equal."""
    entries = merged.setdefault(section, [])
    assert isinstance(entries, list) and isinstance(items, list)  # a checked part's sections
    index = {_name(entry): i for i, entry in enumerate(entries)}
    for item in items:
        name = _name(item)
        key = f"{section}[name={name}]"
        if name not in index:
            index[name] = len(entries)
            entries.append(item)
            owners[key] = source
        elif entries[index[name]] != item:
            raise _conflict(f"{section} {excerpt(name)}", owners[key], source)


def _name(entry: JsonValue) -> str:
    assert isinstance(entry, dict) and isinstance(entry["name"], str)  # checked by the part
    return entry["name"]


def merge_measurement_documents(documents: Sequence[tuple[JsonObject, str]]) -> JsonObject:
    """One measurements document from several (``(document, source)`` pairs, each valid on
    its own as a part); see the module docstring.

    Raises
    ------
    InputError
        A key given twice with different values, naming the second file and both.
    """
    merged: JsonObject = {}
    owners: dict[str, str] = {}
    for document, source in documents:
        for key, value in document.items():
            if key in ("format", "version"):
                merged.setdefault(key, value)
            elif key == "stage":
                stage = merged.setdefault("stage", {})
                assert isinstance(stage, dict) and isinstance(value, dict)  # checked parts
                for name, item in value.items():
                    if name in stage and stage[name] != item:
                        raise _conflict(f"stage.{name}", owners[f"stage.{name}"], source)
                    stage.setdefault(name, item)
                    owners.setdefault(f"stage.{name}", source)
            elif key in _WHOLE:
                if key in merged and merged[key] != value:
                    raise _conflict(key, owners[key], source)
                merged.setdefault(key, value)
                owners.setdefault(key, source)
            elif key in _BY_NAME:
                _merge_named(merged, owners, key, value, source)
    return merged


def load_measurement_files(given: Sequence[str | Path]) -> Measurements:
    """Load one measurements file, or merge several (module docstring) into one.

    The merged measurements' ``source`` is the files' names joined by `` + ``, their
    ``sha256`` that of the lines ``<name>:<sha256 of the file>``, one per file in order.

    Raises
    ------
    InputError
        A file invalid on its own, a conflict between files, a section no file gives.
    """
    paths = [Path(p) for p in given]
    if len(set(paths)) != len(paths):
        raise InputError("the same measurements file is given twice", source=paths[0])
    documents: list[tuple[JsonObject, str]] = []
    digests: list[str] = []
    held: dict[str, list[str]] = {}
    for path in paths:
        data, digest = read_document(path)
        if len(paths) > 1 and isinstance(data, dict) and "panels" in data:
            raise InputError(
                "a measurements file with panels holds the whole stage (every panel type's "
                "wall and charts): solve it alone",
                source=path,
                key="panels",
            )
        for section in check_measurements_part(data, source=str(path)):
            held.setdefault(section, []).append(path.name)
        assert isinstance(data, dict)  # check_measurements_part refuses anything else
        documents.append((data, str(path)))
        digests.append(digest)
    missing = [s for s in REQUIRED_SECTIONS if s not in held]
    if missing and len(paths) == 1:
        raise InputError(
            f"missing required key {missing[0]!r}; a file holding part of the measurements "
            "(the wall, or the charts) is solved with the others: ocio-vp solve WALL.yaml "
            "CHARTS.yaml",
            source=paths[0],
        )
    if missing:
        raise InputError(
            f"no file gives {', '.join(missing)} (given: {', '.join(p.name for p in paths)})",
            source=paths[-1],
        )
    if len(paths) == 1:
        return load_measurements(paths[0])
    merged = merge_measurement_documents(documents)
    source = " + ".join(p.name for p in paths)
    lines = "".join(f"{p.name}:{d}\n" for p, d in zip(paths, digests, strict=True))
    sha256 = hashlib.sha256(lines.encode("utf-8")).hexdigest()
    return measurements_from_dict(merged, source=source, sha256=sha256)
