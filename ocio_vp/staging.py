"""Write outputs all at once or not at all, never over an input or a file ocio-vp did not write.

- Files are written into a hidden staging folder beside the destination and renamed into place
  only when everything succeeded.
- Every folder ocio-vp publishes carries :data:`MARKER`, listing the files it wrote; an existing
  folder is replaced only if it is empty or holds nothing else.
- A single output file is replaced only if it starts with :data:`FILE_SIGNATURE` or already
  holds the same bytes; no output may be, or contain, an input (:func:`check_not_input`).
- A run holds an exclusive lock on the folder it writes into (a second run fails at once);
  ``solve`` and ``demo`` only while they publish (their staging folder fills as they solve).
- A stopped run (Ctrl-C, ``kill``, ``timeout``, a CPU-time limit) removes its staging folders
  (:func:`stop_on_signals`, and ``atexit``).
"""

from __future__ import annotations

import atexit
import contextlib
import os
import secrets
import shutil
import signal
import stat
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

from ocio_vp.errors import InputError

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no locking
    fcntl = None  # type: ignore[assignment]

__all__ = [
    "FILE_SIGNATURE",
    "MARKER",
    "Interrupted",
    "check_file_replaceable",
    "check_not_input",
    "check_replaceable",
    "default_mode",
    "output_lock",
    "publish_dir",
    "publish_dirs",
    "staged_dir",
    "stop_on_signals",
    "write_file_atomically",
    "write_output_file",
]

#: Marker file in every folder ocio-vp publishes: the list of files it wrote there.
MARKER = ".ocio-vp-output"
_MARKER_HEADER = (
    "# Written by ocio-vp. A later ocio-vp run may replace this folder as long as it holds\n"
    "# only the files listed here; anything else in it makes ocio-vp refuse.\n"
)
#: First line of a YAML file ocio-vp writes; such a file may be replaced by a later run.
FILE_SIGNATURE = b"# Written by ocio-vp"
_MOVE_HINT = "move it away or choose another output"


def default_mode(*, folder: bool = False) -> int:
    """The mode a plain ``open``/``mkdir`` would give under the current umask (not
    :mod:`tempfile`'s private one)."""
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if folder else 0o666) & ~mask


# Locks held by this process: folder -> (descriptor, depth), so nested use is fine.
_LOCKS: dict[str, tuple[int, int]] = {}


@contextlib.contextmanager
def output_lock(folder: str | os.PathLike[str]) -> Iterator[None]:
    """Hold an exclusive lock on the existing ``folder`` while writing into it; an InputError
    at once when another process holds it."""
    key = os.path.realpath(folder)
    fd, depth = _LOCKS.get(key, (-1, 0))
    busy = "another ocio-vp run is writing into this folder; wait for it to finish"
    if fcntl is not None and depth == 0:
        try:
            fd = os.open(key, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        except OSError:  # removed since it was made: by another run that gave it up
            raise InputError(busy, source=folder) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            # The lock is on the folder opened above: if another run removed (or replaced) the
            # folder meanwhile, the lock guards nothing that anyone else will write into.
            if not os.path.samestat(os.fstat(fd), os.stat(key)):
                raise OSError("replaced")
        except OSError:
            os.close(fd)
            raise InputError(busy, source=folder) from None
    _LOCKS[key] = (fd, depth + 1)
    try:
        yield
    finally:
        fd, depth = _LOCKS.pop(key)
        if depth > 1:
            _LOCKS[key] = (fd, depth - 1)
        elif fd >= 0:
            os.close(fd)  # closing the descriptor releases the flock


def _make_dirs(folder: Path) -> list[Path]:
    """Create ``folder`` and missing parents; return the ones created, deepest first."""
    missing = [p for p in (folder, *folder.parents) if not os.path.lexists(p)]
    created: list[Path] = []
    for path in reversed(missing):
        try:
            path.mkdir()
        except FileExistsError:  # another run made it meanwhile: it is not ours to remove
            if not path.is_dir():
                _remove_empty(reversed(created))
                raise InputError(f"exists and is not a folder; {_MOVE_HINT}", source=path) from None
            continue
        except OSError as error:
            _remove_empty(reversed(created))
            raise InputError(
                f"cannot create output folder: {error.strerror}", source=path
            ) from None
        created.append(path)
    return created[::-1]


def _remove_empty(folders: Iterable[Path]) -> None:
    for folder in folders:
        with contextlib.suppress(OSError):
            folder.rmdir()


class Interrupted(KeyboardInterrupt):
    """The run was stopped by signal ``signum`` (a KeyboardInterrupt, so that no ``except
    Exception`` swallows it): the command exits with status 128 + ``signum``."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


#: Signals that stop a run: Ctrl-C, ``kill`` and ``timeout``, a closed terminal, ``ulimit -t``.
STOP_SIGNALS = tuple(
    getattr(signal, name)
    for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGXCPU")
    if hasattr(signal, name)
)


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Within this block a stop signal raises :class:`Interrupted` in the main thread, once
    (later ones cannot cut the clean-up short); nothing outside the main thread."""
    stopping: list[int] = []

    def handler(signum: int, frame: object) -> None:
        if not stopping:
            stopping.append(signum)
            raise Interrupted(signum)

    previous = {}
    try:
        for signum in STOP_SIGNALS:
            previous[signum] = signal.signal(signum, handler)
    except ValueError:  # not the main thread
        pass
    try:
        yield
    finally:
        for signum, old in previous.items():
            signal.signal(signum, old)


# Staging folders of this process that are not removed yet: what atexit still removes.
_LIVE_STAGES: set[Path] = set()


@atexit.register
def _remove_live_stages() -> None:
    for stage in list(_LIVE_STAGES):
        shutil.rmtree(stage, ignore_errors=True)
        _LIVE_STAGES.discard(stage)


@contextlib.contextmanager
def staged_dir(parent: str | os.PathLike[str], *, locked: bool = True) -> Iterator[Path]:
    """Yield a fresh staging folder inside ``parent`` (created if needed, and locked meanwhile
    unless not ``locked``); removed on exit, with the folders this call created if still empty.

    Unlocked, the caller takes :func:`output_lock` only to publish, so that other runs may
    publish into ``parent`` while it fills its staging folder (solve writes each environment
    as it solves the next: minutes)."""
    parent = Path(parent)
    if os.path.lexists(parent) and not parent.is_dir():
        raise InputError(f"exists and is not a folder; {_MOVE_HINT}", source=parent)
    created = _make_dirs(parent)
    with output_lock(parent) if locked else contextlib.nullcontext():
        # Named and registered before it exists: a stop signal arriving just as the folder
        # is made still finds it (mkdtemp's name would be lost if it came before returning).
        stage = parent / f".ocio-vp-staging-{os.getpid()}-{secrets.token_hex(6)}"
        _LIVE_STAGES.add(stage)
        try:
            if not _make_stage(stage, parent_may_go=not locked):
                # Unlocked, the run that made ``parent`` may have removed it (once empty, under
                # its lock) since it was found: made again.
                created = _make_dirs(parent)
                _make_stage(stage)
            yield stage
        finally:
            shutil.rmtree(stage, ignore_errors=True)
            if not os.path.lexists(stage):  # else a straggler wrote into it: atexit
                _LIVE_STAGES.discard(stage)
            # Folders this call created are removed only under the lock (held here, or taken
            # if free): a run that finds the folder locked leaves it to the run that holds it
            # (removing it under that run made its staging folder fail, and a third run could
            # then lock a new folder of the same name).
            if created:
                with contextlib.suppress(InputError), output_lock(created[0]):
                    _remove_empty(created)


def _make_stage(stage: Path, *, parent_may_go: bool = False) -> bool:
    """Make the staging folder ``stage``; False if its parent is gone and ``parent_may_go``."""
    try:
        stage.mkdir(mode=0o700)
    except OSError as error:
        if parent_may_go and isinstance(error, FileNotFoundError):
            return False
        raise InputError(f"cannot write: {error.strerror}", source=stage.parent) from None
    stage.chmod(default_mode(folder=True))  # it may itself be published
    return True


def _files(folder: Path) -> list[str]:
    """Relative POSIX paths of every non-folder entry under ``folder``, sorted."""
    out = []
    for root, dirs, names in os.walk(folder):
        dirs.sort()
        for name in names + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
            out.append(Path(root, name).relative_to(folder).as_posix())
    return sorted(out)


def _nested_outputs(final: Path, present: list[str]) -> set[str]:
    """Files of ocio-vp output folders published inside ``final`` after it (an environment's
    ``exports/<target>/`` or ``report/``): each carries its own marker listing them."""
    owned: set[str] = set()
    for name in present:
        if name.rpartition("/")[2] != MARKER or "/" not in name:
            continue
        folder = name.rpartition("/")[0]
        try:
            lines = (final / name).read_text("utf-8").splitlines()
        except (OSError, UnicodeDecodeError):
            continue
        owned |= {f"{folder}/{line}" for line in lines if line and not line.startswith("#")}
        owned.add(name)
    return owned


def check_replaceable(final: str | os.PathLike[str]) -> None:
    """Raise :class:`InputError` unless ``final`` is absent, empty or an ocio-vp output folder
    holding nothing but the files its :data:`MARKER` lists."""
    final = Path(final)
    if not os.path.lexists(final):
        return
    if final.is_symlink() or not final.is_dir():
        raise InputError(f"exists and is not a folder ocio-vp wrote; {_MOVE_HINT}", source=final)
    present = _files(final)
    if not present:
        return
    try:
        lines = (final / MARKER).read_text("utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        raise InputError(
            f"exists and was not written by ocio-vp (no {MARKER} file); {_MOVE_HINT}",
            source=final,
        ) from None
    listed = {line for line in lines if line and not line.startswith("#")} | {MARKER}
    listed |= _nested_outputs(final, present)
    foreign = [name for name in present if name not in listed]
    if foreign:
        more = f" and {len(foreign) - 1} more" if len(foreign) > 1 else ""
        raise InputError(
            f"holds {foreign[0]!r}{more}, which ocio-vp did not write; move it out so the "
            "folder can be replaced, or choose another output",
            source=final,
        )


def check_not_input(
    outputs: Iterable[str | os.PathLike[str]], inputs: Iterable[str | os.PathLike[str]]
) -> None:
    """Refuse an output that is an input, contains one, or lies inside an input file."""
    real_inputs = [(Path(p), Path(os.path.realpath(p))) for p in inputs if p is not None]
    for output in outputs:
        real = Path(os.path.realpath(output))
        for given, source in real_inputs:
            if real == source:
                problem = "is also an input of this run"
            elif source.is_relative_to(real):
                problem = f"contains an input of this run ({given.name})"
            elif real.is_relative_to(source) and not source.is_dir():
                problem = f"lies inside an input file ({given.name})"
            else:
                continue
            raise InputError(
                f"{problem}; choose another output so no input is replaced", source=output
            )


def publish_dirs(
    pairs: Sequence[tuple[Path, Path]], *, inputs: Iterable[str | os.PathLike[str]] = ()
) -> None:
    """Move staged folders (each given its :data:`MARKER`) to their final places, after
    checking every one is replaceable and no input."""
    check_not_input([final for _, final in pairs], inputs)
    for _, final in pairs:
        check_replaceable(final)
    for staged, final in pairs:
        staged, final = Path(staged), Path(final)
        listed = [name for name in _files(staged) if name != MARKER]
        (staged / MARKER).write_text(_MARKER_HEADER + "".join(f"{n}\n" for n in listed), "utf-8")
        _replace_keeping_nested(staged, final)


def _nested_folders(final: Path) -> list[str]:
    """Top-most output folders published inside ``final`` after it (``exports/unreal``,
    ``report``: each has its own :data:`MARKER`)."""
    if not final.is_dir() or final.is_symlink():
        return []
    found: list[str] = []
    for marker in sorted(final.rglob(MARKER)):
        folder = marker.parent.relative_to(final).as_posix()
        if folder != "." and not any(folder.startswith(f + "/") for f in found):
            found.append(folder)
    return found


def _replace_keeping_nested(staged: Path, final: Path) -> None:
    """Replace ``final`` by ``staged``, carrying over the nested output folders of ``final``
    that ``staged`` does not have (an environment's exports and report survive a re-solve:
    :mod:`ocio_vp.formats.provenance` names the stale ones)."""
    moved = []
    try:
        for folder in _nested_folders(final):
            if not os.path.lexists(staged / folder):
                (staged / folder).parent.mkdir(parents=True, exist_ok=True)
                os.replace(final / folder, staged / folder)
                moved.append(folder)
        _replace_dir(staged, final)
    except BaseException:
        for folder in moved:  # put them back where they were
            with contextlib.suppress(OSError):
                (final / folder).parent.mkdir(parents=True, exist_ok=True)
                os.replace(staged / folder, final / folder)
        raise


def publish_dir(
    staged: Path, final: Path, *, inputs: Iterable[str | os.PathLike[str]] = ()
) -> None:
    """Move one finished folder to ``final`` (see :func:`publish_dirs`)."""
    publish_dirs([(staged, final)], inputs=inputs)


def _replace_dir(staged: Path, final: Path) -> None:
    if os.path.lexists(final):
        old = final.with_name(f".{final.name}.old-{os.getpid()}")
        os.replace(final, old)
        try:
            os.replace(staged, final)
        except BaseException:
            os.replace(old, final)  # put the previous output back
            raise
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staged, final)


def check_file_replaceable(path: str | os.PathLike[str], data: bytes | None = None) -> None:
    """Raise unless ``path`` is absent, a file ocio-vp wrote, or already holds ``data``."""
    path = Path(path)
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    except OSError as error:
        raise InputError(f"cannot check: {error.strerror}", source=path) from None
    if stat.S_ISREG(info.st_mode):
        with contextlib.suppress(OSError), open(path, "rb") as handle:
            head = handle.read(max(len(FILE_SIGNATURE), len(data or b"") + 1))
            if head.startswith(FILE_SIGNATURE) or (data is not None and head == data):
                return
    kind = "file" if stat.S_ISREG(info.st_mode) else "file system entry"
    raise InputError(f"is a {kind} ocio-vp did not write; {_MOVE_HINT}", source=path)


def write_output_file(
    path: str | os.PathLike[str], data: bytes | str, *, replace: bool = False
) -> None:
    """:func:`write_file_atomically`, refusing to replace a file ocio-vp did not write unless
    ``replace``."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    if not replace:
        check_file_replaceable(path, raw)
    parent = Path(path).parent
    created = _make_dirs(parent)
    with output_lock(parent):  # created folders removed under the lock (see staged_dir)
        try:
            if not replace:
                check_file_replaceable(path, raw)
            write_file_atomically(path, raw)
        except BaseException:
            _remove_empty(created)
            raise


def write_file_atomically(path: str | os.PathLike[str], data: bytes | str) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename, keeping a replaced
    file's mode."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        mode = path.stat().st_mode & 0o7777
    except OSError:
        mode = default_mode()
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.chmod(tmp, mode)
        with os.fdopen(fd, "wb") as handle:
            handle.write(data.encode("utf-8") if isinstance(data, str) else data)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
