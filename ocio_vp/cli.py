"""The ``ocio-vp`` command: parses arguments and dispatches to :mod:`ocio_vp.commands`.

User mistakes, bad arguments and what the disk or the system did end with one line on stderr
and exit 2 (:func:`ocio_vp.errors.describe_failure`); a bug with one line and exit 1
(``OCIO_VP_TRACEBACK=1`` shows the traceback).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import os
import sys
import types
from collections.abc import Sequence
from typing import Any, NoReturn

from ocio_vp import __version__
from ocio_vp.commands.common import HelpFormatter
from ocio_vp.errors import InputError, describe_failure

__all__ = ["main"]

# Verbs in the order ``--help`` lists them; each is a module in ocio_vp.commands.
COMMANDS = (
    "demo",
    "patterns",
    "measure",
    "solve",
    "validate",
    "simulate",
    "export",
    "apply",
    "report",
    "prepare_hdri",
    "target_chart",
)


#: Commands whose numbers are many small matrices (chart-sized fits, Newton steps on colour
#: batches): OpenBLAS's threads cost them more than they give (docs/performance.md), in this
#: process and in the solve's writing helper, which inherits the setting.
SMALL_MATRIX_COMMANDS = frozenset({"demo", "solve"})


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (``--help`` still shows the usage), with a
    did-you-mean for a mistyped option, command or choice."""

    def error(self, message: str) -> NoReturn:
        problem = f"{message}{did_you_mean(self, message)} (see {self.prog} --help)"
        self.exit(2, f"{self.prog}: error: {InputError(problem)}\n")


def _option_strings(parser: argparse.ArgumentParser) -> list[str]:
    """Every option of ``parser`` and of its subcommands."""
    names = list(parser._option_string_actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                names += list(sub._option_string_actions)
    return names


def did_you_mean(parser: argparse.ArgumentParser, message: str) -> str:
    """``" (did you mean '--wall-encoding'?)"`` for an argparse error, or ``""``.

    >>> did_you_mean(build_parser(), "unrecognized arguments: --wall-encodng pq")
    " (did you mean '--wall-encoding'?)"
    >>> did_you_mean(build_parser(), "argument COMMAND: invalid choice: 'solv' (choose from "
    ...              "'demo', 'solve')")
    " (did you mean 'solve'?)"
    """
    import difflib
    import re

    choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
    if choice:
        wrong, valid = choice.group(1), re.findall(r"'([^']*)'", choice.group(2))
    elif message.startswith("unrecognized arguments:"):
        words = message.split(":", 1)[1].split()
        wrong, valid = next((w for w in words if w.startswith("-")), ""), _option_strings(parser)
        wrong = wrong.split("=", 1)[0]
    else:
        return ""
    close = difflib.get_close_matches(wrong, valid, n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close and wrong else ""


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="ocio-vp",
        description="Colour-calibrate an RGB LED virtual-production stage and write OpenColorIO "
        "configs (LeGendre, Lepicovsky & Debevec, DigiPro 2022). `ocio-vp COMMAND --help` "
        "explains each command.",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    subparsers = parser.add_subparsers(  # type: ignore[call-overload]  # parser_class: a partial
        dest="command",
        required=True,
        metavar="COMMAND",
        parser_class=functools.partial(OneLineParser, formatter_class=HelpFormatter),
    )
    for name in COMMANDS:
        importlib.import_module(f"ocio_vp.commands.{name}").add_parser(subparsers)
    return parser


class _DeferredModule(types.ModuleType):
    """Stands in ``sys.modules`` for a module not loaded yet; the first use of any of its
    attributes loads the real module (which replaces it there) and answers from it."""

    def __getattr__(self, attribute: str) -> Any:
        if sys.modules.get(self.__name__) is self:
            del sys.modules[self.__name__]
        return getattr(importlib.import_module(self.__name__), attribute)


def _defer_colour_plotting() -> None:
    """colour-science's ``__init__`` (0.4.x) imports ``colour.plotting`` and with it matplotlib's
    pyplot, which ocio_vp never uses through colour: a stand-in takes its place until the first
    attribute read from it imports the real one. Called by :func:`main` only, so ``import
    ocio_vp`` in someone else's process leaves their modules alone."""
    name = "colour.plotting"
    if "colour" not in sys.modules and name not in sys.modules:
        sys.modules[name] = _DeferredModule(name)


def _one_blas_thread() -> None:
    """OpenBLAS single-threaded in this process and those it starts, unless the user chose its
    threads (``OPENBLAS_NUM_THREADS``); only before numpy is loaded, when OpenBLAS reads it."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main(argv: Sequence[str] | None = None) -> int:
    from ocio_vp.staging import stop_on_signals

    _defer_colour_plotting()

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command in SMALL_MATRIX_COMMANDS:
        _one_blas_thread()
    try:
        with stop_on_signals():  # kill, timeout: staging folders removed as on Ctrl-C
            return int(args.func(args) or 0)
    except KeyboardInterrupt as stop:
        signum = getattr(stop, "signum", 2)  # Ctrl-C: SIGINT
        print(f"ocio-vp {args.command}: interrupted", file=sys.stderr)
        return 128 + signum
    except (Exception, RecursionError) as error:
        status, message = describe_failure(error)
        if status != 2 and os.environ.get("OCIO_VP_TRACEBACK"):
            raise
        print(f"ocio-vp {args.command}: error: {message}", file=sys.stderr)
        return status


if __name__ == "__main__":
    sys.exit(main())
