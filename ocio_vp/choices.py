"""The choices the command line and the library share, in one numpy-free module.

The ``ocio-vp`` parser imports this module to list choices and defaults without loading numpy
or the solvers (``ocio-vp --help`` stays fast); the library checks its own tables against these
names (``tests/test_choices.py``), so a method, encoding or target added in one place and not
the other fails the suite.
"""

from __future__ import annotations

from typing import Literal

__all__ = [
    "BLACK_LEVEL_METHODS",
    "CONTEXT_VARIABLE",
    "DEFAULT_BASE_CONFIG",
    "DEFAULT_BLACK_LEVEL",
    "DEFAULT_CUBE_RANGE",
    "DEFAULT_CUBE_SIZE",
    "DEFAULT_FOOTAGE_ENCODING",
    "DEFAULT_METHOD",
    "DEFAULT_PEAK_NITS",
    "DEFAULT_PRIORITY",
    "DEFAULT_VALIDATION_THRESHOLD",
    "DEFAULT_WALL_ENCODING",
    "DEFAULT_WHITE_PATCH",
    "ENCODINGS",
    "ENVIRONMENT_TARGETS",
    "EXPORT_TARGETS",
    "LINEAR_METHODS",
    "OPTIMIZATIONS",
    "PRIORITIES",
    "Q_METHODS",
    "SAMPLE_WALL_GAIN",
    "SHOW_TARGETS",
    "WALL_ENCODINGS",
    "BlackLevelMethod",
    "canonical_encoding",
]

#: The white patch of a ColorChecker 24, 0-based in reading order (people see it as patch 19,
#: "white 9.5 (.05 D)"): the default of ``stage.white_patch`` and of an older solution.json
#: that does not say.
DEFAULT_WHITE_PATCH = 18

#: Post-correction (Q) methods, in the order ``--help`` lists them (the registry's records:
#: :data:`ocio_vp.correction.registry.Q_SOLVE_METHODS`).
Q_METHODS = (
    "least-squares",
    "white-preserving",
    "regularised",
    "diagonal",
    "identity",
    "auto",
    "perceptual",
    "joint",
    "root-polynomial",
    "root-polynomial-3",
)
#: Methods whose post-correction is always a 3x3 matrix (the others may be non-linear).
LINEAR_METHODS = frozenset(Q_METHODS) - {"auto", "root-polynomial", "root-polynomial-3"}
#: The simplest model the scene needs (``auto``); ``least-squares`` is the paper's eq. 5.
DEFAULT_METHOD = "auto"

#: What the default post-correction puts first (``solve --priority``, ``priority:`` per
#: environment): ``general`` colours (never losing to least squares on skin), or ``skin``
#: (faces first, general reflectances at a bounded cost: docs/skin.md).
PRIORITIES = ("general", "skin")
DEFAULT_PRIORITY = "general"

#: In-frustum black-level offset: ``exact`` (``-M b``) or the paper's ``b / w_camera``.
BlackLevelMethod = Literal["exact", "paper"]
BLACK_LEVEL_METHODS: tuple[BlackLevelMethod, ...] = ("exact", "paper")
DEFAULT_BLACK_LEVEL: BlackLevelMethod = "exact"

#: The wall's signal encodings (docs/linearity.md).
WALL_ENCODINGS = ("linear", "gamma2.4", "srgb", "pq")
DEFAULT_WALL_ENCODING = "linear"
#: Luminance (cd/m2) of drive 1.0 on a PQ wall when none is given.
DEFAULT_PEAK_NITS = 1000.0
#: The simulated sample stage's wall: its full-drive white is this many times the location's
#: white (``simulate --wall-gain``): content white two stops below the peak, as a stage
#: engineer sets a stage up.
SAMPLE_WALL_GAIN = 4.0

#: Export targets written per environment (``OUT/<environment>/<target>/``).
ENVIRONMENT_TARGETS = ("unreal", "nuke", "resolve", "lights", "dit")
#: Targets written once for all the given environments (``OUT/<target>/``).
SHOW_TARGETS = ("show",)
#: ``ocio-vp export --target`` values: per environment, then ``all`` of those, then ``show`` (one
#: config for every given environment, on a base config).
EXPORT_TARGETS = (*ENVIRONMENT_TARGETS, "all", *SHOW_TARGETS)
#: Cube lattice size and input range (camera RGB) of every exported .cube.
DEFAULT_CUBE_SIZE = 33
DEFAULT_CUBE_RANGE = (-0.25, 16.0)
#: The OCIO context variable that picks the environment in the show config, Nuke's OCIO nodes
#: and Unreal's OCIO assets.
CONTEXT_VARIABLE = "VP_ENVIRONMENT"
#: The show config's default base: OCIO's built-in ACES CG config (every OCIO from 2.2 on).
DEFAULT_BASE_CONFIG = "ocio://cg-config-v1.0.0_aces-v1.3_ocio-v2.1"

#: ``ocio-vp apply --footage-encoding``: linear, or any colour-science decoding name
#: (``colour.CCTF_DECODINGS``, as the capture file's ``encoding:``), checked when it runs.
DEFAULT_FOOTAGE_ENCODING = "linear"

#: OCIO optimisation levels ``apply`` accepts.
OPTIMIZATIONS = ("lossless", "default", "good", "draft")

#: ``ocio-vp validate``: pass when the 95th percentile of ΔE2000 over the shown patches is at
#: most this (docs/validation.md says why 3).
DEFAULT_VALIDATION_THRESHOLD = 3.0


#: Encodings a plate may declare: ``linear`` or any decoding in colour-science's
#: ``colour.CCTF_DECODINGS`` (``sRGB``, ``Gamma 2.4``, ``ARRI LogC4``, ``S-Log3``, ``Cineon`` ...).
ENCODINGS = "linear or a name in colour.CCTF_DECODINGS"


def canonical_encoding(name: object, *, source: object = None, key: str | None = None) -> str:
    """Return the canonical spelling of a plate or footage encoding name (case-insensitive), or
    raise :class:`~ocio_vp.errors.InputError` with close matches."""
    import difflib

    from ocio_vp.errors import InputError

    if isinstance(name, str) and name.lower() == "linear":
        return "linear"  # the default: no need to import colour-science to know it

    import colour

    names = ("linear", *sorted(colour.CCTF_DECODINGS.keys()))
    by_lower = {n.lower(): n for n in names}
    if isinstance(name, str) and name.lower() in by_lower:
        return by_lower[name.lower()]
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.5)
    hint = f"; close matches: {', '.join(close)}" if close else ""
    raise InputError(f"unknown encoding {name!r} (use {ENCODINGS}){hint}", source=source, key=key)
