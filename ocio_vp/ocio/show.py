"""One config for a whole show: every environment's wall and footage spaces on a base config.

``ocio-vp export SOLUTIONS... --target show`` keeps the base config (default: OCIO's built-in
ACES CG config) and adds, as data (:func:`_overlay`):

- per environment, the colour spaces of its own config in :data:`ENVIRONMENT_FAMILIES` as
  ``<name> [<environment>]``, their transforms as they are after the base's reference ->
  that environment's camera gamut;
- under the per-environment names (``LED Wall - Inner Frustum``, ...), colour spaces that pick
  the environment from the context variable :data:`CONTEXT_VARIABLE` (default the first);
- the named transform ``Post-Correction Q``, its look, a footage-after-Q view on every base
  display, and the ``LED Wall`` display.

The base and the overlay are merged by OCIO's own merging (2.5+; the base wins) where the
installed OCIO has it, else by :func:`merge_by_api`, which gives the same config.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import PyOpenColorIO as OCIO

from ocio_vp.choices import CONTEXT_VARIABLE
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
    name_list,
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
    "ShowEnvironment",
    "build_show_config",
    "environment_space",
    "has_config_merger",
    "load_base_config",
    "merge_by_api",
]

DEFAULT_BASE_CONFIG = ACES_CG_CONFIG
#: Families (after ``ocio-vp/``) of an environment config's own colour spaces.
ENVIRONMENT_FAMILIES = ("LED Wall", "Camera")
AP0_ROLE = "aces_interchange"


@dataclass(frozen=True)
class ShowEnvironment:
    """One environment's standalone config (as its folder holds it) under its name."""

    name: str
    config: OCIO.Config


def environment_space(name: str, environment: str) -> str:
    """The show config's name of an environment's own colour space ``name``."""
    return f"{name} [{environment}]"


def has_config_merger() -> bool:
    """Whether the installed OCIO merges configs itself (2.5+)."""
    return hasattr(OCIO, "ConfigMergingHelpers")


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


def _base_to_reference(base: OCIO.Config) -> Transform:
    """The base's ``aces_interchange`` space -> the base's reference (empty when equal)."""
    aces = _record(base.getColorSpace(base.getRoleColorSpace(AP0_ROLE)))
    if aces.to_reference is not None:
        return group([aces.to_reference])
    if aces.from_reference is None:
        return group([])
    return group([aces.from_reference], inverse=True)


def _record(cs: OCIO.ColorSpace) -> ColourSpace:
    """The base's colour space as data (InputError where a transform has no record)."""
    try:
        return colour_space_record(cs)
    except ValueError as error:
        raise InputError(
            f"the base config's {cs.getName()!r}: {error} (a show config copies it)",
            key="--base-config",
        ) from None


def _camera_to_reference(env: ShowEnvironment, aces_to_base: Transform) -> Transform:
    """The environment's reference (its camera gamut) -> the base's reference."""
    config = env.config
    if not config.hasRole(AP0_ROLE):
        raise InputError(
            f"environment {env.name!r}: no camera gamut (no {AP0_ROLE} role), so it cannot join "
            "a show config: add stage.camera_colorspace: NAME to the capture or measurements "
            "file, or solve again with --camera-colorspace NAME",
            key="SOLUTION",
        )
    link = config.getProcessor(REFERENCE, config.getRoleColorSpace(AP0_ROLE))
    return group([transform_record(link.createGroupTransform()), aces_to_base])


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


def _environment_spaces(
    env: ShowEnvironment, own: list[ColourSpace], aces_to_base: Transform
) -> list[ColourSpace]:
    """The environment's own colour spaces ``own``, converted from the base's reference."""
    to_base = _camera_to_reference(env, aces_to_base)
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


def _overlay(base: OCIO.Config, environments: Sequence[ShowEnvironment]) -> ConfigData:
    """Everything the show adds to the base, as data (merged into it afterwards)."""
    aces = base.getRoleColorSpace(AP0_ROLE)
    overlay = ConfigData(
        colour_spaces=[_record(base.getColorSpace(aces))],
        roles={AP0_ROLE: aces},
        default_rule=aces,
        environment={CONTEXT_VARIABLE: environments[0].name},
        search_path=LUT_DIR,
    )
    aces_to_base = _base_to_reference(base)
    shared: dict[str, ColourSpace] | None = None
    for env in environments:
        own = _own_spaces(config_record(env.config))
        names = {cs.name: cs for cs in own}
        shared = names if shared is None else {k: v for k, v in shared.items() if k in names}
        overlay.colour_spaces += _environment_spaces(env, own, aces_to_base)
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
    first = environments[0].config
    for view in first.getViews(DISPLAY):
        overlay.views.append(View(DISPLAY, view, first.getDisplayViewColorSpaceName(DISPLAY, view)))
    return overlay


@contextlib.contextmanager
def _quiet(level: OCIO.LoggingLevel = OCIO.LOGGING_LEVEL_NONE) -> Iterator[None]:
    """OCIO logging at most at ``level`` meanwhile (the merger logs every base-over-input
    choice as a warning: expected here)."""
    before = OCIO.GetLoggingLevel()
    OCIO.SetLoggingLevel(min(level, before, key=int))
    try:
        yield
    finally:
        OCIO.SetLoggingLevel(before)


def merge_by_ocio(base: OCIO.Config, overlay: OCIO.Config) -> OCIO.Config:
    """OCIO's own merging (2.5+): the base wins wherever both define something."""
    params = OCIO.ConfigMergingParameters.Create()
    params.setDefaultStrategy(OCIO.ConfigMergingParameters.STRATEGY_PREFER_BASE)
    for setter in (
        "setRoles",
        "setFileRules",
        "setDisplayViews",
        "setViewTransforms",
        "setLooks",
        "setColorspaces",
        "setNamedTransforms",
    ):
        getattr(params, setter)(OCIO.ConfigMergingParameters.STRATEGY_PREFER_BASE)
    params.setAdjustInputReferenceSpace(False)  # the overlay is already on the base's reference
    params.setInputFirst(False)
    with _quiet():
        return OCIO.ConfigMergingHelpers.MergeConfigs(params, base, overlay)


def merge_by_api(base: OCIO.Config, overlay: OCIO.Config) -> OCIO.Config:
    """What :func:`merge_by_ocio` does for this overlay, by the API (any OCIO 2.2+)."""
    merged = OCIO.Config.CreateFromStream(base.serialize())
    all_spaces = (OCIO.SEARCH_REFERENCE_SPACE_ALL, OCIO.COLORSPACE_ALL)
    for cs in overlay.getColorSpaces(*all_spaces):
        if merged.getColorSpace(cs.getName()) is None:
            merged.addColorSpace(copy.deepcopy(cs))
    for role, space in overlay.getRoles():
        if not merged.hasRole(role):
            merged.setRole(role, space)
    for name in overlay.getNamedTransformNames(OCIO.NAMEDTRANSFORM_ALL):
        if merged.getNamedTransform(name) is None:
            merged.addNamedTransform(copy.deepcopy(overlay.getNamedTransform(name)))
    for name in overlay.getLookNames():
        if merged.getLook(name) is None:
            merged.addLook(copy.deepcopy(overlay.getLook(name)))
    for name in overlay.getEnvironmentVarNames():
        if name not in list(merged.getEnvironmentVarNames()):
            merged.addEnvironmentVar(name, overlay.getEnvironmentVarDefault(name))
    paths = list(merged.getSearchPaths())
    for path in overlay.getSearchPaths():
        if path not in paths:
            merged.addSearchPath(path)
    for display in overlay.getDisplaysAll():
        for view in overlay.getViews(OCIO.VIEW_DISPLAY_DEFINED, display):
            if view not in merged.getViews(OCIO.VIEW_DISPLAY_DEFINED, display):
                merged.addDisplayView(
                    display, view, overlay.getDisplayViewColorSpaceName(display, view)
                )
    return merged


def _view_target(config: OCIO.Config, display: str, view: str) -> tuple[str, str]:
    space = config.getDisplayViewColorSpaceName(display, view)
    if space == OCIO.OCIO_VIEW_USE_DISPLAY_NAME:
        space = display
    return config.getDisplayViewTransformName(display, view), space


def _footage_views(config: OCIO.Config, displays: Sequence[str]) -> list[str]:
    """On every base display, each view's footage twin: the same view after the Q look."""
    added = []
    for display in displays:
        views = [
            *config.getViews(OCIO.VIEW_DISPLAY_DEFINED, display),
            *config.getViews(OCIO.VIEW_SHARED, display),
        ]
        for view in views:
            view_transform, space = _view_target(config, display, view)
            cs = config.getColorSpace(space)
            if not view_transform or cs is None or cs.isData():
                continue  # Raw and plain colour space views: nothing to post-correct for
            name = view + FOOTAGE_VIEW_SUFFIX
            config.addDisplayView(
                display, name, view_transform, space, POST_CORRECTION_LOOK, "", ""
            )
            added.append(name)
    return added


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
    environments: Sequence[ShowEnvironment],
    base: str = DEFAULT_BASE_CONFIG,
    *,
    use_merger: bool | None = None,
) -> OCIO.Config:
    """The show config of ``environments`` on ``base`` (see the module docstring).

    ``use_merger``: OCIO's merging (True), :func:`merge_by_api` (False), or OCIO's if it has
    one (None).

    Raises
    ------
    InputError
        No environment, an environment twice, a base config that does not load or has no
        ``aces_interchange`` role, an environment whose camera gamut is not stated.
    """
    _check_environments(environments)
    base_config = load_base_config(base)
    # the overlay names the base's spaces (Raw, displays) it does not hold: validated merged
    overlay = build(_overlay(base_config, environments), validate=False)
    merge = has_config_merger() if use_merger is None else use_merger
    merged = merge_by_ocio(base_config, overlay) if merge else merge_by_api(base_config, overlay)
    names = ", ".join(env.name for env in environments)
    merged.setName(
        f"ocio-vp_show_{environments[0].name}" if len(environments) == 1 else "ocio-vp_show"
    )
    merged.setDescription(
        f"ocio_vp show config: the environments {names} on {base} ({base_config.getName()}). "
        f"The context variable {CONTEXT_VARIABLE} picks the environment (default "
        f"{environments[0].name}); each also has its own colour spaces, '<name> [<environment>]'."
    )
    displays = name_list(base_config.getActiveDisplays()) or list(base_config.getDisplaysAll())
    footage = _footage_views(merged, [d for d in displays if d != DISPLAY])
    active_views = name_list(base_config.getActiveViews())
    if active_views:
        led = [v for v in overlay.getViews(DISPLAY) if v not in active_views]
        merged.setActiveViews(", ".join([*active_views, *dict.fromkeys(footage), *led]))
    if name_list(base_config.getActiveDisplays()):
        merged.setActiveDisplays(", ".join([*displays, DISPLAY]))
    # the base may list inactive names it does not define (OCIO logs each one on every load)
    inactive = name_list(merged.getInactiveColorSpaces())
    merged.setInactiveColorSpaces(", ".join(n for n in inactive if merged.getColorSpace(n)))
    merged.validate()
    return merged
