"""Escaping for every language an exported name ends up in (Tcl, C, Markdown, file names).

Names are validated on input (:func:`ocio_vp.formats.measurements.check_safe_name`) *and* escaped on
output: a hand-edited ``solution.json`` or a future caller that skips validation must still
never turn a name into code or into a path outside the output folder.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError

__all__ = [
    "c_comment",
    "c_float",
    "inside",
    "markdown_text",
    "nuke_identifier",
    "tcl_float",
    "tcl_string",
]

# Inside a Tcl double-quoted word these characters are special: substitution ([ $ \), the
# closing quote, and braces (Nuke's own .nk reader also counts them).
_TCL_SPECIAL = {"\\", '"', "[", "]", "$", "{", "}"}


def tcl_string(value: object) -> str:
    """Quote ``value`` as one literal Tcl word: ``"..."`` with every special character escaped.

    Newlines and other control characters become ``\\n`` / ``\\xHH`` escapes, so a value can
    neither end the current command nor start a command substitution (``[exec ...]``).

    Examples
    --------
    >>> print(tcl_string('a [exec rm -rf ~] "b"'))
    "a \\[exec rm -rf ~\\] \\"b\\""
    """
    out = []
    for char in str(value):
        code = ord(char)
        if char in _TCL_SPECIAL:
            out.append("\\" + char)
        elif char == "\n":
            out.append("\\n")
        elif char == "\t":
            out.append("\\t")
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\x{code:02x}")
        elif code > 0x7E:
            # Tcl's \uXXXX (BMP) and \UXXXXXXXX escapes keep the file plain ASCII.
            out.append(f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}")
        else:
            out.append(char)
    return '"' + "".join(out) + '"'


def nuke_identifier(value: object, *, prefix: str = "") -> str:
    """A Nuke node name made from ``value``: letters, digits and ``_`` only, not starting with
    a digit (Nuke's rule for node names, also safe anywhere in a .nk file)."""
    text = re.sub(r"[^A-Za-z0-9_]", "_", f"{prefix}{value}")
    if not text or text[0].isdigit():
        text = "_" + text
    return text


def tcl_float(value: float) -> str:
    """A float written so that Tcl/Nuke read back the same float64 (Python's shortest repr)."""
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"non-finite value {number!r} cannot be exported")
    return repr(number)


def c_float(value: float) -> str:
    """A C ``float`` literal holding ``value`` to full single precision (9 significant
    digits round-trip every float32), with the ``f`` suffix.

    Examples
    --------
    >>> c_float(0.1), c_float(1), c_float(-2.5e-7)
    ('0.100000001f', '1.0f', '-2.49999999e-07f')
    """
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"non-finite value {number!r} cannot be exported")
    text = f"{float(np.float32(number)):.9g}"
    if "e" not in text and "." not in text:
        text += ".0"
    return text + "f"


def c_comment(value: object) -> str:
    """Text safe inside a C ``/* ... */`` comment and on one ``//`` line: printable ASCII
    only, no ``*/``, ``/*``, backslash (line splicing) or trigraph-forming ``??``.

    Examples
    --------
    >>> c_comment('x */ system("id"); /*\\nnext')
    'x * / system("id"); / *?next'
    """
    text = "".join(ch if 0x20 <= ord(ch) < 0x7F else "?" for ch in str(value))
    text = text.replace("\\", "/")
    while "*/" in text or "/*" in text or "??" in text:
        text = text.replace("*/", "* /").replace("/*", "/ *").replace("??", "? ?")
    return text


def markdown_text(value: object) -> str:
    """Text shown literally in Markdown on one line (inline code cannot be broken out of)."""
    text = " ".join(str(value).split())
    ticks = "`"
    while ticks in text:
        ticks += "`"
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{ticks}{pad}{text}{pad}{ticks}"


def inside(path: Path, root: Path, *, source: object = None) -> Path:
    """Return ``path`` if it resolves inside ``root``; else raise :class:`InputError`."""
    resolved = Path(path).resolve()
    base = Path(root).resolve()
    if resolved != base and base not in resolved.parents:
        raise InputError(f"refusing to write outside {base}: {resolved}", source=source)
    return Path(path)
