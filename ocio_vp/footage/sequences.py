"""Frame sequences on the command line: ``plate.####.exr``, ``plate.%04d.exr`` or plain files.

A run of ``n`` ``#`` stands for an ``n``-digit, zero-padded frame number (Nuke's convention;
``plate.#.exr`` therefore matches ``plate.7.exr``, ``plate.10.exr``...), ``%0nd`` the same in
printf style and ``%d`` any unpadded number. Without a frame range a pattern expands to the
files that exist; with one (``first-last``) to every frame of the range, so a missing frame is
reported rather than silently skipped.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from pathlib import Path

from ocio_vp.errors import InputError, excerpt

__all__ = [
    "MARK",
    "SOLUTION_MARK",
    "expand_frames",
    "foreign_output_error",
    "foreign_output_reason",
    "foreign_outputs",
    "frame_pattern",
    "output_paths",
    "output_solution",
    "parse_frame_range",
]

_PATTERN = re.compile(r"#+|%0?(\d*)d")
#: Most frames one range may name (an hour at 24 fps is 86,400) and widest frame number field.
MAX_FRAMES = 1_000_000
MAX_PADDING = 16
#: The header attribute ``ocio-vp apply`` puts in every frame it writes (in each post-corrected
#: subimage): what tells its own earlier output from a file it must not replace.
MARK = "ocio_vp:postCorrection"
#: Header attribute naming the post-correction a frame was made with (stage, environment,
#: sha256 of its model, footage encoding): a rerun skips only frames made with the same one.
SOLUTION_MARK = "ocio_vp:solution"


def frame_pattern(text: str) -> tuple[str, str, int] | None:
    """Split ``text`` (a file name, no folder) into ``(prefix, suffix, padding)``, or None.

    Only one frame field per name is allowed; ``padding`` 0 means unpadded.
    """
    matches = list(_PATTERN.finditer(text))
    if not matches:
        return None
    if len(matches) > 1:
        raise InputError("more than one frame field (#, %0Nd) in the name", source=text)
    m = matches[0]
    if m.group(0).startswith("#"):
        padding = len(m.group(0))
        padding = 0 if padding == 1 else padding
    else:
        digits = m.group(1) or "0"
        padding = int(digits) if len(digits) <= 3 else MAX_PADDING + 1
    if padding > MAX_PADDING:
        raise InputError(
            f"a frame number field of more than {MAX_PADDING} digits", source=text[:100]
        )
    return text[: m.start()], text[m.end() :], padding


def parse_frame_range(text: str) -> range:
    """``"1001-1100"`` -> range(1001, 1101); a single number is a one-frame range."""
    m = re.fullmatch(r"\s*(-?\d{1,15})\s*(?:-\s*(-?\d{1,15})\s*)?", text)
    if not m:
        raise InputError(
            f"expected FIRST-LAST (whole numbers), got {excerpt(text)}", key="--frames"
        )
    first = int(m.group(1))
    last = int(m.group(2)) if m.group(2) is not None else first
    if last < first:
        raise InputError(f"the last frame {last} is before the first {first}", key="--frames")
    if last - first + 1 > MAX_FRAMES:
        raise InputError(f"{last - first + 1} frames; at most {MAX_FRAMES} per run", key="--frames")
    return range(first, last + 1)


def _format(prefix: str, suffix: str, padding: int, frame: int) -> str:
    return f"{prefix}{frame:0{padding}d}{suffix}" if padding else f"{prefix}{frame}{suffix}"


def expand_frames(args: Sequence[str], *, frames: range | None = None) -> list[Path]:
    """The input files named by ``args`` (patterns or plain paths), in order, without repeats.

    Raises
    ------
    InputError
        A pattern that matches no file (and no ``frames`` range was given), or a folder.
    """
    out: list[Path] = []
    seen: set[Path] = set()
    for arg in args:
        path = Path(arg)
        parts = frame_pattern(path.name)
        if parts is None:
            if path.is_dir():
                raise InputError(
                    "is a folder; name frames or a pattern such as plate.####.exr", source=arg
                )
            found = [path]
        else:
            prefix, suffix, padding = parts
            folder = path.parent
            if frames is not None:
                found = [folder / _format(prefix, suffix, padding, f) for f in frames]
            else:
                digits = r"-?\d+" if padding == 0 else rf"-?\d{{{padding},}}"
                regex = re.compile(re.escape(prefix) + f"({digits})" + re.escape(suffix))
                numbered = []
                if folder.is_dir():
                    for entry in folder.iterdir():
                        m = regex.fullmatch(entry.name)
                        if m and entry.is_file():
                            numbered.append((int(m.group(1)), entry))
                if not numbered:
                    raise InputError("no frames match this pattern", source=arg)
                found = [p for _, p in sorted(numbered)]
        for p in found:
            if p not in seen:
                seen.add(p)
                out.append(p)
    return out


def output_paths(inputs: Sequence[Path], out_dir: Path) -> list[Path]:
    """``out_dir / name`` for each input; two inputs with one name would overwrite each other."""
    if os.path.lexists(out_dir) and not Path(out_dir).is_dir():
        raise InputError("exists and is not a folder; choose another --out", source=out_dir)
    outputs = [Path(out_dir) / p.name for p in inputs]
    names: dict[Path, Path] = {}
    for src, dst in zip(inputs, outputs, strict=True):
        if dst in names:
            raise InputError(f"{names[dst]} and {src} would both be written to {dst}", key="FRAMES")
        names[dst] = src
        if src.resolve() == dst.resolve():
            raise InputError("--out would overwrite the input frame", source=str(src))
    return outputs


def foreign_output_reason(count: int = 1) -> str:
    """Why an output name taken by another file is refused (``count`` such files), one line."""
    more = f" (and {count - 1} more)" if count > 1 else ""
    return (
        f"exists and was not written by ocio-vp apply (no {MARK} in its header){more}: "
        "move it away or choose another --out"
    )


def foreign_output_error(dst: str | Path) -> str | None:
    """None when ``dst`` does not exist or ``ocio-vp apply`` wrote it; else the one-line reason
    a frame must not be written there nor counted as done (see :func:`foreign_outputs`)."""
    return f"{dst}: {foreign_output_reason()}" if foreign_outputs([Path(dst)]) else None


def _header_attribute(path: str | Path, name: str) -> object | None:
    """The header attribute ``name`` of the image file ``path`` (only the header is read);
    None when it has none or is not a file that can be read as an image."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(str(path)) if Path(path).is_file() else None
    if inp is None:
        oiio.geterror()  # a failed open leaves a message behind: the caller reports the file
        return None
    try:
        return inp.spec().getattribute(name)
    finally:
        inp.close()


def output_solution(path: str | Path) -> str | None:
    """The :data:`SOLUTION_MARK` of a frame ``ocio-vp apply`` wrote (None when it has none)."""
    value = _header_attribute(path, SOLUTION_MARK)
    return None if value is None else str(value)


def foreign_outputs(outputs: Sequence[Path]) -> list[Path]:
    """The existing files among ``outputs`` that ``ocio-vp apply`` did not write.

    A frame it wrote carries :data:`MARK` in its header; a file without it, or that cannot be
    read as an image, was put there by someone else, and neither ``--overwrite`` may replace it
    nor a rerun count it as done.
    """
    return [
        Path(path)
        for path in outputs
        if os.path.lexists(path) and _header_attribute(path, MARK) is None
    ]
