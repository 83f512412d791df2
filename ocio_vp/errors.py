"""The one exception type for user mistakes.

Every problem a user can fix (a bad file, field or value) is raised as :class:`InputError`.
The command line prints it on one line and exits with status 2; anything else is a bug.
"""

from __future__ import annotations

__all__ = ["InputError", "format_key_path"]


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
    """A problem with user input, reported as ``SOURCE: KEY: problem``.

    Parameters
    ----------
    problem
        What is wrong and, where it helps, what was expected.
    source
        The file (or other input) the problem is in.
    key
        The key path inside that file, e.g. ``environments[2].target_chart[5]``.
    """

    def __init__(self, problem: str, *, source: object = None, key: str | None = None) -> None:
        self.problem = " ".join(str(problem).split())  # always one line
        self.source = None if source is None else str(source)
        self.key = key
        super().__init__(str(self))

    def __str__(self) -> str:
        parts = [p for p in (self.source, self.key) if p]
        return ": ".join([*parts, self.problem])
