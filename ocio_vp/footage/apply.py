"""Post-correct footage with a solution's Q: OCIO CPU processor + OpenImageIO, frames in parallel.

The colour maths is the solution's own OCIO config, ``Stage Footage`` -> reference (Q, the
paper's post-correction, eq. 5, plus whatever that colorspace carries), run by OCIO's CPU
processor on float32 buffers in place (``apply(PackedImageDesc)``; ``applyRGB`` on a numpy
array is ~10x slower). Every other channel (alpha, depth, AOVs), every subimage, the metadata,
data and display windows, tiling, pixel formats and compression of each input are kept.

A frame is written under a temporary name and renamed when complete, so an interrupted run
never leaves a partial frame under its final name; a rerun skips the frames already written.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, Section 3.4, eq. 5.
https://doi.org/10.1145/3543664.3543699
"""

from __future__ import annotations

import functools
import itertools
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ocio_vp.errors import InputError

__all__ = [
    "OPTIMIZATIONS",
    "FrameResult",
    "FrameTask",
    "PostCorrection",
    "apply_file",
    "apply_in_place",
    "cpu_processor",
    "load_post_correction",
    "run_task",
]

#: OCIO optimisation levels by name (``benchmarks/bench_ocio_optim.py`` measures them).
OPTIMIZATIONS = ("lossless", "default", "good", "draft")


@dataclass(frozen=True)
class PostCorrection:
    """Which OCIO conversion post-corrects footage: ``source`` -> ``target`` in ``config``."""

    config: str
    source: str
    target: str
    environment: str = ""


def load_post_correction(solution_dir: str | Path) -> PostCorrection:
    """Read ``solution.json`` and its config; check that the named colorspaces exist."""
    import PyOpenColorIO as OCIO

    from ocio_vp.formats.solution import load_solution
    from ocio_vp.ocio.config import POST_CORRECTION_COLORSPACE, REFERENCE

    solution = load_solution(solution_dir)
    folder = Path(solution_dir)
    folder = folder if folder.is_dir() else folder.parent
    names = solution.ocio or {}
    config_path = (folder / names.get("config", "config.ocio")).resolve()
    source = names.get("post_correction_colorspace", POST_CORRECTION_COLORSPACE)
    target = names.get("reference", REFERENCE)
    try:
        config = OCIO.Config.CreateFromFile(str(config_path))
        config.getProcessor(source, target)
    except OCIO.Exception as exc:
        raise InputError(
            f"cannot build the post-correction: {exc}", source=str(config_path)
        ) from None
    return PostCorrection(str(config_path), source, target, solution.environment)


@functools.lru_cache(maxsize=8)
def cpu_processor(pc: PostCorrection, optimization: str = "default"):
    """The float32 CPU processor for ``pc`` (cached per process: workers build it once)."""
    import PyOpenColorIO as OCIO

    levels = {
        "lossless": OCIO.OPTIMIZATION_LOSSLESS,
        "default": OCIO.OPTIMIZATION_DEFAULT,
        "good": OCIO.OPTIMIZATION_GOOD,
        "draft": OCIO.OPTIMIZATION_DRAFT,
    }
    if optimization not in levels:
        raise ValueError(f"optimization must be one of {OPTIMIZATIONS}, got {optimization!r}")
    config = OCIO.Config.CreateFromFile(pc.config)
    processor = config.getProcessor(pc.source, pc.target)
    return processor.getOptimizedCPUProcessor(
        OCIO.BIT_DEPTH_F32, OCIO.BIT_DEPTH_F32, levels[optimization]
    )


_THREADS: dict[int, ThreadPoolExecutor] = {}


def _apply_rows(cpu, rgb: np.ndarray) -> None:
    import PyOpenColorIO as OCIO

    height, width = rgb.shape[:2]
    cpu.apply(OCIO.PackedImageDesc(rgb, width, height, 3))


def apply_in_place(
    cpu, pixels: np.ndarray, *, rgb: tuple[int, int, int] = (0, 1, 2), threads: int = 1
) -> np.ndarray:
    """Apply ``cpu`` to the RGB channels of a (height, width, channels) float32 image, in place.

    Other channels are not touched (not even through OCIO's alpha path, which turns alpha into
    NaN where RGB is infinite). A C-contiguous RGB image is processed with no copy; otherwise
    RGB is gathered into a scratch buffer and scattered back. ``threads`` > 1 splits the rows
    (OCIO releases the GIL while it works).

    Returns
    -------
    numpy.ndarray
        ``pixels``, modified.
    """
    if pixels.dtype != np.float32 or pixels.ndim != 3:
        raise ValueError(
            f"expected a (height, width, channels) float32 image, got {pixels.dtype} {pixels.shape}"
        )
    direct = pixels.shape[2] == 3 and tuple(rgb) == (0, 1, 2) and pixels.flags.c_contiguous
    work = pixels if direct else np.ascontiguousarray(pixels[..., list(rgb)])
    if threads <= 1 or work.shape[0] < 2 * threads:
        _apply_rows(cpu, work)
    else:
        pool = _THREADS.setdefault(threads, ThreadPoolExecutor(threads))
        bounds = np.linspace(0, work.shape[0], threads + 1).astype(int)
        jobs = [pool.submit(_apply_rows, cpu, work[a:b]) for a, b in itertools.pairwise(bounds)]
        for job in jobs:
            job.result()
    if not direct:
        pixels[..., list(rgb)] = work
    return pixels


def _rgb_channels(spec) -> tuple[int, int, int] | None:
    names = list(spec.channelnames)
    if all(c in names for c in "RGB"):
        return names.index("R"), names.index("G"), names.index("B")
    if len(names) >= 3 and not any("." in n for n in names[:3]):
        return 0, 1, 2  # unnamed (e.g. TIFF/DPX written without names): the first three
    return None


def _read_all(src: Path):
    """Every subimage of ``src`` as (spec, float32 pixels); InputError if unreadable."""
    import OpenImageIO as oiio

    if not src.is_file():
        raise InputError("no such frame", source=str(src))
    inp = oiio.ImageInput.open(str(src))
    if inp is None:
        raise InputError(f"cannot read the frame: {oiio.geterror()}", source=str(src))
    parts = []
    try:
        index = 0
        while inp.seek_subimage(index, 0):
            spec = oiio.ImageSpec(inp.spec())
            if spec.deep:
                raise InputError("deep images are not supported", source=str(src))
            pixels = inp.read_image(index, 0, 0, spec.nchannels, oiio.FLOAT)
            if pixels is None or inp.has_error:
                raise InputError(f"corrupt or truncated frame: {inp.geterror()}", source=str(src))
            pixels = np.asarray(pixels, dtype=np.float32)
            parts.append((spec, pixels.reshape(spec.height, spec.width, spec.nchannels)))
            index += 1
    finally:
        inp.close()
    return parts


def _write_all(dst: Path, parts) -> None:
    import OpenImageIO as oiio

    out = oiio.ImageOutput.create(str(dst))
    if out is None:
        raise OSError(f"{dst}: cannot write this format: {oiio.geterror()}")
    specs = [spec for spec, _ in parts]
    ok = out.open(str(dst), specs) if len(specs) > 1 else out.open(str(dst), specs[0])
    try:
        for index, (spec, pixels) in enumerate(parts):
            if index > 0:
                ok = ok and out.open(str(dst), spec, "AppendSubimage")
            ok = ok and out.write_image(pixels)
    finally:
        ok = out.close() and ok
    if not ok:
        raise OSError(f"{dst}: {out.geterror() or oiio.geterror()}")


def apply_file(src: str | Path, dst: str | Path, pc: PostCorrection, *, threads: int = 1) -> int:
    """Post-correct one frame file into ``dst`` (atomically); returns the RGB layers processed.

    Raises
    ------
    InputError
        Missing, unreadable, corrupt frame, or no subimage with RGB channels.
    OSError
        The output could not be written.
    """
    src, dst = Path(src), Path(dst)
    parts = _read_all(src)
    cpu = cpu_processor(pc)
    done = 0
    for spec, pixels in parts:
        rgb = _rgb_channels(spec)
        if rgb is not None:
            apply_in_place(cpu, pixels, rgb=rgb, threads=threads)
            spec.attribute(
                "ocio_vp:postCorrection", f"{pc.source} -> {pc.target} ({pc.environment})"
            )
            done += 1
    if done == 0:
        raise InputError("no R, G, B channels to post-correct", source=str(src))
    dst.parent.mkdir(parents=True, exist_ok=True)
    # Same folder (same file system) for an atomic rename; the extension picks the format.
    tmp = dst.with_name(f".{dst.stem}.partial-{os.getpid()}{dst.suffix}")
    try:
        _write_all(tmp, parts)
        os.replace(tmp, dst)
    finally:
        tmp.unlink(missing_ok=True)
    return done


@dataclass(frozen=True)
class FrameTask:
    """One frame to do: picklable, so it can go to a process pool or a Dask worker."""

    src: str
    dst: str
    post_correction: PostCorrection
    overwrite: bool = False
    threads: int = 1


@dataclass(frozen=True)
class FrameResult:
    """What happened to one frame: ``status`` is done, skipped, input-error or error."""

    src: str
    dst: str
    status: str
    message: str = ""
    seconds: float = 0.0


def run_task(task: FrameTask) -> FrameResult:
    """Do one :class:`FrameTask`, never raising: failures become a result."""
    start = time.perf_counter()
    if not task.overwrite and Path(task.dst).is_file():
        return FrameResult(task.src, task.dst, "skipped", "already written")
    try:
        import OpenImageIO as oiio

        # OpenEXR has its own thread pool besides OIIO's: cap both, so a task given one core
        # (a pool or Dask worker) uses one core and the workers do not oversubscribe the node.
        oiio.attribute("threads", max(1, task.threads))
        oiio.attribute("exr_threads", max(1, task.threads))
        apply_file(task.src, task.dst, task.post_correction, threads=task.threads)
    except InputError as exc:
        return FrameResult(task.src, task.dst, "input-error", str(exc))
    except Exception as exc:  # a write failure, out of disk...: report it, go on
        return FrameResult(task.src, task.dst, "error", f"{type(exc).__name__}: {exc}")
    return FrameResult(task.src, task.dst, "done", seconds=time.perf_counter() - start)
