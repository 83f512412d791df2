"""The types of JSON data: what a document reader returns and what a ``*_to_dict`` writes.

``JsonValue`` is what :func:`json.loads` produces (YAML input is held to the same values by
:mod:`ocio_vp.formats.documents`); code that reads one narrows it with ``isinstance`` before
use, so a wrong shape in a file is found where the file is read. Its containers are read-only
(``Sequence``, ``Mapping``), so a ``list[float]`` or a ``dict[str, list[float]]`` built by a
writer is one as it is; numpy values are not (convert them, e.g. ``.tolist()``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TypeAlias, Union

__all__ = ["JsonMapping", "JsonObject", "JsonScalar", "JsonValue", "YamlValue"]

JsonScalar: TypeAlias = bool | int | float | str | None
JsonValue: TypeAlias = Union[JsonScalar, "Sequence[JsonValue]", "Mapping[str, JsonValue]"]
#: A JSON object being built (a mapping with text keys), the top level of every ocio-vp file.
JsonObject: TypeAlias = "dict[str, JsonValue]"
#: A JSON object only read.
JsonMapping: TypeAlias = "Mapping[str, JsonValue]"
#: A value ocio-vp writes as YAML: JSON's, and mappings keyed by integers (chart indices).
#: Read back, an integer key is its text, as JSON would have it.
YamlValue: TypeAlias = Union[
    JsonScalar, "Sequence[YamlValue]", "Mapping[str, YamlValue]", "Mapping[int, YamlValue]"
]
