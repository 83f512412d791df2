"""A measuring child process: a fresh interpreter, so that its peak memory is the measured
work's alone.

Its code starts with :data:`PRELUDE`, which defines ``hwm()``: the process's own peak resident
set size in bytes, ``VmHWM`` from ``/proc/self/status`` (not ``ru_maxrss``: on Linux that
survives the exec that started the interpreter, so it would include the parent's).
"""

from __future__ import annotations

import subprocess
import sys

PRELUDE = """
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM"):
            return int(line.split()[1]) * 1024
"""


def run_child(code: str, *args: str) -> str:
    """Run :data:`PRELUDE` + ``code`` with ``sys.argv[1:] = args``; its standard output."""
    return subprocess.run(
        [sys.executable, "-c", PRELUDE + code, *args], check=True, capture_output=True, text=True
    ).stdout


MIB = 2**20


def memory_rows(memory: list[tuple[int, dict[str, int]]]) -> tuple[list[str], str]:
    """(table rows, growth sentence) of ``(frames, {"peak", "base"} bytes)`` runs of two
    lengths: the peak, the peak after imports and what measuring added, in MiB."""
    rows = [
        f"| {n} | {r['peak'] / MIB:.0f} | {r['base'] / MIB:.0f} | {(r['peak'] - r['base']) / MIB:.0f} |"
        for n, r in memory
    ]
    (n_a, a), (n_b, b) = memory
    growth = (b["peak"] - b["base"]) - (a["peak"] - a["base"])
    return rows, f"- {n_b / n_a:.1f}x the frames, {growth / MIB:+.0f} MiB of peak memory"
