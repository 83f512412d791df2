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
from typing import Any

__all__ = ["cached_bytecode", "fmt_ms", "markdown_table", "median_time"]


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
