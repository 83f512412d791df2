"""Find and render the jinja2 templates in the top-level ``templates/`` folder.

In a source checkout the folder sits beside the package; an installed (non-editable) wheel
ships it as data files under ``sys.prefix/share/ocio-vp/templates``.

Autoescaping is off on purpose: each target language (Tcl, C, Markdown) needs its own
escaping, applied explicitly through the filters registered here (``tcl``, ``c_comment``,
``md``, ``cfloat``, ``tclfloat``); templates never print a name unfiltered.
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path
from typing import Any

from ocio_vp.exports.escape import c_comment, c_float, markdown_text, tcl_float, tcl_string

__all__ = ["render_template", "template_dir"]


def template_dir() -> Path:
    """The folder holding ``*.j2`` templates (source checkout first, then the install)."""
    candidates = [
        Path(__file__).resolve().parents[2] / "templates",
        Path(sys.prefix) / "share" / "ocio-vp" / "templates",
    ]
    for folder in candidates:
        if folder.is_dir() and any(folder.glob("*.j2")):
            return folder
    raise FileNotFoundError(
        "ocio-vp templates not found; looked in " + ", ".join(str(c) for c in candidates)
    )


@functools.lru_cache(maxsize=1)
def _environment() -> Any:
    import jinja2

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(template_dir())),
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
    return _environment().get_template(name).render(**context)
