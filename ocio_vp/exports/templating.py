"""Find and render the jinja2 templates shipped inside the package (``ocio_vp/templates``).

The source is the top-level ``templates/`` folder; ``ocio_vp/templates`` links to it and the
build copies its files into the package, so :mod:`importlib.resources` finds them in every kind
of install (editable, wheel, ``pip install --user``, a zip on ``sys.path``). Templates are read
as resources, never as paths, so a zipped package works too.

Autoescaping is off on purpose: each target language (Tcl, C, Markdown) needs its own
escaping, applied explicitly through the filters registered here (``tcl``, ``c_comment``,
``md``, ``cfloat``, ``tclfloat``); templates never print a name unfiltered.
"""

from __future__ import annotations

import functools
from importlib import resources
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported where templates are rendered, not at start-up
    import jinja2

from ocio_vp.exports.escape import c_comment, c_float, markdown_text, tcl_float, tcl_string

__all__ = ["html_template", "jinja_environment", "read_template", "render_template"]

#: The package that holds the templates as resources.
TEMPLATE_PACKAGE = "ocio_vp"


def read_template(name: str) -> str:
    """The text of template ``name`` from the package's ``templates`` resources.

    Raises
    ------
    FileNotFoundError
        When the install lacks it (a broken install, not a user mistake).
    """
    resource = resources.files(TEMPLATE_PACKAGE).joinpath("templates").joinpath(name)
    try:
        return resource.read_text(encoding="utf-8")
    except (FileNotFoundError, NotADirectoryError):
        raise FileNotFoundError(
            f"ocio-vp template {name!r} is missing from the installed package ({resource}); "
            "reinstall ocio-vp"
        ) from None


def html_template(name: str) -> jinja2.Template:
    """Template ``name`` for an HTML page: autoescaped, undefined variables an error."""
    import jinja2

    loader = jinja2.FunctionLoader(lambda name: (read_template(name), None, lambda: True))
    env = jinja2.Environment(loader=loader, autoescape=True, undefined=jinja2.StrictUndefined)
    return env.get_template(name)


@functools.lru_cache(maxsize=1)
def jinja_environment() -> jinja2.Environment:
    """The jinja2 environment with our escaping filters, loading templates as resources."""
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda name: (read_template(name), None, lambda: True)),
        autoescape=False,
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
    )
    env.filters.update(
        tcl=tcl_string, tclfloat=tcl_float, cfloat=c_float, c_comment=c_comment, md=markdown_text
    )
    return env


def render_template(name: str, **context: Any) -> str:
    """Render ``templates/<name>`` with ``context`` (undefined variables are an error)."""
    return jinja_environment().get_template(name).render(**context)
