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


#: Column headers of the one terminal table (``solve`` and ``demo``).
SUMMARY_COLUMNS = (
    "environment",
    "method",
    "cond[SL]",
    "cond(Q)",
    "N",
    "lit M-only",
    "lit M+Q",
    "shown M",
    "shown N+Q",
    "CV M+Q",
    "drive<0",
    "clipped",
)

SUMMARY_LEGEND = (
    "errors: mean |camera RGB - target| over R, G, B, in % of the target white patch.\n"
    "  lit = the chart lit by the wall (M only, then after Q; with the drive the wall can emit);\n"
    "  shown = the background seen in camera (through M, then through N + offset and Q);\n"
    "  CV = leave-one-patch-out error after Q ('-' when the method does not give it)."
)


def _percent(per_channel) -> str:
    if per_channel is None:
        return "-"
    return f"{100 * float(sum(per_channel)) / len(per_channel):.2f}%"


def _n_state(solution) -> str:
    if solution.N is None:
        return "NOT solved"
    return "= M" if solution.diagnostics.get("N_equals_M") else "solved"


def summary_row(solution) -> tuple[str, ...]:
    """One environment's row, from :func:`ocio_vp.calibration.diagnostics.summary_errors`."""
    from ocio_vp.calibration.diagnostics import summary_errors

    d = solution.diagnostics
    errors = summary_errors(d)
    model = d.get("model", solution.method)
    method = solution.method if model in (None, solution.method) else f"{solution.method}: {model}"
    return (
        solution.environment,
        method,
        f"{float(d.get('cond_SL', 'nan')):.3g}",
        f"{float(d.get('cond_Q', 'nan')):.3g}",
        _n_state(solution),
        _percent(errors["lit_baseline"]),
        _percent(errors["lit"]),
        _percent(errors["shown_baseline"]),
        _percent(errors["shown"]),
        _percent(errors["cross_validated"]),
        ",".join("RGB"[c] for c in d.get("out_of_frustum_negative_channels") or []) or "-",
        str(len(d.get("clipped_patches") or [])),
    )


def summary_table(solutions) -> str:
    """The terminal table of ``solve`` and ``demo``, its legend and every warning of the solves."""
    rows = [SUMMARY_COLUMNS, *(summary_row(s) for s in solutions)]
    widths = [max(len(r[i]) for r in rows) for i in range(len(SUMMARY_COLUMNS))]
    lines = [SUMMARY_LEGEND]
    lines += ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    for s in solutions:
        if s.diagnostics.get("model_reason"):
            lines.append(f"model: {s.environment}: {s.diagnostics['model_reason']}")
    for s in solutions:
        lines += [f"warning: {s.environment}: {w}" for w in s.diagnostics.get("warnings", [])]
    return "\n".join(lines)
