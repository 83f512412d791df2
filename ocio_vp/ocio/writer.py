"""Write solved environments to disk: ``OUT/<environment>/config.ocio`` and ``solution.json``.

All or nothing: every environment goes into a staging folder, renamed into place only when all
succeeded (:func:`write_solutions`). A non-linear environment bakes LUT chains, far costlier than
a 3x3: :func:`writer_pool` starts one helper process (numpy, OpenColorIO and this writer only)
that writes some environments while this process writes or solves the others; the files are
the same either way.
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing
import os
import shutil
import signal
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from ocio_vp.errors import InputError
from ocio_vp.formats.solution import Solution, solution_to_json
from ocio_vp.ocio.bake import model_outputs
from ocio_vp.ocio.config import config_data, ocio_names, write_config
from ocio_vp.ocio.description import build
from ocio_vp.ocio.panels import add_panel_spaces, panel_outputs
from ocio_vp.ocio.wall import wall_outputs
from ocio_vp.staging import output_lock, publish_dirs, staged_dir
from ocio_vp.wall.encoding import LUT_DIR

__all__ = ["write_environment", "write_solutions", "writer_pool"]


def write_environment(solution: Solution, directory: Path) -> Solution:
    """Write one environment's files into ``directory`` (which must exist).

    Returns the solution with its ``ocio`` block filled in, as written to ``solution.json``.
    """
    wall = wall_outputs(solution)  # panel-linearity LUT sidecar and wall signal encoding
    solution = dataclasses.replace(solution, ocio=ocio_names(), linearity=wall.linearity)
    luts = model_outputs(solution)  # a non-linear Q's LUT sidecars, else None
    files, search_path = dict(wall.files), wall.search_path
    if luts is not None:
        files.update(luts.files)
        search_path = LUT_DIR
        diagnostics = solution.diagnostics.adding(post_correction_ocio=luts.block)
        solution = dataclasses.replace(solution, diagnostics=diagnostics)
    # A stage's other panel types: their own colour spaces, LUTs and encodings (ocio/panels.py).
    panels = panel_outputs(solution, luts)
    if panels is not None:
        files.update(panels.files)
        search_path = LUT_DIR if files else search_path
        solution = dataclasses.replace(solution, panels=panels.panels)
    data = config_data(
        solution,
        extra_wall_transforms=wall.extra_wall_transforms,
        search_path=search_path,
        model=luts,
    )
    if panels is not None:
        add_panel_spaces(data, panels)
    config = build(data)
    for relative, text in files.items():
        (directory / relative).parent.mkdir(parents=True, exist_ok=True)
        (directory / relative).write_text(text, encoding="utf-8")
    write_config(config, directory)
    (directory / "solution.json").write_text(solution_to_json(solution), encoding="utf-8")
    return solution


def _ignore_interrupt() -> None:
    # Ctrl-C reaches every process of the terminal's group: the command reports it once.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _ready() -> bool:
    return True


@contextlib.contextmanager
def writer_pool(
    method: str | None = None, *, protect_emitters: bool = False, environments: int | None = None
) -> Iterator[Executor | None]:
    """One helper process for :func:`write_solutions` of solves by ``method``, started now;
    None for a linear method without ``protect_emitters`` (no environment bakes LUTs: the
    helper would cost more than it saves) and for fewer than two ``environments`` (one is
    written here). ``None``: any method, any number.

    Start it before loading and solving, so its imports overlap that work. "spawn", as for
    footage: the parent has threads (OpenColorIO, OpenBLAS) and forking them can deadlock.
    """
    # Deferred: the helper imports this module and needs none of the solvers.
    from ocio_vp.correction.registry import NON_LINEAR_METHODS

    linear = method is not None and method not in NON_LINEAR_METHODS and not protect_emitters
    if linear or (environments is not None and environments < 2):
        yield None
        return
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=1, mp_context=context, initializer=_ignore_interrupt)
    try:
        pool.submit(_ready)  # a pool starts its process at the first task: start it now
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _cost(solution: Solution) -> float:
    """Relative cost of writing ``solution`` (a non-linear Q bakes 3D LUTs)."""
    return 0.1 if solution.correction.linear else 1.0


def _share(solutions: Sequence[Solution]) -> set[int]:
    """Indices the helper writes: the costliest first, each to the side with less so far
    (this process first on a tie, as the helper may still be starting)."""
    here = helper = 0.0
    mine: set[int] = set()
    for i in sorted(range(len(solutions)), key=lambda i: -_cost(solutions[i])):
        if helper < here:
            helper += _cost(solutions[i])
            mine.add(i)
        else:
            here += _cost(solutions[i])
    return mine


def _write_into(stage: Path, solutions: Sequence[Solution], pool: Executor | None) -> list:
    """Write each solution into ``stage/<environment>``; the helper's share on ``pool``."""
    folders = [_environment_folder(stage, s) for s in solutions]
    futures: dict[int, Future] = {}
    written: list = [None] * len(solutions)
    with _helper_writes(pool, futures):  # an interrupt while submitting still waits
        if pool is not None and len(solutions) > 1:
            for i in sorted(_share(solutions)):
                try:
                    futures[i] = pool.submit(write_environment, solutions[i], folders[i])
                except (BrokenProcessPool, RuntimeError):  # the helper died: write it here
                    break
        for i, solution in enumerate(solutions):
            if i not in futures:
                written[i] = write_environment(solution, folders[i])
        for i, future in futures.items():
            written[i] = _helper_result(future, solutions[i], folders[i])
    return written


def _write_streamed(stage: Path, solutions: Iterator[Solution], pool: Executor) -> list:
    """Write each solution into ``stage/<environment>`` as ``solutions`` yields it (it may solve
    them on the way): each goes to the helper once the next one has come, and the helper writes
    while this process solves; the last is written here, and then this process takes back,
    from the last, every write the helper has not started, so both finish together (the
    helper's queue takes two at once: the last one kept here is what this process writes even
    when there are only two). In order."""
    todo: list[tuple[Solution, Path]] = []
    futures: dict[int, Future] = {}
    written: list = []
    with _helper_writes(pool, futures):
        for solution in solutions:
            folder = _environment_folder(stage, solution)
            todo.append((solution, folder))
            written.append(None)
            if len(todo) > 1:  # one behind: the latest may be the last, written here
                try:
                    futures[len(todo) - 2] = pool.submit(write_environment, *todo[-2])
                except (BrokenProcessPool, RuntimeError):  # the helper died: written below
                    pass
        for i, (solution, folder) in enumerate(todo):  # the last, and any the helper refused
            if i not in futures:
                written[i] = write_environment(solution, folder)
        for i in sorted(futures, reverse=True):  # one at a time: both meet in the middle
            if not futures[i].cancel():
                break  # the helper has it (and every one before it)
            del futures[i]
            written[i] = write_environment(*todo[i])
        for i, future in futures.items():
            written[i] = _helper_result(future, *todo[i])
    return written


@contextlib.contextmanager
def _helper_writes(pool: Executor | None, futures: dict[int, Future]) -> Iterator[None]:
    """Around writes of which ``futures`` (filled inside) run on ``pool``'s helper: a stop
    (Ctrl-C, kill) ends the helper without waiting for its bake, and whatever the exit, nothing
    is still writing into the staging folder when it is removed."""
    try:
        yield
    except KeyboardInterrupt:
        _stop_helper(pool)
        raise
    finally:
        for future in futures.values():
            future.cancel()
        wait(list(futures.values()))


def _environment_folder(stage: Path, solution: Solution) -> Path:
    """``stage/<environment>``, made (the staging folder is new: a folder already there is an
    environment written twice, refused)."""
    folder = stage / solution.environment
    try:
        folder.mkdir()
    except FileExistsError:
        raise InputError(f"environment {solution.environment!r} is given more than once") from None
    return folder


def _helper_result(future: Future, solution: Solution, folder: Path) -> Solution:
    """What the helper wrote; written again here if it crashed (or its error does not survive
    between processes), where the same error, if any, is raised as itself."""
    try:
        return future.result()
    except InputError:
        raise
    except Exception:
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir()
        return write_environment(solution, folder)


def _stop_helper(pool: Executor | None) -> None:
    """End the helper process of ``pool`` now (its futures fail; the pool is broken)."""
    for process in list((getattr(pool, "_processes", None) or {}).values()):
        process.terminate()
        process.join(5)


def write_solutions(
    solutions: Iterable[Solution],
    out_dir: str | Path,
    *,
    inputs: Iterable[str | os.PathLike[str]] = (),
    pool: Executor | None = None,
) -> list[Solution]:
    """Write every solution to ``out_dir/<environment>/``, all or nothing.

    An existing environment folder is replaced only if ocio-vp wrote it and it holds nothing
    else, and none may be one of ``inputs`` (see :mod:`ocio_vp.staging`). With ``pool`` (see
    :func:`writer_pool`) its process writes some of the environments: shared by their cost for
    a sequence; for an iterator (solving as it goes), each as it comes while this process
    solves the next, this process taking back the last ones (:func:`_write_streamed`).
    """
    out_dir = Path(out_dir)
    # Locked only to publish: another run may publish into out_dir while these are solved and
    # written (and it is refused at once only while this run publishes).
    with staged_dir(out_dir, locked=False) as stage:
        if pool is not None and not isinstance(solutions, Sequence):
            written = _write_streamed(stage, iter(solutions), pool)
        else:
            written = _write_into(stage, list(solutions), pool)
        pairs = [(stage / s.environment, out_dir / s.environment) for s in written]
        with output_lock(out_dir):
            publish_dirs(pairs, inputs=inputs)
    return written
