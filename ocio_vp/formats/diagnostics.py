"""``solution.json``'s ``diagnostics`` block as typed records (:mod:`ocio_vp.formats.records`).

Every block a consumer reads is a small frozen dataclass with the same types after a solve and
after a load; the package never looks a solve result up by string.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ocio_vp.choices import DEFAULT_WHITE_PATCH
from ocio_vp.formats.jsontypes import JsonMapping
from ocio_vp.formats.records import Figures, Record, read_record, read_value
from ocio_vp.formats.skin import SkinFigures
from ocio_vp.model.footage_range import Agreement

__all__ = [
    "MIN_NEGATIVE",
    "MIN_RETAINED",
    "Charts",
    "ClippedCharts",
    "Diagnostics",
    "DriveRange",
    "Extrapolation",
    "FixturesNotes",
    "IdentityCheck",
    "InFrustumMatch",
    "Inconsistency",
    "PanelsNotes",
    "PostCorrectionOCIO",
    "TypeMatch",
    "lowest_channel_words",
]

#: A bright saturated input whose output keeps less than this share of its dominant channel
#: has collapsed; one whose output has a channel below this times its dominant one has flipped.
MIN_RETAINED = 0.25
MIN_NEGATIVE = -0.5


@dataclass(frozen=True)
class Charts(Record):
    """Per-patch (n, 3) camera RGB for the report: the target, the lit chart through M alone
    and after Q, the chart shown in-frustum through M and through N, the offset and Q."""

    target: np.ndarray
    lit_baseline: np.ndarray
    lit_corrected: np.ndarray
    displayed_baseline: np.ndarray
    displayed_corrected: np.ndarray


@dataclass(frozen=True)
class ClippedCharts(Record):
    """The lit chart (n, 3) through M alone and after Q as the wall lights it when it clips a
    negative drive."""

    lit_baseline: np.ndarray
    lit_corrected: np.ndarray


@dataclass(frozen=True)
class IdentityCheck(Record):
    """``max_abs_error`` of eq. 7 (``Q [SL] N = I``) and its rounding ``bound``."""

    max_abs_error: float
    bound: float


@dataclass(frozen=True)
class DriveRange(Record):
    """How many chart colours the in-frustum matrix drives outside [0, ``max_drive``]
    (:func:`ocio_vp.calibration.diagnostics.in_frustum_drive_range`), and with M."""

    below_zero: int
    above_max: int
    patches_outside: list[int]
    max_drive: float
    content_scale: float
    below_zero_with_M: int | None = None
    above_max_with_M: int | None = None

    OMIT_NONE: ClassVar[tuple[str, ...]] = ("below_zero_with_M", "above_max_with_M")


@dataclass(frozen=True)
class Extrapolation(Figures):
    """What a solve measured of its post-correction beyond the chart
    (:mod:`ocio_vp.correction.extrapolation`; each key: docs/stability.md)."""

    led_damage: float
    led_damage_least_squares: float
    kept: float
    negative: float | None
    folds: float | None

    # The LEDs' ΔE2000 to 4 significant digits (a rank-1 Q's agree to 2e-8 only).
    DIGITS = 4
    FIGURES = ("led_damage", "led_damage_least_squares")

    def __post_init__(self) -> None:
        super().__post_init__()
        # The probe's -inf (a dominant output at or below zero: no share of it exists) is
        # written as null, never as a non-finite number; ``kept`` <= 0 says the same.
        if self.negative is not None and not np.isfinite(self.negative):
            object.__setattr__(self, "negative", None)

    @property
    def flips_or_collapses(self) -> bool:
        return self.kept < MIN_RETAINED or (self.negative or 0.0) < MIN_NEGATIVE

    def describe(self) -> str:
        return (
            f"in-frame LEDs p95 ΔE2000 {self.led_damage:.3g} (least squares "
            f"{self.led_damage_least_squares:.3g}); bright saturated inputs keep >= "
            f"{self.kept:.0%} of their channel, {lowest_channel_words(self.negative)}; "
            + ("rank-deficient" if self.folds is None else f"folds in {self.folds:.1%}")
            + " of the reflective solid"
        )


def lowest_channel_words(negative: float | None) -> str:
    """``'lowest channel -299% of it'`` (the saturation probe's second figure), or what an
    undefined one (None, -inf: the dominant output at or below zero) means.

    >>> lowest_channel_words(-2.99), lowest_channel_words(float("-inf"))
    ('lowest channel -299% of it', 'the channel itself at or below zero')
    """
    if negative is None or not np.isfinite(negative):
        return "the channel itself at or below zero"
    return f"lowest channel {negative:+.0%} of it"


@dataclass(frozen=True)
class FixturesNotes(Record):
    """The practical fixtures' drive solve (:func:`ocio_vp.fixtures.fixtures_diagnostics`)."""

    applied: bool
    reason: str
    error_wall_only: float
    error_with_fixtures: float
    error_reduction: float
    active_limits: list[str]
    #: The limits the solve kept, described (numbers and sentences: a record for people).
    limits: dict[str, Any]
    wall_drive: np.ndarray
    error_units: str


@dataclass(frozen=True)
class TypeMatch(Record):
    """One in-frustum panel type against the reference type, in camera on the chart."""

    delta_E_2000_mean: float
    delta_E_2000_max: float
    unreachable: list[int]
    unreachable_on_reference: list[int]


@dataclass(frozen=True)
class InFrustumMatch(Record):
    """How the in-frustum types match the ``reference`` type in camera
    (:func:`ocio_vp.calibration.panels.in_frustum_match`)."""

    reference: str
    types: dict[str, TypeMatch]


@dataclass(frozen=True)
class PanelsNotes(Record):
    """A stage of several panel types (docs/solution.md): the ``primary`` type, each type's
    ``shares``, the lit white's (3,) errors, the in-frustum types' match (None for one)."""

    primary: str
    shares: dict[str, float]
    lit_white_error: np.ndarray
    lit_white_error_primary_M: np.ndarray
    in_frustum_match: InFrustumMatch | None = None


@dataclass(frozen=True)
class PostCorrectionOCIO(Record):
    """How the config carries a non-linear post-correction (:mod:`ocio_vp.ocio.bake`): its LUT
    chains' sidecar ``files``, ``lut_size``, each chain's design, and their agreement with the
    exact model (``inverse_agreement`` None without Q^-1; both None in older files)."""

    files: list[str]
    lut_size: int | None = None
    chains: dict[str, str] | None = None
    agreement: Agreement | None = None
    inverse_agreement: Agreement | None = None


@dataclass(frozen=True)
class Inconsistency(Record):
    """A patch found inconsistent (:mod:`ocio_vp.correction.outliers`): index, name, how far
    off it is, how far it drags the fit, and its held-out residual; an entry of
    ``excluded_patches``."""

    index: int
    name: str
    relative: float  # |held-out prediction - target| / the patch's own size
    z: float  # robust standard deviations of all patches' residuals
    influence: float  # mean ΔE2000 it moves the fit's colours of the other patches
    residual: tuple[float, float, float]  # held-out prediction - target, relative to white
    swapped_with: int | None = None  # the neighbour it looks swapped with, if that is the cause
    swapped_name: str | None = None
    # the pair's held-out residuals (fitted without both), as read and exchanged, of white
    swap_residuals: tuple[float, float] | None = None
    # how many times better the other patches are predicted without it than without a typical
    # patch (:func:`deletion_gain`)
    deletion: float = 1.0
    # another patch that explains the chart at least as well, when the data cannot tell which
    # of the two is bad (both are excluded)
    ambiguous_with: int | None = None
    ambiguous_name: str | None = None
    ambiguous_deletion: float | None = None  # the other's deletion gain

    def describe(self) -> str:
        """One phrase for the terminal and solution.json."""
        if self.swapped_with is not None:
            as_read, exchanged = self.swap_residuals or (0.0, 0.0)
            return (
                f"{self.name} and {self.swapped_name} look swapped: predicted from the other "
                f"patches, the pair is off by {100 * as_read:.0f}% of white as read and by "
                f"{100 * exchanged:.0f}% with the two exchanged "
                f"({as_read / max(exchanged, 1e-12):.1f}x better); both are excluded"
            )
        off = ", ".join(f"{100 * v:+.1f}%" for v in self.residual)
        if self.ambiguous_with is not None:
            return (
                f"{self.name} or {self.ambiguous_name}: one of the two is inconsistent with the "
                f"rest and the data cannot tell which (without {self.name} the other patches "
                f"are predicted {self.deletion:.2f}x better than without a typical patch, "
                f"without {self.ambiguous_name} {self.ambiguous_deletion:.2f}x); {self.name} is "
                f"off by {100 * self.relative:.0f}% of itself and moves the fit's colours of the "
                f"other patches by {self.influence:.1f} ΔE2000; both are excluded"
            )
        return (
            f"{self.name}: predicted from the other patches it is off by {off} of white "
            f"(R, G, B), {100 * self.relative:.0f}% of the patch itself, {self.z:.1f} robust "
            f"standard deviations; it moves the fit's colours of the other patches by "
            f"{self.influence:.1f} ΔE2000 on average, and without it they are predicted "
            f"{self.deletion:.1f}x better than without a typical patch"
        )


@dataclass(frozen=True)
class Diagnostics(Record):
    """What a solve measured about itself: ``solution.json``'s ``diagnostics`` block (each key
    in docs/stability.md, *Diagnostics*).

    Every field has one type, the same after a solve and after
    :func:`~ocio_vp.formats.solution.load_solution` (arrays float64, blocks typed records): read
    it by attribute. ``present`` holds the keys a loaded file had, in its order (None after a
    solve: every field); ``extra`` those this version does not know, kept so they round-trip.
    """

    white_patch: int = DEFAULT_WHITE_PATCH
    cond_SL: float | None = None
    cond_Q: float | None = None
    rank_Q: int | None = None
    N_solved: bool | None = None
    N_reason: str | None = None
    max_condition_q_for_N: float | None = None
    lit_chart_error_baseline: np.ndarray | None = None
    lit_chart_error: np.ndarray | None = None
    residual_rms: float | None = None
    displayed_chart_error_baseline: np.ndarray | None = None
    displayed_chart_error: np.ndarray | None = None
    out_of_frustum_drive: np.ndarray | None = None
    #: Method specific, for people (no module reads it): JSON as the method wrote it.
    method_notes: dict[str, Any] | None = None
    warnings: list[str] = field(default_factory=list)
    charts: Charts | None = None
    model: str | None = None
    model_reason: str | None = None
    rank_target: int | None = None
    cross_validated_error: np.ndarray | None = None
    residuals_per_patch: np.ndarray | None = None
    out_of_frustum_negative_channels: list[int] | None = None
    lit_chart_error_clipped_drive: np.ndarray | None = None
    lit_chart_error_baseline_clipped_drive: np.ndarray | None = None
    charts_clipped_drive: ClippedCharts | None = None
    in_frustum_drive_range: DriveRange | None = None
    black_level_bounce: np.ndarray | None = None
    clipped_patches: list[int] | None = None
    N_equals_M: bool | None = None
    identity_check: IdentityCheck | None = None
    patch_screening: bool | None = None
    excluded_patches: list[Inconsistency] | None = None
    model_description: str | None = None
    extrapolation: Extrapolation | None = None
    #: How the chart was synthesized (:mod:`ocio_vp.formats.synthesis`'s record, as written).
    synthesized_target: dict[str, Any] | None = None
    fixtures: FixturesNotes | None = None
    panels: PanelsNotes | None = None
    post_correction_ocio: PostCorrectionOCIO | None = None
    skin: SkinFigures | None = None
    #: What the solve assumed for optional measurements the file did not give (no
    #: ``black_level`` for the environment, no ``stage.white_patch``), one sentence each.
    assumed: list[str] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    present: tuple[str, ...] | None = field(default=None, repr=False, compare=False)

    #: Fields written only when set.
    OMIT_NONE: ClassVar[tuple[str, ...]] = (
        "synthesized_target",
        "fixtures",
        "panels",
        "post_correction_ocio",
        "skin",
        "assumed",
    )

    @classmethod
    def from_dict(cls, data: JsonMapping) -> Diagnostics:
        """The block as read from ``solution.json``: every value typed; missing keys keep
        their defaults (and stay missing when written), unknown ones are kept in ``extra``.
        The ``root_polynomial_ocio`` block of the versions before ``post_correction_ocio``
        gives its ``files`` (the rest of it is kept as it was)."""
        diagnostics = read_record(cls, data, "diagnostics")
        legacy = data.get("root_polynomial_ocio")
        if diagnostics.post_correction_ocio is None and isinstance(legacy, Mapping):
            files = read_value(legacy.get("files", []), list[str], "root_polynomial_ocio.files")
            block = PostCorrectionOCIO(files=files)
            object.__setattr__(block, "_present", ())
            object.__setattr__(diagnostics, "post_correction_ocio", block)
        return diagnostics

    def recorded(self, name: str) -> bool:
        """Whether the solve (or the file it was read from) recorded field ``name``: an older
        file may lack one, which then holds its default."""
        return self.present is None or name in self.present

    def adding(self, **changes: Any) -> Diagnostics:
        """This record with ``changes``; a loaded one also writes the keys it gains."""
        present = self.present
        if present is not None:
            present = (*present, *(k for k in changes if k not in present))
        return dataclasses.replace(self, **changes, present=present)
