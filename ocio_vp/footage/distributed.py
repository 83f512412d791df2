"""Run independent tasks (frames, environments) in this process, a local pool, or on Dask.

No job system of our own: a local :class:`concurrent.futures.ProcessPoolExecutor` by default,
a Dask ``distributed`` cluster when a scheduler address (``tcp://host:8786``) is given. Tasks
must be picklable top-level functions with picklable arguments and results; results arrive in
completion order, each with the index of its item, so a caller can report progress as frames
finish. A task that raises does not stop the others: its exception is returned in its place.
See ``docs/distributed.md`` for how a render farm runs this.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import TYPE_CHECKING, Any, TypeVar

from ocio_vp.errors import InputError

if TYPE_CHECKING:
    from ocio_vp.formats.measurements import Environment, Measurements
    from ocio_vp.formats.solution import Solution
    from ocio_vp.pipeline import SolveOptions

__all__ = ["default_workers", "map_unordered", "solve_environments"]

T = TypeVar("T")
R = TypeVar("R")


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def _inline(func: Callable[[T], R], items: Sequence[T]) -> Iterator[tuple[int, R | BaseException]]:
    for i, item in enumerate(items):
        try:
            yield i, func(item)
        except Exception as exc:  # reported by the caller, the other items go on
            yield i, exc


def _local_pool(
    func: Callable[[T], R], items: Sequence[T], workers: int
) -> Iterator[tuple[int, R | BaseException]]:
    # "spawn": the parent has threads (tqdm, OCIO); forking a threaded process can deadlock.
    # At most 2 tasks per worker are in flight, so nothing grows with the number of items.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        pending: dict[Any, int] = {}
        todo = iter(enumerate(items))
        for i, item in todo:
            pending[pool.submit(func, item)] = i
            if len(pending) >= 2 * workers:
                break
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                i = pending.pop(future)
                exc = future.exception()
                yield i, exc if exc is not None else future.result()
                for j, item in todo:
                    pending[pool.submit(func, item)] = j
                    break


def _dask(
    func: Callable[[T], R], items: Sequence[T], scheduler: str
) -> Iterator[tuple[int, R | BaseException]]:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:  # pragma: no cover - dask is a dependency
        raise InputError("Dask distributed is not installed", key="--scheduler") from exc
    try:
        client = Client(scheduler, timeout="20s")
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot reach the Dask scheduler: {exc}", key="--scheduler") from exc
    try:
        # pure=False: a frame written twice must be written twice (resuming is our job).
        futures = client.map(func, list(items), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for future in as_completed(futures):
            failed = future.status == "error"
            yield index[future.key], future.exception() if failed else future.result()
            future.release()
    finally:
        client.close()


def map_unordered(
    func: Callable[[T], R],
    items: Iterable[T],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
) -> Iterator[tuple[int, R | BaseException]]:
    """Yield ``(index, func(item) or the exception it raised)`` as tasks finish.

    Parameters
    ----------
    func
        A picklable, top-level function.
    items
        Its arguments, one task each.
    workers
        Local processes (default: one per core); 1 runs in this process.
    scheduler
        A Dask scheduler address (``tcp://host:port``); when given, ``workers`` is ignored and
        the cluster's workers run the tasks.
    """
    items = list(items)
    if scheduler:
        if not scheduler.startswith(("tcp://", "tls://", "inproc://", "ws://", "wss://")):
            raise InputError(
                f"expected a scheduler address such as tcp://host:8786, got {scheduler!r}",
                key="--scheduler",
            )
        return _dask(func, items, scheduler)
    n = default_workers() if workers is None else int(workers)
    if n < 1:
        raise InputError(f"--workers must be >= 1, got {n}", key="--workers")
    n = min(n, max(1, len(items)))
    return _inline(func, items) if n == 1 else _local_pool(func, items, n)


def _solve_one(
    payload: tuple[Measurements, Environment, SolveOptions | None],
) -> Solution:
    from ocio_vp.pipeline import solve_environment

    measurements, environment, options = payload
    return solve_environment(measurements, environment, options)


def solve_environments(
    measurements: Measurements,
    environments: Sequence[Environment],
    options: SolveOptions | None = None,
    *,
    scheduler: str | None = None,
    workers: int | None = 1,
) -> list[Solution]:
    """:func:`ocio_vp.pipeline.solve_environment` for each environment with ``options`` (a
    :class:`ocio_vp.pipeline.SolveOptions`, None for the defaults), in their order, on a local
    pool or a Dask cluster (``scheduler``); the first failure is raised."""
    results: list[Any] = [None] * len(environments)
    payloads = [(measurements, env, options) for env in environments]
    for i, result in map_unordered(_solve_one, payloads, workers=workers, scheduler=scheduler):
        if isinstance(result, BaseException):
            raise result
        results[i] = result
    return results
