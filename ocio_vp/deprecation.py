"""Names that left the public API, served for one more release with a DeprecationWarning.

A module sets ``__getattr__ = deprecated_names(__name__, table)`` (PEP 562), the table mapping
each old name to (what to use instead, in words; where its value lives, ``"module:name"``, or a
function returning it), imported only when the old name is used.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["REMOVED_IN", "deprecated_names", "warn_deprecated"]

#: The release that removes every name served here (deprecated from the release after 0.1.0).
REMOVED_IN = "0.3.0"


def warn_deprecated(old: str, replacement: str, stacklevel: int = 3) -> None:
    """Warn that ``old`` goes away in :data:`REMOVED_IN`, naming ``replacement``."""
    warnings.warn(
        f"{old} is deprecated and will be removed in ocio_vp {REMOVED_IN}: use {replacement}",
        DeprecationWarning,
        stacklevel=stacklevel,
    )


def deprecated_names(
    module: str, table: Mapping[str, tuple[str, str | Callable[[], Any]]]
) -> Callable[[str], Any]:
    """A module ``__getattr__`` serving the old names of ``table`` with a DeprecationWarning."""

    def __getattr__(name: str) -> Any:
        if name not in table:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        replacement, value = table[name]
        warn_deprecated(f"{module}.{name}", replacement)
        if isinstance(value, str):
            module_name, _, attribute = value.partition(":")
            return getattr(importlib.import_module(module_name), attribute)
        return value()

    return __getattr__
