"""The embedded sample data: the paper's seven environments on the default simulated stage.

``sample_configs/paper_stage.yaml`` is the measurements file and
``sample_configs/paper_stage/<environment>/`` the configs solved from it (paper eq. 5 exactly,
``method="least-squares"``, so a change of the library's default method does not change
them). Regenerate with ``python -m ocio_vp.simulator.samples sample_configs``; same code and
libraries, same bytes.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from ocio_vp.formats.measurements import load_measurements, save_measurements

__all__ = [
    "SAMPLE_METHOD",
    "SAMPLE_NAME",
    "simulate_and_solve",
    "write_paper_samples",
]

SAMPLE_NAME = "paper_stage"
#: The paper's eq. 5, fixed so the committed sample does not follow the library default.
SAMPLE_METHOD = "least-squares"


def simulate_and_solve(measurements_path: Path, *, method: str | None = None, stage=None):
    """Simulate the paper stage, save its measurements file, load it back and solve it.

    Returns ``(measurements, solutions)``; the solutions name the saved file and its sha256.
    """
    from ocio_vp.pipeline import DEFAULT_METHOD, solve_measurements
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    stage = paper_stage() if stage is None else stage
    save_measurements(simulate_measurements(stage=stage), measurements_path)
    measurements = load_measurements(measurements_path)
    solutions = solve_measurements(measurements, method=method or DEFAULT_METHOD)
    return measurements, solutions


def write_paper_samples(directory: str | Path) -> Path:
    """Write ``DIR/paper_stage.yaml`` and ``DIR/paper_stage/<environment>/`` (all or nothing).

    Returns the measurements file's path.
    """
    from ocio_vp.ocio.writer import write_solutions
    from ocio_vp.staging import write_file_atomically

    directory = Path(directory)
    final = directory / f"{SAMPLE_NAME}.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / final.name
        _, solutions = simulate_and_solve(scratch, method=SAMPLE_METHOD)
        write_solutions(solutions, directory / SAMPLE_NAME)
        write_file_atomically(final, scratch.read_bytes())
    return final


if __name__ == "__main__":
    print(write_paper_samples(sys.argv[1] if len(sys.argv) > 1 else "sample_configs"))
