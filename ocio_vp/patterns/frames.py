"""Writing a sequence's frames and its ``sequence.yaml`` into a folder, all at once or not at all.

Each distinct picture is encoded once; every other frame showing it is a hard link to that file
(a copy where the file system has none). File formats and code values: docs/patterns.md.
"""

from __future__ import annotations

import errno
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np
import yaml

from ocio_vp.patterns.sequence import FILE_FORMATS, PatternSequence, expand_frame, sequence_to_dict

__all__ = ["SEQUENCE_FILE", "write_frame", "write_sequence_file", "write_sequence_folder"]

SEQUENCE_FILE = "sequence.yaml"
_OIIO_TYPE = {"exr": "half", "tiff": "uint16", "dpx": "uint16"}
_COMPRESSION = {"exr": "zip", "tiff": "lzw"}
_LINK_FAILURES = {errno.EXDEV, errno.EPERM, errno.EMLINK, errno.ENOTSUP, errno.EOPNOTSUPP}


def write_frame(
    path: str | Path, rgb: tuple[float, float, float], sequence: PatternSequence
) -> None:
    """One flat frame of ``rgb`` (drive for EXR, signal fraction for TIFF/DPX) at the
    sequence's size and file format.

    Raises
    ------
    OSError
        When OpenImageIO cannot write the file.
    """
    import OpenImageIO as oiio

    width, height = sequence.size
    spec = oiio.ImageSpec(width, height, 3, _OIIO_TYPE[sequence.file_format])
    spec.channelnames = ("R", "G", "B")
    if sequence.file_format in _COMPRESSION:
        spec.attribute("compression", _COMPRESSION[sequence.file_format])
    if sequence.file_format == "dpx":
        spec.attribute("oiio:BitsPerSample", FILE_FORMATS["dpx"])
    spec.attribute("Software", "ocio-vp patterns")
    row = np.tile(np.asarray(rgb, dtype=np.float32), (width, 1))
    out = oiio.ImageOutput.create(str(path))
    if out is None or not out.open(str(path), spec):
        raise OSError(f"{path}: cannot write: {oiio.geterror()}")
    try:
        band = max(1, min(height, (1 << 22) // (width * 3)))
        for y in range(0, height, band):
            rows = np.ascontiguousarray(np.broadcast_to(row, (min(band, height - y), width, 3)))
            if not out.write_scanlines(y, y + rows.shape[0], 0, rows):
                raise OSError(f"{path}: cannot write: {out.geterror()}")
    finally:
        out.close()


def _frame_values(sequence: PatternSequence) -> list[tuple[int, tuple[float, float, float]]]:
    """(frame, value written) for every frame, in order."""
    out = []
    for patch in sequence.patches:
        value = patch.drive if sequence.file_format == "exr" else patch.signal
        for frame in range(patch.first, patch.last + 1):
            lit = patch.kind != "sync" or any(a <= frame <= b for a, b in patch.flashes)
            out.append((frame, value if lit else (0.0, 0.0, 0.0)))
    return out


def _link_or_copy(source: Path, target: Path) -> None:
    try:
        os.link(source, target)
    except OSError as error:
        if error.errno not in _LINK_FAILURES:
            raise
        shutil.copyfile(source, target)


def write_sequence_file(sequence: PatternSequence, path: str | Path, *, note: str = "") -> None:
    """``sequence.yaml``: the ocio-vp signature line, a comment, then the document."""
    header = f"# Written by ocio-vp patterns (ocio-vp/patterns v1, docs/patterns.md){note}\n"
    text = yaml.safe_dump(
        sequence_to_dict(sequence), sort_keys=False, default_flow_style=None, width=100
    )
    Path(path).write_text(header + text, encoding="utf-8")


def write_sequence_folder(
    sequence: PatternSequence,
    folder: str | Path,
    *,
    frames: bool = True,
    on_frame: Callable[[], None] | None = None,
) -> Path:
    """Write every frame (one file per distinct picture, hard links for the rest) and
    ``sequence.yaml`` into ``folder`` (new or empty; callers stage it). Returns the yaml's path.
    ``frames=False`` writes ``sequence.yaml`` alone.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if frames:
        written: dict[tuple[float, float, float], Path] = {}
        for frame, value in _frame_values(sequence):
            target = folder / expand_frame(sequence.frames, frame)
            target.parent.mkdir(parents=True, exist_ok=True)
            if value in written:
                _link_or_copy(written[value], target)
            else:
                write_frame(target, value, sequence)
                written[value] = target
            if on_frame is not None:
                on_frame()
    path = folder / SEQUENCE_FILE
    write_sequence_file(sequence, path, note="" if frames else "; frames not written")
    return path
