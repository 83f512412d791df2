"""Benchmarks: ``python -m benchmarks.run [--quick]`` writes docs/performance.md.

Every ``benchmarks/bench_<topic>.py`` exposes ``run(quick: bool = False) -> str`` returning a
markdown section whose rows pair a time (median of several runs) with an accuracy figure
measured in the same run. The small helpers below keep those sections uniform.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["fmt_ms", "markdown_table", "median_time"]


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
