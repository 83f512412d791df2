"""Typed field reading for the files people write by hand (measurements, capture, sequence).

A :class:`Validator` reads one field at a time (a mapping with its allowed keys, a number in a
range, a whole number, a flag, a choice, a list, an ``[r, g, b]``, a chart, a safe name) and
raises :class:`InputError` naming the file, the key path and the problem, so each rule and each
message is written once. The parsers of a file's sections take it as ``ctx``.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

from ocio_vp.choices import WALL_ENCODINGS
from ocio_vp.errors import InputError, excerpt, format_key_path
from ocio_vp.formats.geometry import PanelGeometry
from ocio_vp.formats.jsontypes import JsonMapping, JsonValue

__all__ = [
    "CHANNELS",
    "MAX_CAMERA_VALUE",
    "MAX_PEAK_NITS",
    "MIN_BETA",
    "MIN_SIGNAL",
    "PANEL_RANGE",
    "SAFE_NAME",
    "Key",
    "Validator",
    "check_safe_name",
    "describe",
]

Key = tuple[str | int, ...]
#: The LED channels, in the order of [SL]'s columns.
CHANNELS = ("red", "green", "blue")
#: Names that are safe as folder names and inside Tcl, C, YAML and OCIO names.
#: (``\Z``, not ``$``: ``$`` also matches before a final newline.)
SAFE_NAME = re.compile(r"\A[A-Za-z0-9][A-Za-z0-9_-]{0,63}\Z")
#: Largest magnitude of a camera RGB value (raw 16-bit code values and HDR merges stay far below).
MAX_CAMERA_VALUE = 1e9
#: A block of camera values (primaries, a chart) whose largest value is positive but below this
#: is refused: it is not a photographed signal but data scaled by mistake.
MIN_SIGNAL = 1e-12
#: Smallest form factor ``beta`` (a panel ~500x farther away than it is wide).
MIN_BETA = 1e-6
#: Calibration panel width, height and distance (and |offset|) in metres.
PANEL_RANGE = (1e-3, 1e3)
#: Largest peak (cd/m2 of drive 1.0) a PQ wall may state: PQ's own ceiling.
MAX_PEAK_NITS = 10000.0


def describe(value: JsonValue) -> str:
    """What a wrong value is, for "expected ..., got ..." messages."""
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    if value is None:
        return "nothing"
    return f"{type(value).__name__} {excerpt(value)}"


class Validator:
    """Reads fields of a parsed document; every error names ``source`` and the key path."""

    def __init__(self, source: str = "") -> None:
        self.source = source

    def error(self, key: Key, problem: str) -> InputError:
        return InputError(problem, source=self.source or None, key=format_key_path(*key) or None)

    def mapping(
        self,
        value: JsonValue,
        key: Key,
        required: tuple[str, ...],
        optional: tuple[str, ...] = (),
        *,
        what: str = "key",
        listing: str = "",
    ) -> Mapping[str, Any]:
        """A mapping with every ``required`` key and no key (``what``) beyond ``optional``; an
        unknown key's message names the allowed ones sorted, or in their order after ``listing``
        (e.g. "panel types") when given."""
        if not isinstance(value, Mapping):
            raise self.error(key, f"expected a mapping, got {describe(value)}")
        # Unknown keys first: a misspelt required key is reported as the typo it is.
        allowed = set(required) | set(optional)
        for name in value:
            if name not in allowed:
                hint = difflib.get_close_matches(str(name)[:100], sorted(allowed), n=1)
                suggestion = f" (did you mean {hint[0]!r}?)" if hint else ""
                if listing:
                    expected = f"{listing}: {', '.join((*required, *optional))}"
                else:
                    expected = f"expected one of: {', '.join(sorted(allowed))}"
                raise self.error((*key, str(name)[:60]), f"unknown {what}{suggestion}; {expected}")
        for name in required:
            if name not in value:
                raise self.error(key, f"missing required key {excerpt(name)}")
        return value

    def header(self, top: JsonMapping, fmt: str, version: int) -> None:
        """Refuse a document whose ``format`` is not ``fmt`` or ``version`` not ``version``."""
        if top["format"] != fmt:
            raise self.error(("format",), f"expected {fmt!r}, got {excerpt(top['format'])}")
        if top["version"] != version or isinstance(top["version"], bool):
            raise self.error(
                ("version",), f"this ocio-vp reads version {version}, got {excerpt(top['version'])}"
            )

    def items(self, value: JsonValue, key: Key, what: str = "", *, empty: bool = False) -> list:
        """A list (non-empty unless ``empty``) of ``what``."""
        if not isinstance(value, list) or (not value and not empty):
            of = f" of {what}" if what else ""
            raise self.error(
                key, f"expected a {'' if empty else 'non-empty '}list{of}, got {describe(value)}"
            )
        return value

    def number(
        self,
        value: JsonValue,
        key: Key,
        *,
        minimum: float = 0.0,
        strict: bool = False,
        maximum: float = math.inf,
        at_most: str = "",
    ) -> float:
        """A finite float64 in ``[minimum, maximum]`` (``(minimum, maximum]`` when ``strict``);
        ``at_most`` words the upper bound in its message (default "a number <= maximum")."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(key, f"expected a number, got {describe(value)}")
        try:
            number = float(value)
        except OverflowError:  # an integer beyond float64
            raise self.error(key, "expected a number, got an integer too large for one") from None
        if not math.isfinite(number):
            raise self.error(key, f"expected a finite number, got {excerpt(value)}")
        if number < minimum or (strict and number == minimum):
            relation = ">" if strict else ">="
            raise self.error(key, f"expected a number {relation} {minimum:g}, got {number:.6g}")
        if number > maximum:
            bound = at_most or f"a number <= {maximum:g}"
            raise self.error(key, f"expected {bound}, got {number:.6g}")
        return number

    def whole(
        self,
        value: JsonValue,
        key: Key,
        minimum: int | None = 0,
        maximum: int | None = None,
        *,
        noun: str = "a whole number",
    ) -> int:
        """An integer (not a bool) in ``[minimum, maximum]`` (None: unbounded); ``noun`` names
        it in the message."""
        low = -math.inf if minimum is None else minimum
        high = math.inf if maximum is None else maximum
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            if minimum is None:
                expected = noun
            elif maximum is None:
                expected = f"{noun} >= {minimum}"
            else:
                expected = f"{noun} {minimum}..{maximum}"
            raise self.error(key, f"expected {expected}, got {excerpt(value)}")
        return value

    def size(
        self, value: JsonValue, key: Key, maximum: int | None = None, *, whole_list: bool = False
    ) -> tuple[int, int]:
        """``[width, height]`` in pixels, each 1 or more (at most ``maximum``). A wrong value is
        named by its place in the list, or (``whole_list``) the whole list is quoted."""
        high = math.inf if maximum is None else maximum
        pair = value if isinstance(value, list) and len(value) == 2 else None
        whole = pair is not None and all(
            isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= high for v in pair
        )
        if whole_list and not whole:
            raise self.error(key, f"expected [width, height] in pixels, got {excerpt(value)}")
        if pair is None:
            raise self.error(key, "expected [width, height]")
        width, height = (self.whole(v, (*key, i), 1, maximum) for i, v in enumerate(pair))
        return width, height

    def flag(self, value: JsonValue, key: Key) -> bool:
        if not isinstance(value, bool):
            raise self.error(key, f"expected true or false, got {describe(value)}")
        return value

    def choice(
        self,
        value: JsonValue,
        key: Key,
        allowed: Collection[str],
        *,
        what: str = "",
        quoted: bool = False,
    ) -> str:
        """One of ``allowed``; ``what`` names the kind of value in the message, ``quoted`` lists
        the choices as a Python list (``['a', 'b']``) rather than ``a, b``."""
        if not isinstance(value, str) or value not in allowed:
            listed = str(list(allowed)) if quoted else ", ".join(allowed)
            if what:
                raise self.error(key, f"unknown {what} {excerpt(value)}; expected one of: {listed}")
            raise self.error(key, f"expected one of {listed}, got {excerpt(value)}")
        return value

    def text(self, value: JsonValue, key: Key, *, limit: int | None = 500) -> str:
        """One line of non-blank text of at most ``limit`` characters; with ``limit`` None, any
        non-empty text (several lines, blanks) as files written before this rule held."""
        if limit is None:
            if not isinstance(value, str) or not value:
                raise self.error(key, "expected a non-empty text")
            return value
        if not isinstance(value, str) or not value.strip() or len(value) > limit:
            raise self.error(key, f"expected a non-empty text of at most {limit} characters")
        if "\n" in value or "\r" in value:
            raise self.error(key, "expected one line of text")
        return value

    def wall_encoding(self, value: JsonValue, key: Key) -> str:
        return self.choice(value, key, WALL_ENCODINGS, what="encoding")

    def peak_nits(self, value: JsonValue, key: Key) -> float:
        return self.number(value, key, strict=True, maximum=MAX_PEAK_NITS)

    def encoding(
        self, value: JsonMapping, key: Key, name: str, *, needs_peak: bool = False
    ) -> tuple[str | None, float | None]:
        """The wall encoding ``value[name]`` (None: not stated) and ``peak_nits``, which only a
        ``pq`` one may give (and must, if ``needs_peak``)."""
        encoding = value.get(name)
        if encoding is not None:
            encoding = self.wall_encoding(encoding, (*key, name))
        if "peak_nits" in value and encoding != "pq":
            raise self.error((*key, "peak_nits"), f"only with {name}: pq")
        if "peak_nits" in value:
            return encoding, self.peak_nits(value["peak_nits"], (*key, "peak_nits"))
        if needs_peak and encoding == "pq":
            raise self.error((*key, "peak_nits"), "a pq wall needs its peak (cd/m2 of drive 1.0)")
        return encoding, None

    def calibration(
        self, value: JsonMapping, key: Key
    ) -> tuple[PanelGeometry | None, float | None]:
        """``calibration_panel`` and/or ``beta`` of a mapping (the stage, or a panel type):
        the lit-chart setup that gives beta; one of them is required."""
        panel = None
        if "calibration_panel" in value:
            pkey = (*key, "calibration_panel")
            raw = self.mapping(
                value["calibration_panel"],
                pkey,
                required=("width", "height", "distance"),
                optional=("offset_x", "offset_y"),
            )
            low, high = PANEL_RANGE  # metres: a panel from a millimetre to a kilometre
            sizes = {
                name: self.number(raw[name], (*pkey, name), minimum=low, maximum=high)
                for name in ("width", "height", "distance")
            }
            offsets = {
                name: self.number(raw.get(name, 0.0), (*pkey, name), minimum=-high, maximum=high)
                for name in ("offset_x", "offset_y")
            }
            panel = PanelGeometry(**sizes, **offsets)
        beta = None
        if "beta" in value:
            beta = self.number(value["beta"], (*key, "beta"), minimum=MIN_BETA)
            if beta > 1.0:
                raise self.error((*key, "beta"), f"a form factor is at most 1, got {beta:.6g}")
        if panel is None and beta is None:
            raise self.error(key, "give either calibration_panel {width, height, distance} or beta")
        return panel, beta

    def rgb(
        self,
        value: JsonValue,
        key: Key,
        *,
        minimum: float = 0.0,
        maximum: float = MAX_CAMERA_VALUE,
    ) -> np.ndarray:
        """Camera ``[r, g, b]``: each value in ``[minimum, maximum]``."""
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise self.error(key, f"expected [r, g, b], got {describe(value)}")
        numbers = [
            self.number(v, (*key, i), minimum=minimum, maximum=maximum) for i, v in enumerate(value)
        ]
        return np.array(numbers, dtype=np.float64)

    def matrix(self, value: JsonValue, key: Key, shape: tuple[int, int], what: str) -> np.ndarray:
        """A (rows, columns) float64 matrix of finite numbers of any sign, given as rows."""
        rows, columns = shape
        if not isinstance(value, list) or len(value) != rows:
            raise self.error(key, f"expected {what}, got {describe(value)}")
        out = []
        for i, row in enumerate(value):
            if not isinstance(row, list) or len(row) != columns:
                raise self.error(
                    (*key, i), f"expected a row of {columns} numbers, got {describe(row)}"
                )
            out.append([self.number(v, (*key, i, k), minimum=-math.inf) for k, v in enumerate(row)])
        return np.array(out, dtype=np.float64)

    def chart(
        self, value: JsonValue, key: Key, n: int | None, like: str = "lit_chart.red"
    ) -> np.ndarray:
        """(n, 3) camera RGB of a chart's patches, as many as ``like`` has when ``n`` is given."""
        if not isinstance(value, (list, tuple)) or not value:
            raise self.error(key, f"expected a list of [r, g, b] patches, got {describe(value)}")
        if n is not None and len(value) != n:
            raise self.error(key, f"has {len(value)} patches, expected {n} like {like}")
        return np.stack([self.rgb(v, (*key, i)) for i, v in enumerate(value)])

    def primaries(self, value: JsonValue, key: Key) -> np.ndarray:
        """[SL] (3, 3) of a ``primaries`` block: column k the camera RGB of LED channel k."""
        block = self.mapping(value, key, required=CHANNELS)
        SL = np.stack([self.rgb(block[c], (*key, c)) for c in CHANNELS], axis=1)
        return self.signal(SL, key)

    def lit_chart(self, value: JsonValue, key: Key, n: int | None, like: str = "") -> np.ndarray:
        """[SRL] (n, camera, LED) of a ``lit_chart`` block; every channel's chart has ``n``
        patches (as ``like`` has) or, ``n`` None, as many as its red one."""
        block = self.mapping(value, key, required=CHANNELS)
        charts: list[np.ndarray] = []
        for c in CHANNELS:
            if n is None and charts:
                n, like = len(charts[0]), f"{format_key_path(*key)}.red"
            charts.append(self.chart(block[c], (*key, c), n, like))
        return self.signal(np.stack(charts, axis=2), key)

    def signal(self, values: np.ndarray, key: Key) -> np.ndarray:
        """Refuse camera values that are all positive-but-tiny: scaled data, not a photograph."""
        peak = float(np.max(np.abs(values))) if values.size else 0.0
        if 0.0 < peak < MIN_SIGNAL:
            raise self.error(
                key, f"largest value is {peak:.3g}, below {MIN_SIGNAL:g}: is the data scaled?"
            )
        return values

    def name(self, value: JsonValue, key: Key) -> str:
        if not isinstance(value, str) or not SAFE_NAME.match(value):
            raise self.error(
                key,
                f"unsafe name {excerpt(value)}: use 1-64 letters, digits, '_' or '-', "
                "starting with a letter or digit",
            )
        return value

    def unique_name(self, value: JsonValue, key: Key, seen: dict[str, int]) -> str:
        """A safe name not in ``seen`` (name -> index in the list ``key[:-1]`` names), added."""
        name = self.name(value, (*key, "name"))
        if name in seen:
            where = format_key_path(*key[:-1], seen[name])
            raise self.error((*key, "name"), f"duplicate name {name!r} (also {where})")
        seen[name] = int(key[-1])
        return name


def check_safe_name(value: JsonValue, *, source: object = None, key: str | None = None) -> str:
    """Return ``value`` if it is a safe environment/stage name, else raise :class:`InputError`."""
    return Validator(str(source) if source else "input").name(value, (key or "name",))
