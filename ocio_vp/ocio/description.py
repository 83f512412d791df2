"""A config as plain data, and the one function that turns it into an OpenColorIO config.

As OpenColorIO-Config-ACES's ``ConfigData`` and ``generate_config``: what goes into a config is
held in small records that import nothing from OpenColorIO (two descriptions compare with
``==``); :func:`build` is the only place that makes a config from them. A :class:`Transform` is
an OCIO class name, its parameters by setter name, a group's children and its direction;
:func:`transform_record` reads one back from an OCIO transform.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import PyOpenColorIO as OCIO

__all__ = [
    "FAMILY",
    "ColourSpace",
    "ConfigData",
    "Enum",
    "Kept",
    "Look",
    "NamedTransform",
    "Transform",
    "View",
    "ViewTransform",
    "build",
    "clamp",
    "colour_space",
    "colour_space_record",
    "file",
    "group",
    "matrix",
    "merge",
    "split_config",
    "transform_record",
]


@dataclass(frozen=True)
class Enum:
    """An OCIO enum value by its module-level name (``RANGE_CLAMP``, ``INTERP_LINEAR``)."""

    name: str


Value = str | float | bool | tuple[float, ...] | Enum


@dataclass(frozen=True)
class Transform:
    """One OCIO transform as data: class name, parameters (setter name without ``set``, in the
    order they are set), a group's children, whether it runs inverted, and its metadata's
    attributes (``name``, ``id``)."""

    type: str
    params: tuple[tuple[str, Value], ...] = ()
    children: tuple[Transform, ...] = ()
    inverse: bool = False
    metadata: tuple[tuple[str, str], ...] = ()

    def inverted(self) -> Transform:
        """The same transform in the other direction."""
        return dataclasses.replace(self, inverse=not self.inverse)


#: Parameters each transform type carries, by OCIO getter/setter name (read where ``_IS_SET``).
PARAMS: dict[str, tuple[str, ...]] = {
    "MatrixTransform": ("Matrix", "Offset"),
    "FileTransform": ("Src", "CCCId", "Interpolation"),
    "RangeTransform": ("Style", "MinInValue", "MaxInValue", "MinOutValue", "MaxOutValue"),
    "LogCameraTransform": (
        "Base",
        "LinSideBreakValue",
        "LogSideSlopeValue",
        "LogSideOffsetValue",
        "LinSideSlopeValue",
        "LinSideOffsetValue",
        "LinearSlopeValue",
    ),
    "LogAffineTransform": (
        "Base",
        "LogSideSlopeValue",
        "LogSideOffsetValue",
        "LinSideSlopeValue",
        "LinSideOffsetValue",
    ),
    "LogTransform": ("Base",),
    "ExponentTransform": ("Value", "NegativeStyle"),
    "ExponentWithLinearTransform": ("Gamma", "Offset", "NegativeStyle"),
    "BuiltinTransform": ("Style",),
    "ColorSpaceTransform": ("Src", "Dst", "DataBypass"),
    "GroupTransform": (),
}
_IS_SET = {
    "MinInValue": "hasMinInValue",
    "MaxInValue": "hasMaxInValue",
    "MinOutValue": "hasMinOutValue",
    "MaxOutValue": "hasMaxOutValue",
    "LinearSlopeValue": "isLinearSlopeValueSet",
}


def matrix(m44: Iterable[float], offset: Iterable[float] = (0.0,) * 4, *, inverse: bool = False):
    """A MatrixTransform record from a row-major 4x4 and a 4-offset."""
    values = (("Matrix", tuple(float(v) for v in m44)), ("Offset", tuple(float(v) for v in offset)))
    return Transform("MatrixTransform", values, inverse=inverse)


def file(src: str) -> Transform:
    """A FileTransform record (OCIO's default interpolation)."""
    return Transform("FileTransform", (("Src", src),))


def clamp(
    *,
    min_in: float | None = None,
    max_in: float | None = None,
    min_out: float | None = None,
    max_out: float | None = None,
) -> Transform:
    """A clamping RangeTransform record (a bound left None is open)."""
    bounds = [("MinInValue", min_in), ("MaxInValue", max_in)]
    bounds += [("MinOutValue", min_out), ("MaxOutValue", max_out)]
    values = tuple((name, float(v)) for name, v in bounds if v is not None)
    return Transform("RangeTransform", (("Style", Enum("RANGE_CLAMP")), *values))


def group(transforms: Iterable[Transform], *, inverse: bool = False) -> Transform:
    """A GroupTransform record."""
    return Transform("GroupTransform", children=tuple(transforms), inverse=inverse)


def one(transforms: list[Transform]) -> Transform:
    """The transform itself when there is one, else their group."""
    return transforms[0] if len(transforms) == 1 else group(transforms)


@dataclass(frozen=True)
class ColourSpace:
    """A colour space: ``to_reference`` / ``from_reference`` None where not given."""

    name: str
    family: str
    description: str
    encoding: str = ""
    categories: tuple[str, ...] = ()
    is_data: bool = False
    to_reference: Transform | None = None
    from_reference: Transform | None = None
    display_referred: bool = False
    aliases: tuple[str, ...] = ()
    bit_depth: Enum = Enum("BIT_DEPTH_UNKNOWN")


#: The family every colour space this tool makes sits under (``ocio-vp/<family>``).
FAMILY = "ocio-vp"


def colour_space(
    name: str,
    description: str,
    *,
    family: str,
    encoding: str = "scene-linear",
    to_reference: Transform | None = None,
    from_reference: Transform | None = None,
    is_data: bool = False,
) -> ColourSpace:
    """A colour space of this tool's family ``ocio-vp/<family>``."""
    return ColourSpace(
        name,
        f"{FAMILY}/{family}",
        description,
        encoding,
        is_data=is_data,
        to_reference=to_reference,
        from_reference=from_reference,
    )


@dataclass(frozen=True)
class NamedTransform:
    name: str
    family: str
    description: str
    forward: Transform | None
    inverse: Transform | None = None
    categories: tuple[str, ...] = ()
    aliases: tuple[str, ...] = ()
    encoding: str = ""


@dataclass(frozen=True)
class Look:
    name: str
    process_space: str
    transform: Transform
    description: str
    inverse: Transform | None = None


@dataclass(frozen=True)
class ViewTransform:
    name: str
    description: str
    from_reference: Transform


@dataclass(frozen=True)
class View:
    """A view of a display: a colour space, or a view transform to a display colour space.

    ``display`` "": a shared view's definition; ``shared``: the display lists the shared view
    ``name`` (nothing else is read)."""

    display: str
    name: str
    colour_space: str
    view_transform: str = ""
    looks: str = ""
    rule: str = ""
    description: str = ""
    shared: bool = False


@dataclass(frozen=True)
class Kept:
    """An element of a read config that no record rebuilds exactly (:func:`split_config`),
    as OCIO has it: an ``OCIO.ColorSpace``, ``NamedTransform``, ``Look`` or ``ViewTransform``,
    and its place among the elements of its kind (:func:`build` puts it back there)."""

    name: str
    aliases: tuple[str, ...]
    element: object
    index: int

    @property
    def kind(self) -> str:
        """The OCIO class name of the element (``ColorSpace``, ...)."""
        return type(self.element).__name__


@dataclass
class ConfigData:
    """Everything a config holds, in the order it is added (the serialized order)."""

    name: str = ""
    description: str = ""
    version: tuple[int, int] = (2, 1)
    search_path: str = ""
    roles: dict[str, str] = field(default_factory=dict)
    colour_spaces: list[ColourSpace] = field(default_factory=list)
    named_transforms: list[NamedTransform] = field(default_factory=list)
    looks: list[Look] = field(default_factory=list)
    view_transforms: list[ViewTransform] = field(default_factory=list)
    views: list[View] = field(default_factory=list)
    active_displays: tuple[str, ...] = ()
    active_views: tuple[str, ...] = ()
    #: Context variables and their defaults (the config's ``environment`` section).
    environment: dict[str, str] = field(default_factory=dict)
    #: The colour space of the file rules' default rule ("": OCIO's, the ``default`` role).
    default_rule: str = ""
    default_view_transform: str = ""
    inactive_colour_spaces: tuple[str, ...] = ()
    #: Elements a config read by :func:`split_config` keeps as OCIO objects.
    kept: tuple[Kept, ...] = ()

    @property
    def opaque(self) -> tuple[str, ...]:
        """The names of the :attr:`kept` elements."""
        return tuple(k.name for k in self.kept)

    def kept_names(self) -> set[str]:
        """The names and aliases of the :attr:`kept` elements."""
        return {n for k in self.kept for n in (k.name, *k.aliases)}

    def colour_space(self, name: str) -> ColourSpace:
        """The colour space called ``name`` or with that alias (KeyError when there is none)."""
        for cs in self.colour_spaces:
            if name == cs.name or name in cs.aliases:
                return cs
        raise KeyError(name)

    def has_colour_space(self, name: str) -> bool:
        return any(name == cs.name or name in cs.aliases for cs in self.colour_spaces)

    def view_names(self, display: str) -> list[str]:
        return [v.name for v in self.views if v.display == display]


def _enum(value: object) -> Value:
    name = getattr(value, "name", None)
    if name is not None and not isinstance(value, (str, float, int)):
        return Enum(str(name))
    if isinstance(value, (list, tuple)):
        return tuple(float(v) for v in value)
    return value  # type: ignore[return-value]


def transform_record(transform: OCIO.Transform) -> Transform:
    """The record of an OCIO transform of a type in :data:`PARAMS` (ValueError otherwise)."""
    import PyOpenColorIO as OCIO

    kind = type(transform).__name__
    if kind not in PARAMS:
        raise ValueError(f"no record for OCIO's {kind}")
    params = []
    for name in PARAMS[kind]:
        is_set = _IS_SET.get(name)
        if is_set is not None and not getattr(transform, is_set)():
            continue
        value = getattr(transform, f"get{name}")()
        if name == "CCCId" and not value:
            continue
        params.append((name, _enum(value)))
    children = tuple(transform_record(t) for t in transform) if kind == "GroupTransform" else ()
    inverse = transform.getDirection() == OCIO.TRANSFORM_DIR_INVERSE
    get = getattr(transform, "getFormatMetadata", None)  # BuiltinTransform has none
    metadata = () if get is None else tuple(get().getAttributes())
    return Transform(kind, tuple(params), children, inverse, metadata)


def _optional_record(transform: OCIO.Transform | None) -> Transform | None:
    return None if transform is None else transform_record(transform)


def colour_space_record(cs: OCIO.ColorSpace) -> ColourSpace:
    """The record of an OCIO colour space."""
    import PyOpenColorIO as OCIO

    def get(direction):
        return _optional_record(cs.getTransform(direction))

    return ColourSpace(
        name=cs.getName(),
        family=cs.getFamily(),
        description=cs.getDescription(),
        encoding=cs.getEncoding(),
        categories=tuple(cs.getCategories()),
        is_data=cs.isData(),
        to_reference=get(OCIO.COLORSPACE_DIR_TO_REFERENCE),
        from_reference=get(OCIO.COLORSPACE_DIR_FROM_REFERENCE),
        display_referred=cs.getReferenceSpaceType() == OCIO.REFERENCE_SPACE_DISPLAY,
        aliases=tuple(cs.getAliases()),
        bit_depth=Enum(cs.getBitDepth().name),
    )


def ocio_transform(record: Transform) -> OCIO.Transform:
    """The OCIO transform of a record (every call a new object)."""
    import PyOpenColorIO as OCIO

    if record.type == "GroupTransform":
        transform = OCIO.GroupTransform([ocio_transform(t) for t in record.children])
    elif record.type == "LogCameraTransform":  # the one whose constructor needs a value
        transform = OCIO.LogCameraTransform(linSideBreak=dict(record.params)["LinSideBreakValue"])
    else:
        transform = getattr(OCIO, record.type)()
    for name, value in record.params:
        setter = getattr(transform, f"set{name}")
        setter(getattr(OCIO, value.name) if isinstance(value, Enum) else value)
    if record.inverse:
        transform.setDirection(OCIO.TRANSFORM_DIR_INVERSE)
    for key, text in record.metadata:
        transform.getFormatMetadata()[key] = text
    return transform


def _ocio_optional(record: Transform | None) -> OCIO.Transform | None:
    return None if record is None else ocio_transform(record)


def _ocio_colour_space(record: ColourSpace) -> OCIO.ColorSpace:
    import PyOpenColorIO as OCIO

    return OCIO.ColorSpace(
        referenceSpace=OCIO.REFERENCE_SPACE_DISPLAY
        if record.display_referred
        else OCIO.REFERENCE_SPACE_SCENE,
        name=record.name,
        family=record.family,
        encoding=record.encoding,
        description=record.description,
        isData=record.is_data,
        aliases=list(record.aliases),
        bitDepth=getattr(OCIO, record.bit_depth.name),
        toReference=_ocio_optional(record.to_reference),
        fromReference=_ocio_optional(record.from_reference),
        categories=list(record.categories),
    )


def _ocio_named_transform(record: NamedTransform) -> OCIO.NamedTransform:
    import PyOpenColorIO as OCIO

    named = OCIO.NamedTransform(
        name=record.name,
        aliases=list(record.aliases),
        family=record.family,
        description=record.description,
        forwardTransform=_ocio_optional(record.forward),
        inverseTransform=_ocio_optional(record.inverse),
        categories=list(record.categories),
    )
    named.setEncoding(record.encoding)
    return named


def _ocio_look(record: Look) -> OCIO.Look:
    import PyOpenColorIO as OCIO

    return OCIO.Look(
        name=record.name,
        processSpace=record.process_space,
        transform=ocio_transform(record.transform),
        inverseTransform=_ocio_optional(record.inverse),
        description=record.description,
    )


def _ocio_view_transform(record: ViewTransform) -> OCIO.ViewTransform:
    import PyOpenColorIO as OCIO

    return OCIO.ViewTransform(
        referenceSpace=OCIO.REFERENCE_SPACE_SCENE,
        name=record.name,
        description=record.description,
        fromReference=ocio_transform(record.from_reference),
    )


def _add_view(config: OCIO.Config, view: View) -> None:
    if view.shared:
        config.addDisplaySharedView(view.display, view.name)
    elif not view.display:
        config.addSharedView(
            view.name, view.view_transform, view.colour_space, view.looks, view.rule,
            view.description,
        )  # fmt: skip
    else:
        config.addDisplayView(
            view.display, view.name, view.view_transform, view.colour_space, view.looks,
            view.rule, view.description,
        )  # fmt: skip


def build(data: ConfigData, *, start: OCIO.Config | None = None) -> OCIO.Config:
    """The OCIO config of ``data``, validated (``PyOpenColorIO.Exception``: a bug).

    ``start``: the config to add to (taken, not copied; :func:`split_config`'s second half,
    which holds no element of the four kinds ``data`` lists), else an empty one."""
    import PyOpenColorIO as OCIO

    config = OCIO.Config() if start is None else start
    config.setMajorVersion(data.version[0])
    config.setMinorVersion(data.version[1])
    config.setName(data.name)
    config.setDescription(data.description)
    if data.search_path:
        config.setSearchPath(data.search_path)
    made = (
        ("ColorSpace", [_ocio_colour_space(r) for r in data.colour_spaces]),
        ("NamedTransform", [_ocio_named_transform(r) for r in data.named_transforms]),
        ("Look", [_ocio_look(r) for r in data.looks]),
        ("ViewTransform", [_ocio_view_transform(r) for r in data.view_transforms]),
    )
    for kind, elements in made:
        for kept in sorted(data.kept, key=lambda k: k.index):
            if kept.kind == kind:
                elements.insert(kept.index, kept.element)
        for element in elements:
            getattr(config, f"add{kind}")(element)
    if data.default_view_transform:
        config.setDefaultViewTransformName(data.default_view_transform)
    for view in data.views:
        _add_view(config, view)
    for role, space in data.roles.items():
        config.setRole(role, space)
    if data.default_rule:
        rules = config.getFileRules()
        rules.setDefaultRuleColorSpace(data.default_rule)
        config.setFileRules(rules)
    for name, default in data.environment.items():
        config.addEnvironmentVar(name, default)
    if data.active_displays:
        config.setActiveDisplays(", ".join(data.active_displays))
    if data.active_views:
        config.setActiveViews(", ".join(data.active_views))
    if data.inactive_colour_spaces:
        config.setInactiveColorSpaces(", ".join(data.inactive_colour_spaces))
    config.validate()
    return config


def _named_record(nt: OCIO.NamedTransform) -> NamedTransform:
    import PyOpenColorIO as OCIO

    return NamedTransform(
        nt.getName(),
        nt.getFamily(),
        nt.getDescription(),
        _optional_record(nt.getTransform(OCIO.TRANSFORM_DIR_FORWARD)),
        _optional_record(nt.getTransform(OCIO.TRANSFORM_DIR_INVERSE)),
        tuple(nt.getCategories()),
        tuple(nt.getAliases()),
        nt.getEncoding(),
    )


def _look_record(look: OCIO.Look) -> Look:
    return Look(
        look.getName(),
        look.getProcessSpace(),
        transform_record(look.getTransform()),
        look.getDescription(),
        _optional_record(look.getInverseTransform()),
    )


def _view_transform_record(vt: OCIO.ViewTransform) -> ViewTransform:
    import PyOpenColorIO as OCIO

    transform = vt.getTransform(OCIO.VIEWTRANSFORM_DIR_FROM_REFERENCE)
    if transform is None:
        raise ValueError(f"view transform {vt.getName()!r} has no from_reference")
    return ViewTransform(vt.getName(), vt.getDescription(), transform_record(transform))


def _views(config: OCIO.Config) -> list[View]:
    """Shared views' definitions, then per display its own views and the shared ones it lists."""
    import PyOpenColorIO as OCIO

    def view(display: str, name: str) -> View:
        return View(
            display,
            name,
            config.getDisplayViewColorSpaceName(display, name),
            config.getDisplayViewTransformName(display, name),
            config.getDisplayViewLooks(display, name),
            config.getDisplayViewRule(display, name),
            config.getDisplayViewDescription(display, name),
        )

    views = [view("", name) for name in config.getSharedViews()]
    for display in config.getDisplaysAll():
        views += [view(display, v) for v in config.getViews(OCIO.VIEW_DISPLAY_DEFINED, display)]
        views += [
            View(display, v, "", shared=True) for v in config.getViews(OCIO.VIEW_SHARED, display)
        ]
    return views


_O = TypeVar("_O")
_R = TypeVar("_R")
_N = TypeVar("_N", ColourSpace, NamedTransform, Look, ViewTransform)


def _yaml(item: object) -> str:
    """How OCIO writes ``item`` (a colour space, named transform, look or view transform)."""
    import PyOpenColorIO as OCIO

    config = OCIO.Config()
    getattr(config, f"add{type(item).__name__}")(item)
    return config.serialize()


def _split(
    items: Iterable[_O], record: Callable[[_O], _R], rebuild: Callable[[_R], object], exact: bool
) -> tuple[list[_R], list[Kept]]:
    """(records of ``items`` that rebuild them exactly, as OCIO writes both; the items that do
    not: a transform without record, a field the record does not carry); not ``exact``: every
    record, unchecked."""
    records: list[_R] = []
    kept: list[Kept] = []
    for index, item in enumerate(items):
        if not exact:
            records.append(record(item))
            continue
        try:
            rec = record(item)
            same = _yaml(rebuild(rec)) == _yaml(item)
        except ValueError:
            same = False
        if same:
            records.append(rec)
        else:
            aliases = tuple(getattr(item, "getAliases", tuple)())  # looks, view transforms: none
            kept.append(Kept(item.getName(), aliases, item, index))  # type: ignore[attr-defined]
    return records, kept


def split_config(
    config: OCIO.Config, *, exact: bool = True
) -> tuple[ConfigData, OCIO.Config | None]:
    """``config`` as data, and a copy of it with only what the data does not describe: the file
    rules (but the default rule's colour space), viewing rules, luma, strict parsing, family
    separator (:func:`build` adds the data to this copy). Each colour space, named transform,
    look and view transform no record rebuilds exactly is kept as OCIO has it
    (:attr:`ConfigData.kept`). ``exact=False``: every element as data, unchecked, and no copy."""
    import PyOpenColorIO as OCIO

    every = (OCIO.SEARCH_REFERENCE_SPACE_ALL, OCIO.COLORSPACE_ALL)
    all_spaces = config.getColorSpaces(*every)
    all_named = config.getNamedTransforms(OCIO.NAMEDTRANSFORM_ALL)
    all_vts = config.getViewTransforms()
    spaces, kept_spaces = _split(all_spaces, colour_space_record, _ocio_colour_space, exact)
    named, kept_named = _split(all_named, _named_record, _ocio_named_transform, exact)
    looks, kept_looks = _split(config.getLooks(), _look_record, _ocio_look, exact)
    vts, kept_vts = _split(all_vts, _view_transform_record, _ocio_view_transform, exact)
    rules = config.getFileRules()
    default_rule = rules.getColorSpace(rules.getNumEntries() - 1)
    data = ConfigData(
        name=config.getName(),
        description=config.getDescription(),
        version=(config.getMajorVersion(), config.getMinorVersion()),
        search_path=config.getSearchPath(),
        roles=dict(config.getRoles()),
        colour_spaces=spaces,
        named_transforms=named,
        looks=looks,
        view_transforms=vts,
        views=_views(config),
        active_displays=tuple(name_list(config.getActiveDisplays())),
        active_views=tuple(name_list(config.getActiveViews())),
        environment={
            n: config.getEnvironmentVarDefault(n) for n in config.getEnvironmentVarNames()
        },
        default_rule="" if default_rule == "default" else default_rule,
        default_view_transform=config.getDefaultViewTransformName(),
        inactive_colour_spaces=tuple(name_list(config.getInactiveColorSpaces())),
        kept=(*kept_spaces, *kept_named, *kept_looks, *kept_vts),
    )
    if not exact:
        return data, None
    rest = OCIO.Config.CreateFromStream(config.serialize())
    rest.clearColorSpaces()
    rest.clearNamedTransforms()
    rest.clearLooks()
    rest.clearViewTransforms()
    rest.clearDisplays()
    for name in config.getSharedViews():  # no clearSharedViews before OCIO 2.4
        rest.removeSharedView(name)
    rest.clearEnvironmentVars()
    for setter in (rest.setActiveDisplays, rest.setActiveViews, rest.setInactiveColorSpaces):
        setter("")  # the data's lists (build sets them only when not empty)
    return data, rest


def config_record(config: OCIO.Config) -> ConfigData:
    """The data of an OCIO config whose every transform has a record (what :func:`build`
    makes; ValueError otherwise)."""
    return split_config(config, exact=False)[0]


def merge(base: ConfigData, overlay: ConfigData) -> ConfigData:
    """``overlay`` merged onto ``base``: every element of the base as it is, and the overlay's
    where the base has none of that name or alias (the base wins, as OCIO's
    ``STRATEGY_PREFER_BASE``); the overlay's name and description where given; the newer
    version; the base's file rule, active and inactive lists and default view transform."""
    paths = [p for p in (*base.search_path.split(":"), *overlay.search_path.split(":")) if p]
    views = {(v.display, v.name) for v in base.views}

    def new(mine: list[_N], theirs: list[_N]) -> list[_N]:
        taken = {
            *base.kept_names(),
            *(n for x in mine for n in (x.name, *getattr(x, "aliases", ()))),
        }
        return mine + [item for item in theirs if item.name not in taken]

    def add(mine: dict[str, str], theirs: dict[str, str]) -> dict[str, str]:
        return {**mine, **{k: v for k, v in theirs.items() if k not in mine}}

    return dataclasses.replace(
        base,
        name=overlay.name or base.name,
        description=overlay.description or base.description,
        version=max(base.version, overlay.version),
        search_path=":".join(dict.fromkeys(paths)),
        roles=add(base.roles, overlay.roles),
        colour_spaces=new(base.colour_spaces, overlay.colour_spaces),
        named_transforms=new(base.named_transforms, overlay.named_transforms),
        looks=new(base.looks, overlay.looks),
        view_transforms=new(base.view_transforms, overlay.view_transforms),
        views=base.views + [v for v in overlay.views if (v.display, v.name) not in views],
        environment=add(base.environment, overlay.environment),
    )


def name_list(value: object) -> list[str]:
    """A name list as OCIO returns it (a comma-separated string before 2.5, else an iterator)."""
    if isinstance(value, str):
        return [v.strip() for v in value.split(",") if v.strip()]
    return list(value)  # type: ignore[call-overload]
