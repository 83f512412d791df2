"""Write output folders all at once or not at all.

Files are written into a hidden staging folder beside the destination and renamed into place
only when everything succeeded, so a failure never leaves a half-written output folder.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ocio_vp.errors import InputError

__all__ = ["default_mode", "publish_dir", "staged_dir", "write_file_atomically"]


def default_mode(*, folder: bool = False) -> int:
    """The mode a plain ``open``/``mkdir`` would give under the current umask.

    :mod:`tempfile` creates private files (0600) and folders (0700); what we publish from them
    must look like any other output of the user's.
    """
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if folder else 0o666) & ~mask


@contextlib.contextmanager
def staged_dir(parent: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a fresh staging folder inside ``parent`` (created if needed); removed on exit.

    If ``parent`` did not exist and nothing was published into it, it is removed too.
    """
    parent = Path(parent)
    created = not parent.exists()
    if parent.exists() and not parent.is_dir():
        raise InputError("exists and is not a folder; choose another output folder", source=parent)
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"cannot create output folder: {error.strerror}", source=parent) from None
    stage = Path(tempfile.mkdtemp(prefix=".ocio-vp-staging-", dir=parent))
    try:
        stage.chmod(default_mode(folder=True))  # it may itself be published
        yield stage
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        if created and parent.exists() and not any(parent.iterdir()):
            parent.rmdir()


def publish_dir(staged: Path, final: Path) -> None:
    """Move a finished folder to ``final``, replacing an older one of the same name."""
    final = Path(final)
    if final.exists():
        old = final.with_name(f".{final.name}.old-{os.getpid()}")
        os.replace(final, old)
        os.replace(staged, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staged, final)


def write_file_atomically(path: str | os.PathLike[str], data: bytes | str) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    A file that is replaced keeps its mode; a new one gets the umask's default.
    """
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
