"""Benchmarks: ``python -m benchmarks.run [--quick]`` writes docs/performance.md.

Every ``benchmarks/bench_<topic>.py`` exposes ``run(quick: bool = False) -> str`` returning a
markdown section whose rows pair a time (median of several runs) with an accuracy figure
measured in the same run. The small helpers below keep those sections uniform.
"""

from __future__ import annotations

import contextlib
import os
import statistics
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

__all__ = ["cached_bytecode", "fmt_ms", "markdown_table", "median_time", "replace_section"]


def median_time(func: Callable[[], Any], *, repeats: int = 5, warmup: int = 1) -> float:
    """Median wall time of ``func()`` in seconds over ``repeats`` runs after ``warmup`` runs."""
    for _ in range(warmup):
        func()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def fmt_ms(seconds: float) -> str:
    """Seconds as ms (below 1 s) or s, three significant figures."""
    return f"{seconds * 1e3:.3g} ms" if seconds < 1 else f"{seconds:.3g} s"


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A GitHub markdown table."""
    lines = ["| " + " | ".join(map(str, header)) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(map(str, row)) + " |" for row in rows]
    return "\n".join(lines)


def replace_section(document: str, section: str) -> str:
    """``document`` with the section headed by ``section``'s first line (up to the next heading
    of the same level, or the end) replaced by ``section``; appended when it has none.

    >>> replace_section("# T\\n\\n## A\\nold\\n\\n## B\\nb\\n", "## A\\nnew\\n")
    '# T\\n\\n## A\\nnew\\n\\n## B\\nb\\n'
    >>> replace_section("# T\\n", "## A\\nnew\\n")
    '# T\\n\\n## A\\nnew\\n'
    """
    heading = section.split("\n", 1)[0]
    level = heading[: len(heading) - len(heading.lstrip("#"))] + " "
    body = section.rstrip("\n") + "\n"
    text = document.rstrip("\n")
    if not text:
        return body
    lines = text.split("\n")
    if heading not in lines:
        return f"{text}\n\n{body}"
    start = lines.index(heading)
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith(level)), len(lines))
    tail = "\n".join(lines[end:])
    return "\n".join(lines[:start]) + "\n" + body + (f"\n{tail}\n" if tail else "")


def write_section(section: str, out: str | None) -> None:
    """Print ``section``, or put it in the document ``out`` with :func:`replace_section` (the
    other sections kept; the document made when missing)."""
    if not out:
        print(section)
        return
    path = Path(out)
    existing = path.read_text(encoding="utf-8") if path.exists() else ""
    path.write_text(replace_section(existing, section), encoding="utf-8")


@contextlib.contextmanager
def cached_bytecode() -> Iterator[dict[str, str]]:
    """An environment for timing whole commands as a user runs them after the first time.

    Python caches compiled modules (``__pycache__``) unless ``PYTHONDONTWRITEBYTECODE`` is set,
    as it is on some build and CI machines; there every run would recompile ocio_vp's modules
    (~0.2 s on the demo), which no user pays twice. This environment drops that variable and
    sends the cache to a temporary folder (``PYTHONPYCACHEPREFIX``), removed afterwards, so the
    checkout is left as it was. Run each command once untimed to fill the cache.
    """
    with tempfile.TemporaryDirectory(prefix="ocio_vp_pycache_") as prefix:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = prefix
        yield env
