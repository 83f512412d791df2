"""solution.json's ``panels`` block, written for a stage of several panel types: what was
solved for each (keys and meaning: docs/solution.md); and the ``ocio`` block of both levels.
"""

from __future__ import annotations

import dataclasses
from collections.abc import ItemsView, Iterator, KeysView, Mapping, ValuesView
from dataclasses import dataclass, field

import numpy as np

from ocio_vp.deprecation import warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.formats.checker import Validator, check_safe_name
from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.linearity import Linearity, read_linearity
from ocio_vp.formats.records import Record, finite_array, json_object, optional_array, read_record

__all__ = [
    "CONFIG_FILENAME",
    "OcioNames",
    "PanelSolution",
    "panel_solutions_from_dict",
    "panel_solutions_to_dict",
]

#: The config's file name beside solution.json when its ``ocio`` block does not name one.
CONFIG_FILENAME = "config.ocio"


@dataclass(frozen=True)
class OcioNames(Record):
    """solution.json's ``ocio`` block: the config file and the names of its colour spaces,
    named transform, display and views by role. Empty until the config is written; a panel
    type's names only its own colour spaces and views; an older file may lack some."""

    config: str | None = None
    reference: str | None = None
    out_of_frustum: str | None = None
    in_frustum: str | None = None
    post_correction: str | None = None
    post_correction_colorspace: str | None = None
    display: str | None = None
    view_out_of_frustum: str | None = None
    view_in_frustum: str | None = None

    @property
    def config_file(self) -> str:
        return self.config or CONFIG_FILENAME

    # The dict interface of this block's earlier form, served for one more release.

    def __getitem__(self, key: str) -> str:
        value = self._old_lookup(key, f'ocio["{key}"]')
        if value is None:
            raise KeyError(key)
        return value

    def get(self, key: str, default: str | None = None) -> str | None:
        value = self._old_lookup(key, f'ocio.get("{key}")')
        return default if value is None else value

    def __contains__(self, key: object) -> bool:
        warn_deprecated(f'"{key}" in ocio', f"ocio.{key} is not None")
        return key in self._named()

    def __iter__(self) -> Iterator[str]:
        warn_deprecated("iterating ocio", "ocio.to_dict()")
        return iter(self._named())

    def keys(self) -> KeysView[str]:  # with ocio[key], what dict(ocio) reads
        warn_deprecated("ocio.keys()", "ocio.to_dict()")
        return self._named().keys()

    def items(self) -> ItemsView[str, str]:
        warn_deprecated("ocio.items()", "ocio.to_dict()")
        return self._named().items()

    def values(self) -> ValuesView[str]:
        warn_deprecated("ocio.values()", "ocio.to_dict()")
        return self._named().values()

    def _named(self) -> dict[str, str]:
        """The roles named in this block, as the old dict had them (None: no key)."""
        return {k: v for k in OcioNames.OMIT_NONE if (v := getattr(self, k)) is not None}

    def _old_lookup(self, key: str, spelled: str) -> str | None:
        warn_deprecated(spelled, f"ocio.{key}", stacklevel=4)
        return self._named().get(key)


OcioNames.OMIT_NONE = tuple(f.name for f in dataclasses.fields(OcioNames))  # each when named


def read_ocio_names(block: JsonValue, key: str = "ocio") -> OcioNames:
    """The ``ocio`` block (absent: empty); only text values (InputError naming ``key``)."""
    block = {} if block is None else block
    if not isinstance(block, Mapping) or not all(isinstance(v, str) for v in block.values()):
        raise InputError("expected names (text) only", key=key)
    return read_record(OcioNames, block, key)


@dataclass(frozen=True)
class PanelSolution:
    """One panel type's solve in one environment (float64 arrays; keys: docs/solution.md):
    ``drive`` is its lighting drive ``M w_avg``, ``share`` its part of the light on the chart's
    white patch (luminance, 0-1); ``N`` (None with ``N_reason`` where Q cannot be inverted) and
    ``black_level_offset`` only for an in-frustum type."""

    name: str
    in_frustum: bool
    SL: np.ndarray
    M: np.ndarray
    beta: float
    w_avg: np.ndarray
    drive: np.ndarray
    share: float
    N: np.ndarray | None = None
    N_reason: str | None = None
    black_level_offset: np.ndarray | None = None
    linearity: Linearity | None = None
    ocio: OcioNames = field(default_factory=OcioNames)

    @property
    def in_frustum_matrix(self) -> np.ndarray:
        """N where it was solved, else M (as :attr:`Solution.in_frustum_matrix`)."""
        return self.M if self.N is None else self.N


def panel_solutions_to_dict(panels: Mapping[str, PanelSolution]) -> JsonObject:
    """The ``panels`` block."""
    out: JsonObject = {}
    for name, p in panels.items():
        entry = {
            "in_frustum": p.in_frustum,
            "SL": p.SL,
            "M": p.M,
            "beta": p.beta,
            "w_avg": p.w_avg,
            "drive": p.drive,
            "share": p.share,
        }
        if p.in_frustum:
            entry.update(N=p.N, N_reason=p.N_reason, black_level_offset=p.black_level_offset)
        entry.update(linearity=p.linearity, ocio=p.ocio)
        out[name] = json_object(entry)
    return out


def _one(name: str, entry: JsonValue) -> PanelSolution:
    key = f"panels.{name}"
    if not isinstance(entry, Mapping) or not isinstance(entry.get("in_frustum"), bool):
        raise InputError("expected a mapping with in_frustum true or false", key=key)
    in_frustum = entry["in_frustum"] is True
    inner = entry if in_frustum else {}  # what only an in-frustum type has
    numbers = {
        f: Validator().number(entry.get(f), (key, f), maximum=1.0) for f in ("beta", "share")
    }
    reason = entry.get("N_reason")
    if reason is not None and not isinstance(reason, str):
        raise InputError("expected text", key=f"{key}.N_reason")
    return PanelSolution(
        name=name,
        in_frustum=in_frustum,
        SL=finite_array(entry, "SL", (3, 3), key),
        M=finite_array(entry, "M", (3, 3), key),
        beta=numbers["beta"],
        w_avg=finite_array(entry, "w_avg", (3,), key),
        drive=finite_array(entry, "drive", (3,), key),
        share=numbers["share"],
        N=optional_array(inner, "N", (3, 3), key),
        N_reason=reason if in_frustum else None,
        black_level_offset=optional_array(inner, "black_level_offset", (3,), key),
        linearity=read_linearity(entry.get("linearity"), f"{key}.linearity"),
        ocio=read_ocio_names(entry.get("ocio"), f"{key}.ocio"),
    )


def panel_solutions_from_dict(block: JsonValue) -> dict[str, PanelSolution] | None:
    """The ``panels`` block of a loaded solution.json (None when absent); InputErrors name the
    key (:func:`~ocio_vp.formats.solution.load_solution` adds the file)."""
    if block is None:
        return None
    if not isinstance(block, Mapping) or not block:
        raise InputError("expected a non-empty mapping of panel types", key="panels")
    out = {}
    for name, entry in block.items():
        check_safe_name(name, key="panels")
        out[name] = _one(name, entry)
    if not any(p.in_frustum for p in out.values()):
        raise InputError("no in-frustum panel type", key="panels")
    return out
