"""The ``ocio-vp`` command: parses arguments and dispatches to :mod:`ocio_vp.commands`.

User mistakes (:class:`ocio_vp.errors.InputError`) end with one line on stderr and exit 2.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import sys
from collections.abc import Sequence

from ocio_vp import __version__
from ocio_vp.commands.common import HelpFormatter
from ocio_vp.errors import InputError

__all__ = ["main"]

# Verbs in the order ``--help`` lists them; each is a module in ocio_vp.commands.
COMMANDS = (
    "demo",
    "solve",
    "simulate",
    "measure",
    "export",
    "apply",
    "report",
    "prepare_hdri",
    "target_chart",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ocio-vp",
        description="Colour-calibrate an RGB LED virtual-production stage and write OpenColorIO "
        "configs (LeGendre, Lepicovsky & Debevec, DigiPro 2022). `ocio-vp COMMAND --help` "
        "explains each command.",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    subparsers = parser.add_subparsers(
        dest="command",
        required=True,
        metavar="COMMAND",
        parser_class=functools.partial(argparse.ArgumentParser, formatter_class=HelpFormatter),
    )
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"ocio_vp.commands.{name}")
        except ModuleNotFoundError as error:
            if error.name == f"ocio_vp.commands.{name}":
                continue  # verb not built in this version
            raise
        module.add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except InputError as error:
        print(f"ocio-vp {args.command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"ocio-vp {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
