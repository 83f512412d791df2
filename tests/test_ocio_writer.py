"""Writing environments with a helper process: the same files, and every failure as without it.

Independent check: the files written by this process alone (no pool), byte for byte.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.solution import solution_to_json
from ocio_vp.ocio.writer import _share, write_solutions, writer_pool
from ocio_vp.pipeline import solve_environment

# The real helper process throughout (tests/conftest.py replaces it for other in-process solves).
pytestmark = pytest.mark.writer_helper


@pytest.fixture(scope="module")
def solutions():
    from ocio_vp.simulator.stage import paper_stage_measurements

    m = paper_stage_measurements(("incandescent", "direct_sun", "sodium_vapour"))
    methods = ("root-polynomial", "root-polynomial", "least-squares")
    return [solve_environment(m, e, method=k) for e, k in zip(m.environments, methods, strict=True)]


def _files(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


@pytest.fixture(scope="module")
def alone(solutions, tmp_path_factory):
    out = tmp_path_factory.mktemp("alone") / "out"
    written = write_solutions(solutions, out)
    return _files(out), [solution_to_json(s) for s in written]


def test_a_helper_writes_the_same_files(solutions, alone, tmp_path):
    with writer_pool() as pool:
        written = write_solutions(solutions, tmp_path / "out", pool=pool)
    assert _files(tmp_path / "out") == alone[0]
    assert [solution_to_json(s) for s in written] == alone[1]
    # the helper's share was not empty: one of the two root-polynomial environments
    assert _share(solutions) == {1}


def test_a_helper_that_dies_is_replaced_by_this_process(solutions, alone, tmp_path):
    # The worker exits as it starts: every task sent to it fails with BrokenProcessPool.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(1, mp_context=context, initializer=os._exit, initargs=(3,)) as pool:
        written = write_solutions(solutions, tmp_path / "out", pool=pool)
    assert _files(tmp_path / "out") == alone[0]
    assert [solution_to_json(s) for s in written] == alone[1]


def test_solutions_streamed_to_a_helper_give_the_same_files_in_order(solutions, alone, tmp_path):
    """An iterator (solve's: solved as they are written) goes to the helper one by one and this
    process takes back the writes not started; a stand-in helper (a thread: no process start)
    and one that refuses every task give the files written alone, in order."""
    from concurrent.futures import ThreadPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    with ThreadPoolExecutor(1) as pool:
        written = write_solutions(iter(solutions), tmp_path / "out", pool=pool)
    assert _files(tmp_path / "out") == alone[0]
    assert [solution_to_json(s) for s in written] == alone[1]

    class Dead(ThreadPoolExecutor):
        def submit(self, *args, **kwargs):
            raise BrokenProcessPool("gone")

    with Dead(1) as pool:
        written = write_solutions(iter(solutions), tmp_path / "dead", pool=pool)
    assert _files(tmp_path / "dead") == alone[0]
    assert [solution_to_json(s) for s in written] == alone[1]


def test_an_input_error_in_the_helper_is_reported_and_nothing_is_written(solutions, tmp_path):
    # A root-polynomial Q that is all zeros has no inverse, yet the solution keeps its N: an
    # InputError in write_environment. It is the second root-polynomial environment: the
    # helper's share.
    model = solutions[1].correction
    zero = dataclasses.replace(
        model, coefficients=np.zeros_like(model.coefficients), fallback=np.zeros((3, 3))
    )
    bad = dataclasses.replace(solutions[1], post_correction=zero)
    broken = [solutions[0], bad, solutions[2]]
    assert _share(broken) == {1}
    with pytest.raises(InputError) as here:
        write_solutions(broken, tmp_path / "here")
    with writer_pool() as pool, pytest.raises(InputError) as helper:
        write_solutions(broken, tmp_path / "helper", pool=pool)
    assert str(helper.value) == str(here.value)
    assert "no inverse" in str(helper.value)
    for out in ("here", "helper"):  # all or nothing: no environment folder, no staging left
        assert not (tmp_path / out).exists() or not any((tmp_path / out).iterdir())


def test_an_environment_written_twice_is_refused_and_nothing_is_written(solutions, tmp_path):
    # demo and library callers reach the writer without solve's own check of --environment
    twice = [solutions[2], solutions[2]]
    for out, given in (("list", twice), ("stream", iter(twice))):
        with ThreadPoolExecutor(1) as pool, pytest.raises(InputError, match="more than once"):
            write_solutions(given, tmp_path / out, pool=pool)
        assert not (tmp_path / out).exists() or not any((tmp_path / out).iterdir())


def test_share_balances_the_bakes():
    # five root-polynomial environments (cost 1) and two 3x3 ones (cost 0.1), in any order
    kinds = [False, True, False, False, True, False, False]  # linear or not
    correction = dataclasses.make_dataclass("Correction", ["linear"])
    fake = [dataclasses.make_dataclass("S", ["correction"])(correction(k)) for k in kinds]
    helper = _share(fake)
    cost = [0.1 if k else 1.0 for k in kinds]
    mine = sum(cost[i] for i in helper)
    here = sum(cost) - mine
    # this process takes three bakes, the helper two and both cheap ones: 3.0 vs 2.2
    assert (here, round(mine, 6)) == (3.0, 2.2)


def test_no_pool_for_a_linear_method():
    # least squares never bakes LUTs: a helper would only cost its start-up
    with writer_pool("least-squares") as pool:
        assert pool is None
    with writer_pool("root-polynomial") as pool:
        assert pool is not None
    # one environment is written where it is solved: nothing to share
    with writer_pool("root-polynomial", environments=1) as pool:
        assert pool is None


def _lock_elsewhere(folder: Path) -> int:
    """Lock ``folder`` as another run's ``output_lock`` would (flock is per open file: a second
    descriptor conflicts with this process's own lock); BlockingIOError if a run holds it."""
    import fcntl

    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BaseException:
        os.close(fd)
        raise
    return fd


def test_a_streamed_write_locks_the_folder_only_to_publish(solutions, alone, tmp_path):
    """While solve streams its environments into the staging folder (solving the next), the
    output folder is not locked: another run (two --environment solves side by side) may
    publish into it meanwhile; the lock is taken to publish, and a run holding it then stops
    this one on one line with nothing published and no staging folder left."""
    from concurrent.futures import ThreadPoolExecutor

    out = tmp_path / "out"
    other = dataclasses.replace(solutions[2], environment="other_stage")

    def solving(out: Path, hold_at_the_end: list[int] | None = None):
        for i, solution in enumerate(solutions):
            yield solution
            staged = [p for p in out.iterdir() if p.name.startswith(".ocio-vp-staging-")]
            assert len(staged) == 1  # being written, unpublished
            fd = _lock_elsewhere(out)  # refused if this run held the lock while solving
            if hold_at_the_end is not None and i == len(solutions) - 1:
                hold_at_the_end.append(fd)  # another run is publishing as this one ends
                continue
            os.close(fd)
            if i == 0 and hold_at_the_end is None:  # another run writes and publishes now
                write_solutions([other], out)

    with ThreadPoolExecutor(1) as pool:
        written = write_solutions(solving(out), out, pool=pool)
    assert [solution_to_json(s) for s in written] == alone[1]
    assert {k: v for k, v in _files(out).items() if not k.startswith("other_stage")} == alone[0]
    assert (out / "other_stage" / "config.ocio").is_file()

    again, held = tmp_path / "again", []
    try:
        with ThreadPoolExecutor(1) as pool, pytest.raises(InputError, match="another ocio-vp"):
            write_solutions(solving(again, held), again, pool=pool)
    finally:
        for fd in held:
            os.close(fd)
    assert held and list(again.iterdir()) == []  # nothing published, no staging folder
