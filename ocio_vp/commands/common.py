"""What every verb shares: help that names its defaults, the ``--method`` option, progress bars.

Kept light (no numpy at import) so ``ocio-vp --help`` stays fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import Any

__all__ = ["HelpFormatter", "add_method_argument", "progress", "warn"]


class HelpFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` to every option whose help does not already say its default.

    Options without a meaningful default (``None``, flags) must say in words what happens when
    they are left out; this formatter cannot invent that.
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        default = action.default
        if "default" in text.lower() or default is None or default is False:
            return text
        if default is argparse.SUPPRESS:
            return text
        if action.option_strings or action.nargs in (argparse.OPTIONAL, argparse.ZERO_OR_MORE):
            value = action.default
            if isinstance(value, (list, tuple)):
                value = " ".join(str(v) for v in value) or "none"
            return f"{text} (default: {str(value).replace('%', '%%')})"
        return text


def add_method_argument(parser: argparse.ArgumentParser) -> None:
    """``--method``, its choices listed from the Q-solve registry, default the library's."""
    from ocio_vp.choices import DEFAULT_METHOD, Q_METHODS

    parser.add_argument(
        "--method",
        choices=Q_METHODS,
        default=DEFAULT_METHOD,
        metavar="METHOD",
        help="Q-solve method, one of: " + ", ".join(Q_METHODS) + ". "
        f"'{DEFAULT_METHOD}' picks the simplest model the scene needs; 'least-squares' is the "
        f"paper's eq. 5 (default: {DEFAULT_METHOD})",
    )


def progress(iterable: Iterable | None = None, **options: Any):
    """A tqdm bar on stderr, shown only when stderr is a terminal (``disable=None``)."""
    from tqdm import tqdm

    options.setdefault("disable", None)
    options.setdefault("file", sys.stderr)
    options.setdefault("leave", False)
    options.setdefault("dynamic_ncols", True)
    return tqdm(iterable, **options)


def warn(verb: str, message: str) -> None:
    """One warning line on stderr, ``ocio-vp VERB: warning: ...``."""
    print(f"ocio-vp {verb}: warning: {message}", file=sys.stderr)
