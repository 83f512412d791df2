"""The types of JSON data: what a document reader returns and what a ``*_to_dict`` writes.

``JsonValue`` is exactly what :func:`json.loads` produces (YAML input is held to the same
values by :mod:`ocio_vp.formats.documents`); code that reads one narrows it with
``isinstance`` before use, so a wrong shape in a file is found where the file is read.
"""

from __future__ import annotations

from typing import TypeAlias, Union

__all__ = ["JsonObject", "JsonScalar", "JsonValue"]

JsonScalar: TypeAlias = Union[None, bool, int, float, str]
JsonValue: TypeAlias = Union[JsonScalar, "list[JsonValue]", "dict[str, JsonValue]"]
#: A JSON object (a mapping with text keys), the top level of every ocio-vp file.
JsonObject: TypeAlias = "dict[str, JsonValue]"
