"""What every verb that takes solutions accepts: one vocabulary, one resolver.

``report``, ``export`` and ``apply`` all take the same things: an environment folder
(``OUT/<environment>/`` with its ``solution.json``), that ``solution.json`` itself, an
``ocio-vp solve`` output folder (meaning all its environments), or several of these (a shell
glob such as ``calib/*`` included). Things ocio-vp itself writes beside the environments (a
report folder, export folders, measurement files, overlays) are skipped with a note, so the same
command works again after it has written them; anything else that holds no solution is an error.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ocio_vp.choices import ENVIRONMENT_TARGETS
from ocio_vp.errors import InputError

__all__ = ["SolutionFolders", "generated_kind", "solution_folders"]

SOLUTION_FILE = "solution.json"
#: File formats of ours that may sit in a solve output folder (the demo writes one there).
_OUR_FORMATS = {"ocio-vp/measurements": "a measurements file", "ocio-vp/capture": "a capture file"}


@dataclass(frozen=True)
class SolutionFolders:
    """Environment folders named by the user, in order, without duplicates.

    ``solve_folders`` are the ``solve`` output folders they sit in (each once, in order);
    ``complete`` tells whether every environment of those folders is included; ``skipped``
    lists ``(path, what it is)`` for the generated things that were passed over.
    """

    folders: tuple[Path, ...]
    solve_folders: tuple[Path, ...]
    complete: bool
    skipped: tuple[tuple[Path, str], ...] = ()

    @property
    def environments(self) -> list[str]:
        return [folder.name for folder in self.folders]

    def notes(self) -> list[str]:
        """One line per skipped path, for the terminal."""
        return [f"skipped {path}: {kind}, not a solution" for path, kind in self.skipped]


def generated_kind(path: Path) -> str | None:
    """What ocio-vp output ``path`` is ('a report folder', ...), or None if it is none of ours."""
    if path.name.startswith(".ocio-vp-") or path.name.startswith(".ocio_vp"):
        return "an ocio-vp working folder"
    if path.is_dir():
        if (path / "index.html").is_file() and (path / "img").is_dir():
            return "a report folder"
        if path.name == "exports" or any((path / t).is_dir() for t in ENVIRONMENT_TARGETS):
            return "an export folder"
        if path.name.endswith(".overlays"):
            return "an overlay folder"
        if path.name == "show" and (path / "config.ocio").is_file():
            return "a show config folder"
        return None
    if path.is_file() and path.suffix.lower() in (".yaml", ".yml", ".json"):
        try:
            with path.open("rb") as handle:
                head = handle.read(4096).decode("utf-8", errors="replace")
        except OSError:
            return None
        for key, kind in _OUR_FORMATS.items():
            if key in head:
                return kind
    return None


def _environment_folders(path: Path) -> list[Path]:
    """The environment folders ``path`` names ([] when it holds no solution)."""
    if path.is_file():
        return [path.parent] if path.name == SOLUTION_FILE else []
    if (path / SOLUTION_FILE).is_file():
        return [path]
    if path.is_dir():
        return sorted(p.parent for p in path.glob(f"*/{SOLUTION_FILE}"))
    return []


def solution_folders(paths: Sequence[str | Path], *, key: str = "SOLUTION_DIR") -> SolutionFolders:
    """Resolve what the user named into environment folders (see the module docstring).

    Raises
    ------
    InputError
        A path that does not exist, one that holds no solution and is not something ocio-vp
        writes, or nothing to work on at all.
    """
    found: dict[Path, Path] = {}
    skipped: list[tuple[Path, str]] = []
    for raw in paths:
        path = Path(raw)
        if not path.exists():
            raise InputError("no such file or folder", source=path, key=key)
        folders = _environment_folders(path)
        if not folders:
            kind = generated_kind(path)
            if kind is None:
                raise InputError(
                    "no solution.json here or in its sub-folders (expected an environment "
                    "folder or an `ocio-vp solve` output folder); run `ocio-vp solve` first",
                    source=path,
                    key=key,
                )
            skipped.append((path, kind))
        for folder in folders:
            found.setdefault(folder.resolve(), folder)
    if not found:
        names = ", ".join(str(p) for p in paths)
        raise InputError(f"no solution among {names}", key=key)
    chosen = tuple(found.values())
    solve_folders = tuple(dict.fromkeys(f.resolve().parent for f in chosen))
    every = {p.parent.resolve() for s in solve_folders for p in s.glob(f"*/{SOLUTION_FILE}")}
    return SolutionFolders(chosen, solve_folders, every <= set(found), tuple(skipped))
