"""What the wall was sent while it was measured, carried from ``sequence.yaml`` to the solve.

``patterns`` writes the wall's encoding, peak (PQ) and frame size into ``sequence.yaml``;
``measure`` copies them into the measurements file's ``stage`` (``wall_encoding``,
``peak_nits``, ``pattern_size``; docs/measurements.md) and ``solve`` uses them. A stage of
several panel types gives ``encoding`` and ``peak_nits`` per type instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from ocio_vp.errors import InputError, excerpt
from ocio_vp.formats.checker import Validator
from ocio_vp.formats.jsontypes import JsonMapping, JsonObject

__all__ = ["WALL_STATE_KEYS", "WallState", "parse_wall_state", "stage_with_sequence"]

#: The ``stage`` keys this module owns, in file order.
WALL_STATE_KEYS = ("wall_encoding", "peak_nits", "pattern_size")
_MAX_SIZE = 65536


@dataclass(frozen=True)
class WallState:
    """The wall's signal encoding, peak and pattern size as a measurements file states them
    (None: not stated, e.g. a wall measured from plates)."""

    encoding: str | None = None
    peak_nits: float | None = None
    pattern_size: tuple[int, int] | None = None

    def to_dict(self) -> JsonObject:
        """The ``stage`` keys (only the stated ones)."""
        out: JsonObject = {}
        if self.encoding is not None:
            out["wall_encoding"] = self.encoding
        if self.peak_nits is not None:
            out["peak_nits"] = self.peak_nits
        if self.pattern_size is not None:
            out["pattern_size"] = list(self.pattern_size)
        return out

    def describe(self) -> str:
        """``'pq at 1000 cd/m2'``, ``'linear'`` or ``'not stated'``."""
        if self.encoding is None:
            return "not stated"
        peak = f" at {self.peak_nits:g} cd/m2" if self.peak_nits is not None else ""
        return f"{self.encoding}{peak}"


def parse_wall_state(ctx: Validator, stage: JsonMapping, key: tuple[str | int, ...]) -> WallState:
    """The :class:`WallState` of a ``stage`` mapping (``ctx``: the file's Validator)."""
    encoding, peak = ctx.encoding(stage, key, "wall_encoding", needs_peak=True)
    size = stage.get("pattern_size")
    pattern_size = (
        None if size is None else ctx.size(size, (*key, "pattern_size"), _MAX_SIZE, whole_list=True)
    )
    return WallState(encoding, None if peak is None else float(peak), pattern_size)


class PlayedSequence(Protocol):
    """What the wall played (a :class:`~ocio_vp.patterns.sequence.PatternSequence`, which
    imports this module): its signal encoding, peak and pattern size."""

    @property
    def encoding(self) -> str: ...

    @property
    def peak_nits(self) -> float | None: ...

    @property
    def size(self) -> tuple[int, int]: ...


def stage_with_sequence(stage: JsonMapping, sequence: PlayedSequence, *, source: str) -> JsonObject:
    """``stage`` (a capture file's section) with the wall state of the take's ``sequence``
    (a :class:`~ocio_vp.patterns.sequence.PatternSequence`) added; a capture file that states
    another encoding or peak than the sequence the wall played is refused."""
    take = WallState(
        sequence.encoding,
        None if sequence.peak_nits is None else float(sequence.peak_nits),
        (int(sequence.size[0]), int(sequence.size[1])),
    )
    for name, value in take.to_dict().items():
        if name in stage and stage[name] != value:
            raise InputError(
                f"the capture file says {excerpt(stage[name])}, the take's sequence.yaml "
                f"{excerpt(value)} (the wall played {take.describe()}): state what the wall "
                "played, or leave the key out",
                source=source,
                key=f"stage.{name}",
            )
    return {**stage, **take.to_dict()}
