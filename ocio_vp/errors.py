"""The one exception type for user mistakes, and bounded quoting of user values.

Every problem a user can fix is an :class:`InputError`, printed on one line with exit status 2;
user values are quoted through :func:`excerpt`, so a huge or endless value stays one short line.
"""

from __future__ import annotations

import reprlib

__all__ = ["MAX_MESSAGE", "InputError", "describe_failure", "excerpt", "format_key_path"]

#: Longest message :class:`InputError` prints (the command line adds ``ocio-vp VERB: error: ``).
MAX_MESSAGE = 268

_REPR = reprlib.Repr()
_REPR.maxlevel = 2
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = _REPR.maxset = 4
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = 40


def excerpt(value: object, limit: int = 40) -> str:
    """A short, escaped, one-line ``repr`` of ``value`` that never builds the whole ``repr``.

    Examples
    --------
    >>> excerpt("name\\n")
    "'name\\\\n'"
    >>> excerpt("x" * 10_000)
    "'xxxxxxxxxxxxxxxxx...xxxxxxxxxxxxxxxxxx'"
    >>> excerpt(list(range(10**6)))
    '[0, 1, 2, 3, ...]'
    """
    try:
        text = _REPR.repr(value)
    except Exception:  # a value whose repr fails still gets a message
        text = f"<{type(value).__name__}>"
    text = text.encode("ascii", "backslashreplace").decode("ascii")
    text = " ".join(text.split())
    if len(text) > max(limit, 16) * 2:
        text = text[: max(limit, 16) * 2 - 3] + "..."
    return text


def _clip(text: str, limit: int) -> str:
    """One line, printable ASCII-escaped, at most ``limit`` characters (middle elided)."""
    text = " ".join(str(text).split())
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    if len(text) > limit:
        half = (limit - 3) // 2
        text = f"{text[:half]}...{text[-half:]}"
    return text


def format_key_path(*parts: str | int) -> str:
    """Join key-path parts as a user reads them: ``environments[2].target_chart[5]``."""
    text = ""
    for part in parts:
        if isinstance(part, int):
            text += f"[{part}]"
        elif text:
            text += f".{part}"
        else:
            text = str(part)
    return text


class InputError(ValueError):
    """A problem with user input, reported as ``SOURCE: KEY: problem`` on one short line.

    Parameters
    ----------
    problem
        What is wrong and, where it helps, what was expected.
    source
        The file (or other input) the problem is in.
    key
        The key path inside that file, e.g. ``environments[2].target_chart[5]``.

    Each part is clipped to one line, the whole under :data:`MAX_MESSAGE` characters.
    """

    def __init__(self, problem: str, *, source: object = None, key: str | None = None) -> None:
        self.source = None if source is None else _clip(str(source), 100)
        self.key = None if key is None else _clip(key, 50)
        room = MAX_MESSAGE - len(self.source or "") - len(self.key or "") - 4
        self.problem = _clip(problem, room)
        super().__init__(str(self))

    def __str__(self) -> str:
        parts = [p for p in (self.source, self.key) if p]
        return ": ".join([*parts, self.problem])


def describe_failure(error: BaseException) -> tuple[int, str]:
    """The exit status and one-line message for an exception that ended a command: 2 for
    what the user can act on (:class:`InputError`, ``OSError``, out of memory, OpenColorIO
    refusing a config, a linear-algebra failure on extreme input), else 1 (a bug)."""
    if isinstance(error, InputError):
        return 2, str(error)
    if isinstance(error, OSError):
        what = error.strerror or type(error).__name__
        where = error.filename if error.filename is not None else None
        return 2, str(InputError(what, source=where))
    if isinstance(error, MemoryError):
        return 2, "out of memory: the input is too large for this machine"
    kind = type(error)
    text = excerpt(str(error), 80).strip("'\"")
    if kind.__module__.startswith("PyOpenColorIO"):
        return 2, str(InputError(f"OpenColorIO: {text}"))
    if kind.__name__ == "LinAlgError":
        return 2, str(InputError(f"numerical failure ({text}); check the input values' scale"))
    hint = "this is a bug in ocio-vp; set OCIO_VP_TRACEBACK=1 to see where, and report it"
    return 1, str(InputError(f"internal error: {kind.__name__}: {text} ({hint})"))
