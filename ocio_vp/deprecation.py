"""Module attributes served on first use (PEP 562): names that left the public API, for one
more release with a DeprecationWarning (:func:`deprecated_names`), and a package's public names,
imported when first read (:func:`published_on_first_use`; ``ocio_vp`` itself writes the same two
functions out, so that ``import ocio_vp`` loads none of its modules).
"""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["REMOVED_IN", "deprecated_names", "published_on_first_use", "warn_deprecated"]

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
    """A module ``__getattr__`` serving the old names of ``table`` with a DeprecationWarning: each
    maps to (what to use instead, in words; where its value lives, ``"module:name"``, or a
    function returning it), imported only when the old name is used."""

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


def published_on_first_use(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` (a module being imported), whose
    public names ``exports`` maps to the modules defining them: the first read of a name imports
    its module and keeps the value in the package, so later reads skip the lookup."""
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str) -> object:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted([*namespace, *exports])

    return __getattr__, __dir__
