"""``diagnostics.skin`` of ``solution.json``: what a solve expects faces to look like, as typed
records (figures and keys: docs/solution.md, docs/skin.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from ocio_vp.formats.records import Figures
from ocio_vp.metrics import ROUNDING

__all__ = ["ROUNDING", "SkinBand", "SkinDefault", "SkinFigures"]


@dataclass(frozen=True)
class SkinBand(Figures):
    """One lightness band (ITA°): its sample count and mean ΔE2000, this solve and least
    squares."""

    band: str
    samples: int
    expected: float
    least_squares: float


@dataclass(frozen=True)
class SkinDefault(Figures):
    """The default post-correction on the same problem, beside this solve (written with skin
    first; each key: docs/solution.md). The backgrounds' errors
    (:func:`ocio_vp.correction.skin_figures.background_error`) are None where Q has no inverse
    or in a file written before them."""

    model: str
    expected: float
    led_damage: float
    led_damage_default: float
    background_outside: int
    background_outside_default: int
    background: float | None = None
    background_default: float | None = None

    def words(self) -> str:
        """The terminal's line: this solve's background and in-frame LED figures beside the
        default's."""
        if self.background is None or self.background_default is None:
            background = "background not modelled (Q has no inverse: N not solved)"
        else:
            background = (
                f"background {_percent(self.background)} of white (default "
                f"{_percent(self.background_default)})"
            )
        return (
            f"{background}; LEDs in frame p95 ΔE2000 {self.led_damage:.3g} (default "
            f"{self.led_damage_default:.3g})"
        )


@dataclass(frozen=True)
class SkinFigures(Figures):
    """What a solve expects of skin (each key: docs/solution.md): mean ΔE2000 over the skin
    samples and the fitted chart patches, for this post-correction and the paper's least
    squares on the same patches; ``bands`` lightest first, ``default`` only with skin first."""

    priority: str
    source: str
    samples: int
    expected: float
    least_squares: float
    chart: float
    chart_least_squares: float
    bands: tuple[SkinBand, ...] = ()
    default: SkinDefault | None = None

    @property
    def ratio(self) -> float:
        """Expected skin ΔE2000 over least squares' (1 where least squares' is rounding)."""
        return _ratio(self.expected, self.least_squares)

    @property
    def chart_ratio(self) -> float:
        """The chart's mean ΔE2000 over least squares' (1 where that is rounding)."""
        return _ratio(self.chart, self.chart_least_squares)

    def words(self) -> str:
        """``skin 1.2 ΔE (0.80x LS)``: the terminal's skin figure."""
        return f"{_figure(self.expected)} ({self.ratio:.2f}x LS)"


# ΔE2000 below ROUNDING is rounding (machine-dependent digits): printed as 0, ratios as 1.


def _ratio(value: float, reference: float) -> float:
    if reference < ROUNDING:
        return 1.0 if value < ROUNDING else float("inf")
    return value / reference


def _figure(value: float) -> str:
    return f"{value:.2f}" if value >= ROUNDING else "0"


def _percent(value: float) -> str:
    return f"{100 * value:.3f} %"
