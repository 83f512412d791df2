"""One config for a whole show: every environment's wall and footage spaces on a base config.

``ocio-vp export SOLUTIONS... --target show`` (docs/exports.md, *Show config*): the base read
into data (:func:`~ocio_vp.ocio.description.split_config`), what the show adds (:func:`_overlay`)
merged onto it (:func:`show_data`, the base wins by name), and the one builder makes the config.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import PyOpenColorIO as OCIO

from ocio_vp.choices import CONTEXT_VARIABLE
from ocio_vp.deprecation import deprecated_names, warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.ocio.config import (
    DISPLAY,
    POST_CORRECTION,
    POST_CORRECTION_COLORSPACE,
    REFERENCE,
)
from ocio_vp.ocio.description import (
    FAMILY,
    ColourSpace,
    ConfigData,
    Look,
    NamedTransform,
    Transform,
    View,
    build,
    colour_space_record,
    config_record,
    group,
    merge,
    split_config,
    transform_record,
)
from ocio_vp.ocio.viewing import (
    ACES_CG_CONFIG,
    FOOTAGE_VIEW_SUFFIX,
    POST_CORRECTION_LOOK,
)
from ocio_vp.wall.encoding import LUT_DIR

__all__ = [
    "CONTEXT_VARIABLE",
    "DEFAULT_BASE_CONFIG",
    "ENVIRONMENT_FAMILIES",
    "EnvironmentData",
    "ShowEnvironment",
    "build_show_config",
    "environment_data",
    "environment_space",
    "load_base_config",
    "show_data",
]

DEFAULT_BASE_CONFIG = ACES_CG_CONFIG
#: Families (after ``ocio-vp/``) of an environment config's own colour spaces.
ENVIRONMENT_FAMILIES = ("LED Wall", "Camera")
AP0_ROLE = OCIO.ROLE_INTERCHANGE_SCENE


@dataclass(frozen=True)
class _KeptSpace:
    """The old ``KeptSpace``: a base colour space kept as OCIO has it, as the show read it."""

    name: str
    aliases: tuple[str, ...]
    is_data: bool
    record: ColourSpace | None
    problem: str = ""


#: Names served for one more release (ocio_vp.deprecation).
__getattr__ = deprecated_names(
    __name__,
    {
        "KeptSpace": (
            "ConfigData.kept (ocio_vp.ocio.description.Kept: the OCIO object itself)",
            lambda: _KeptSpace,
        )
    },
)


@dataclass(frozen=True)
class ShowEnvironment:
    """One environment's standalone config (as its folder holds it) under its name."""

    name: str
    config: OCIO.Config


def environment_space(name: str, environment: str) -> str:
    """The show config's name of an environment's own colour space ``name``."""
    return f"{name} [{environment}]"


@dataclass(frozen=True)
class EnvironmentData:
    """One environment as the show reads it: its config's data and its reference (the camera
    gamut) -> its ``aces_interchange`` space."""

    name: str
    data: ConfigData
    camera_to_aces: Transform


def load_base_config(base: str) -> OCIO.Config:
    """The base config from a path or an ``ocio://`` URI; it must name ``aces_interchange``."""
    try:
        with _quiet(OCIO.LOGGING_LEVEL_WARNING):  # OCIO's info lines on the base's own names
            config = OCIO.Config.CreateFromFile(base)
            config.validate()
    except OCIO.Exception as error:
        raise InputError(f"cannot load the base config: {error}", key="--base-config") from None
    if not config.hasRole(AP0_ROLE):
        raise InputError(
            f"the base config {base!r} has no {AP0_ROLE} role: the environments' camera gamuts "
            "cannot be placed in it",
            key="--base-config",
        )
    return config


def _own_spaces(config: ConfigData) -> list[ColourSpace]:
    families = tuple(f"{FAMILY}/{family}" for family in ENVIRONMENT_FAMILIES)
    return [
        cs
        for cs in config.colour_spaces
        if not cs.display_referred
        and (cs.family in families or cs.family.startswith(tuple(f + "/" for f in families)))
    ]


def _aces_space(base: ConfigData) -> ColourSpace:
    """The base's ``aces_interchange`` space, named by name or alias, rebuilt or kept
    (InputError where its transform has no record)."""
    name = base.roles[AP0_ROLE]
    if base.has_colour_space(name):
        return base.colour_space(name)
    for kept in base.kept:
        if kept.kind == "ColorSpace" and name in (kept.name, *kept.aliases):
            try:
                return colour_space_record(kept.element)
            except ValueError as error:
                raise InputError(
                    f"the base config's {AP0_ROLE} space {kept.name!r}: {error} (the "
                    "environments' camera gamuts cannot be placed in it)",
                    key="--base-config",
                ) from None
    raise InputError(f"the base config has no {AP0_ROLE} space {name!r}", key="--base-config")


def _base_to_reference(aces: ColourSpace) -> Transform:
    """The base's ``aces_interchange`` space -> the base's reference (empty when equal)."""
    if aces.to_reference is not None:
        return group([aces.to_reference])
    if aces.from_reference is None:
        return group([])
    return group([aces.from_reference], inverse=True)


def environment_data(env: ShowEnvironment) -> EnvironmentData:
    """``env`` read into data (InputError where its camera gamut is not stated)."""
    config = env.config
    if not config.hasRole(AP0_ROLE):
        raise InputError(
            f"environment {env.name!r}: no camera gamut (no {AP0_ROLE} role), so it cannot join "
            "a show config: add stage.camera_colorspace: NAME to the capture or measurements "
            "file, or solve again with --camera-colorspace NAME",
            key="SOLUTION",
        )
    link = config.getProcessor(REFERENCE, config.getRoleColorSpace(AP0_ROLE))
    return EnvironmentData(
        env.name, config_record(config), transform_record(link.createGroupTransform())
    )


def _renamed(transform: Transform, names: dict[str, str]) -> Transform:
    """``transform`` with its ColorSpaceTransforms naming the environment's spaces."""
    if transform.type == "GroupTransform":
        children = tuple(_renamed(t, names) for t in transform.children)
        return dataclasses.replace(transform, children=children)
    if transform.type != "ColorSpaceTransform":
        return transform
    params = tuple(
        (
            key,
            names.get(value, value) if key in ("Src", "Dst") and isinstance(value, str) else value,
        )
        for key, value in transform.params
    )
    return dataclasses.replace(transform, params=params)


def _environment_spaces(env: EnvironmentData, aces_to_base: Transform) -> list[ColourSpace]:
    """The environment's own colour spaces, converted from the base's reference."""
    own = _own_spaces(env.data)
    to_base = group([env.camera_to_aces, aces_to_base])
    names = {cs.name: environment_space(cs.name, env.name) for cs in own}
    spaces = []
    for cs in own:
        to_ref, from_ref = cs.to_reference, cs.from_reference
        if to_ref is None and from_ref is None:  # the environment's reference itself
            new_to: Transform | None = to_base
        else:
            new_to = None if to_ref is None else group([_renamed(to_ref, names), to_base])
        new_from = (
            None if from_ref is None else group([to_base.inverted(), _renamed(from_ref, names)])
        )
        spaces.append(
            dataclasses.replace(
                cs,
                name=names[cs.name],
                family=f"{FAMILY}/Environments/{env.name}",
                description=f"[{env.name}] {cs.description}",
                aliases=(),
                to_reference=new_to,
                from_reference=new_from,
            )
        )
    return spaces


def _switched_space(name: str, template: ColourSpace, aces: str, aces_to_base: Transform):
    """``name``, converting to ``<name> [$VP_ENVIRONMENT]`` through the base's ACES space."""
    switched = environment_space(name, f"${CONTEXT_VARIABLE}")
    return ColourSpace(
        name,
        template.family,
        f"{name} of the environment ${CONTEXT_VARIABLE} names (context variable; "
        f"default in this config's environment section): {name} [<environment>].",
        template.encoding,
        categories=template.categories,
        to_reference=group([_space_transform(switched, aces), aces_to_base]),
        from_reference=group([aces_to_base.inverted(), _space_transform(aces, switched)]),
    )


def _space_transform(src: str, dst: str) -> Transform:
    return Transform("ColorSpaceTransform", (("Src", src), ("Dst", dst), ("DataBypass", True)))


def _overlay(environments: Sequence[EnvironmentData], aces_space: ColourSpace) -> ConfigData:
    """Everything the show adds to the base (its ``aces_interchange`` space ``aces_space``)."""
    aces = aces_space.name
    overlay = ConfigData(environment={CONTEXT_VARIABLE: environments[0].name}, search_path=LUT_DIR)
    aces_to_base = _base_to_reference(aces_space)
    shared: dict[str, ColourSpace] | None = None
    for env in environments:
        names = {cs.name: cs for cs in _own_spaces(env.data)}
        shared = names if shared is None else {k: v for k, v in shared.items() if k in names}
        overlay.colour_spaces += _environment_spaces(env, aces_to_base)
    for name, template in (shared or {}).items():
        overlay.colour_spaces.append(_switched_space(name, template, aces, aces_to_base))
    q = _space_transform(POST_CORRECTION_COLORSPACE, REFERENCE)
    overlay.named_transforms.append(
        NamedTransform(
            POST_CORRECTION,
            f"{FAMILY}/Post",
            f"The post-correction Q of the environment ${CONTEXT_VARIABLE} names: "
            f"{POST_CORRECTION_COLORSPACE} -> {REFERENCE} of that environment.",
            q,
            categories=("file-io",),
        )
    )
    overlay.looks.append(
        Look(
            POST_CORRECTION_LOOK,
            REFERENCE,
            q,
            f"The post-correction Q of the environment ${CONTEXT_VARIABLE} names, "
            "for monitor views of footage recorded on the stage.",
        )
    )
    led = {v.name: v for v in environments[0].data.views if v.display == DISPLAY}
    active = environments[0].data.active_views  # OCIO lists a display's views in this order
    overlay.views += [led[n] for n in active if n in led] if active else list(led.values())
    return overlay


@contextlib.contextmanager
def _quiet(level: OCIO.LoggingLevel = OCIO.LOGGING_LEVEL_NONE) -> Iterator[None]:
    """OCIO logging at most at ``level`` meanwhile."""
    before = OCIO.GetLoggingLevel()
    OCIO.SetLoggingLevel(min(level, before, key=int))
    try:
        yield
    finally:
        OCIO.SetLoggingLevel(before)


def _footage_views(data: ConfigData, displays: Sequence[str]) -> list[View]:
    """On every base display, each view's footage twin: the same view after the Q look."""
    shared = {v.name: v for v in data.views if not v.display}
    is_data = {n: cs.is_data for cs in data.colour_spaces for n in (cs.name, *cs.aliases)}
    for kept in data.kept:
        if isinstance(kept.element, OCIO.ColorSpace):
            is_data.update(dict.fromkeys((kept.name, *kept.aliases), kept.element.isData()))
    added = []
    for display in displays:
        mine = [v for v in data.views if v.display == display]
        for view in [v for v in mine if not v.shared] + [shared[v.name] for v in mine if v.shared]:
            space = (
                display
                if view.colour_space == OCIO.OCIO_VIEW_USE_DISPLAY_NAME
                else view.colour_space
            )
            if not view.view_transform or is_data.get(space, True):
                continue  # Raw and plain colour space views: nothing to post-correct for
            name = view.name + FOOTAGE_VIEW_SUFFIX
            added.append(View(display, name, space, view.view_transform, POST_CORRECTION_LOOK))
    return added


def show_data(
    base: ConfigData,
    environments: Sequence[EnvironmentData],
    label: str,
    kept: Sequence[object] | None = None,
) -> ConfigData:
    """The show config of ``environments`` on ``base`` (``label``: how its description names
    the base), as data: the overlay merged onto the base, the footage views, the active and
    inactive lists. ``kept`` (deprecated, ignored): the base's kept colour spaces, which
    ``base.kept`` now holds."""
    if kept is not None:
        warn_deprecated("show_data(kept=...)", "show_data(base) (it reads base.kept)")
    overlay = _overlay(environments, _aces_space(base))
    names = ", ".join(env.name for env in environments)
    first = environments[0].name
    overlay.name = f"ocio-vp_show_{first}" if len(environments) == 1 else "ocio-vp_show"
    overlay.description = (
        f"ocio_vp show config: the environments {names} on {label}. The context variable "
        f"{CONTEXT_VARIABLE} picks the environment (default {first}); each also has its own "
        "colour spaces, '<name> [<environment>]'."
    )
    merged = merge(base, overlay)
    displays = base.active_displays or tuple(
        dict.fromkeys(v.display for v in base.views if v.display)
    )
    footage = _footage_views(base, [d for d in displays if d != DISPLAY])
    merged.views += footage
    if base.active_views:
        led = [v.name for v in overlay.views if v.name not in base.active_views]
        footage_names = dict.fromkeys(v.name for v in footage)
        merged.active_views = (*base.active_views, *footage_names, *led)
    if base.active_displays:
        merged.active_displays = (*base.active_displays, DISPLAY)
    # the base may list inactive names it does not define (OCIO logs each one on every load)
    defined = {n for cs in merged.colour_spaces for n in (cs.name, *cs.aliases)}
    defined |= base.kept_names()
    merged.inactive_colour_spaces = tuple(n for n in base.inactive_colour_spaces if n in defined)
    return merged


def _check_environments(environments: Sequence[ShowEnvironment]) -> None:
    if not environments:
        raise InputError("no environment to put in the show config", key="SOLUTION")
    seen: set[str] = set()
    for env in environments:
        if env.name in seen:
            raise InputError(
                f"two solutions of environment {env.name!r}: a show config holds each "
                "environment once (export them into separate show configs)",
                key="SOLUTION",
            )
        seen.add(env.name)


def build_show_config(
    environments: Sequence[ShowEnvironment], base: str = DEFAULT_BASE_CONFIG
) -> OCIO.Config:
    """The show config of ``environments`` on ``base`` (docs/exports.md, *Show config*).

    Raises
    ------
    InputError
        No environment, an environment twice, a base config that does not load or has no
        ``aces_interchange`` role (or one without a record), an environment whose camera gamut
        is not stated.
    """
    _check_environments(environments)
    base_config = load_base_config(base)
    with _quiet(OCIO.LOGGING_LEVEL_WARNING):
        data, rest = split_config(base_config)
    _aces_space(data)  # a base that cannot take the environments, before reading them
    merged = show_data(data, [environment_data(env) for env in environments],
                       f"{base} ({base_config.getName()})")  # fmt: skip
    with _quiet(OCIO.LOGGING_LEVEL_WARNING):
        return build(merged, start=rest)
