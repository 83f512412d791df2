"""Post-correct footage with a solution's Q: OCIO CPU processor + OpenImageIO, frames in parallel.

The colour maths is the solution's own OCIO config, ``Stage Footage`` -> reference (Q, the
paper's post-correction, eq. 5, plus whatever that colorspace carries), run by OCIO's CPU
processor in place through the pluggable :class:`PixelTransform` (:data:`TRANSFORMS`); a
non-linear Q is applied exactly instead (:class:`ModelTransform`). Every other channel, every
subimage, the metadata, data and display windows, tiling, pixel formats and compression of
each input are kept. Pixels stay in the file's own type when a subimage is uniformly half or
float (OCIO converts half itself, rounding as storing a float32 result as half does); other
files are read as float32 and stored back in their types. Frames are written atomically and a
rerun skips those already written (docs/distributed.md).

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, Section 3.4, eq. 5.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import json
import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ocio_vp.choices import OPTIMIZATIONS  # OCIO optimisation levels (bench_ocio_optim)
from ocio_vp.deprecation import deprecated_names
from ocio_vp.errors import InputError
from ocio_vp.footage.sequences import MARK, SOLUTION_MARK, foreign_output_error, output_solution
from ocio_vp.model.correction import correction_from_dict, correction_to_dict

__all__ = [
    "OPTIMIZATIONS",
    "TRANSFORMS",
    "VIA",
    "EncodedTransform",
    "FrameResult",
    "FrameTask",
    "ModelTransform",
    "OcioTransform",
    "PixelTransform",
    "PostCorrection",
    "apply_file",
    "apply_in_place",
    "cpu_processor",
    "existing_output",
    "frame_failure",
    "load_frame",
    "load_post_correction",
    "load_task",
    "other_solution_reason",
    "pixel_transform",
    "run_task",
    "set_io_threads",
    "solution_identity",
    "store_frame",
    "store_task",
    "transform_frame",
    "write_failure",
]


@dataclass(frozen=True)
class PostCorrection:
    """Which OCIO conversion post-corrects footage: ``source`` -> ``target`` in ``config``.

    ``kind`` names the :data:`TRANSFORMS` factory that turns it into a :class:`PixelTransform`;
    ``model`` is a non-linear post-correction's ``post_correction`` block as JSON text (kind
    ``model``: :mod:`ocio_vp.model`, applied exactly), so that this stays hashable and
    picklable. ``encoding`` is the footage's encoding (kind ``encoded``: decoded, corrected
    and encoded again; a colour-science decoding name), ``solution`` the text that identifies
    the post-correction in every frame written (:data:`SOLUTION_MARK`).
    """

    config: str
    source: str
    target: str
    environment: str = ""
    kind: str = "ocio"
    model: str = ""
    encoding: str = ""
    solution: str = ""


#: How ``apply`` computes a non-linear Q: its exact ``model`` (default) or the solution's
#: ``config`` (the OCIO chain every host runs: LUT bakes of the model, their agreement with
#: it recorded in ``solution.json``). A 3x3 Q is the config's matrix either way.
VIA = ("model", "config")


def load_post_correction(
    solution_dir: str | Path, encoding: str = "", *, via: str = "model"
) -> PostCorrection:
    """Read ``solution.json`` and its config; check that the named colorspaces exist.

    ``encoding``: the footage's encoding (a colour-science decoding name, ``linear`` or ``""``
    for linear footage). ``via``: see :data:`VIA`."""
    if encoding == "linear":
        encoding = ""
    if via not in VIA:
        raise InputError(f"expected one of {', '.join(VIA)}, got {via!r}", key="--via")
    if via == "config" and encoding:
        raise InputError(
            "the config's chain takes linear footage; encoded footage is corrected with the "
            "model (leave --via out)",
            key="--via",
        )
    import PyOpenColorIO as OCIO

    from ocio_vp.formats.solution import load_solution

    solution = load_solution(solution_dir)
    folder = Path(solution_dir)
    folder = folder if folder.is_dir() else folder.parent
    names = solution.ocio
    source, target = names.post_correction_colorspace, names.reference
    if source is None or target is None:
        # Deferred: the ocio package pulls in the wall's encodings (scipy: costly at start-up)
        # and solution.json names both colorspaces; only files without them need the defaults.
        from ocio_vp.ocio.config import POST_CORRECTION_COLORSPACE, REFERENCE

        source, target = source or POST_CORRECTION_COLORSPACE, target or REFERENCE
    config_path = (folder / names.config_file).resolve()
    try:
        config = OCIO.Config.CreateFromFile(str(config_path))
        config.getProcessor(source, target)
    except OCIO.Exception as exc:
        raise InputError(
            f"cannot build the post-correction: {exc}", source=str(config_path)
        ) from None
    model = json.dumps(correction_to_dict(solution.correction), sort_keys=True)
    identity = solution_identity(solution.stage, solution.environment, model, encoding)
    kind = "model"  # the exact model, not the config's LUT bake of it
    if encoding:  # decode, the exact post-correction, encode
        kind, source, target = "encoded", f"{source} ({encoding})", f"{target} ({encoding})"
    elif solution.correction.linear:
        kind = "ocio"
    elif via == "config":  # the config's LUT chains: the same pixels as every host, not the model
        kind, identity = "ocio", f"{identity}, via config"
    return PostCorrection(
        str(config_path),
        source,
        target,
        solution.environment,
        kind,
        model if kind != "ocio" else "",
        encoding,
        identity,
    )


def solution_identity(stage: str, environment: str, model: str, encoding: str = "") -> str:
    """The text stored in each frame (:data:`SOLUTION_MARK`): which stage, environment and
    post-correction (sha256 of its ``post_correction`` block) made it, and the encoding."""
    digest = hashlib.sha256(model.encode("utf-8")).hexdigest()[:16]
    text = f"{stage}/{environment} post-correction sha256:{digest}"
    return f"{text}, footage {encoding}" if encoding else text


@functools.lru_cache(maxsize=8)
def cpu_processor(pc: PostCorrection, optimization: str = "default", bit_depth: str = "f32"):
    """The CPU processor for ``pc`` on ``bit_depth`` (``f32`` or ``f16``) buffers, in and out.

    Cached per process, so workers build it once.
    """
    import PyOpenColorIO as OCIO

    if optimization not in OPTIMIZATIONS:
        raise ValueError(f"optimization must be one of {OPTIMIZATIONS}, got {optimization!r}")
    depth = {"f32": OCIO.BIT_DEPTH_F32, "f16": OCIO.BIT_DEPTH_F16}[bit_depth]
    config = OCIO.Config.CreateFromFile(pc.config)
    processor = config.getProcessor(pc.source, pc.target)
    level = getattr(OCIO, f"OPTIMIZATION_{optimization.upper()}")
    return processor.getOptimizedCPUProcessor(depth, depth, level)


class PixelTransform(Protocol):
    """What ``apply`` runs on every pixel: called on a C-contiguous (h, w, 3) RGB array of
    float32 or float16 (OpenEXR half), which it modifies in place. It may be called from several
    threads at once on different rows."""

    def __call__(self, rgb: np.ndarray) -> None: ...


@dataclass(frozen=True)
class OcioTransform:
    """A :class:`PixelTransform` running OCIO CPU processors: ``f32`` for float32 buffers and
    ``f16`` for half ones (OCIO converts half to float32 and back itself, with the same
    round-to-nearest-even as a float32 result stored as half, so the output is bitwise the same
    as converting, transforming in float32 and converting back, at a third of the memory
    traffic)."""

    f32: Any
    f16: Any = None

    def __call__(self, rgb: np.ndarray) -> None:
        import PyOpenColorIO as OCIO

        height, width = rgb.shape[:2]
        if rgb.dtype == np.float16 and self.f16 is not None:
            desc = OCIO.PackedImageDesc(rgb, width, height, 3, OCIO.BIT_DEPTH_F16, 2, 6, 6 * width)
            self.f16.apply(desc)
        elif rgb.dtype == np.float16:  # no half processor: through a float32 copy
            work = rgb.astype(np.float32)
            self.f32.apply(OCIO.PackedImageDesc(work, width, height, 3))
            rgb[...] = work
        else:
            self.f32.apply(OCIO.PackedImageDesc(rgb, width, height, 3))


@dataclass(frozen=True)
class ModelTransform:
    """A :class:`PixelTransform` applying a non-linear post-correction exactly: the model's
    formulas (:mod:`ocio_vp.model.correction`) by :func:`ocio_vp.model.pixels.pixel_function`,
    on bands of :attr:`band` pixels copied into planes; half buffers are computed in float32,
    float32 ones in float64, and stored back in the buffer's own type (a half overflow becomes
    inf, as OCIO's half output does). Accuracy: docs/root_polynomial.md ("the exact model").
    """

    correction: Any
    band: int = 1 << 14

    @functools.cached_property
    def functions(self) -> dict[Any, tuple[Any, Callable[[np.ndarray], np.ndarray]]]:
        """Buffer type -> (arithmetic type, the pixel function in it)."""
        from ocio_vp.model.pixels import pixel_function

        return {
            np.dtype(np.float16): (np.float32, pixel_function(self.correction, np.float32)),
            np.dtype(np.float32): (np.float64, pixel_function(self.correction, np.float64)),
        }

    def __call__(self, rgb: np.ndarray) -> None:
        arithmetic, f = self.functions[rgb.dtype]
        planes = np.empty((3, min(self.band, rgb.size // 3)), dtype=arithmetic)

        def step(block: np.ndarray) -> None:
            X = planes[:, : len(block)]
            for k in range(3):
                np.copyto(X[k], block[:, k])
            out = f(X)
            with np.errstate(over="ignore"):  # half overflow: inf, as documented
                for k in range(3):
                    np.copyto(block[:, k], out[k], casting="same_kind")

        _in_bands(rgb, self.band, step)


def _in_bands(rgb: np.ndarray, band: int, step: Callable[[np.ndarray], None]) -> None:
    """Run ``step`` on (n, 3) bands of ``band`` pixels of ``rgb``, which it modifies in place."""
    flat = rgb.reshape(-1, 3)  # a view when rgb is C-contiguous (the protocol), else a copy
    for start in range(0, len(flat), band):
        step(flat[start : start + band])
    if not np.shares_memory(flat, rgb):
        rgb[...] = flat.reshape(rgb.shape)


@dataclass(frozen=True)
class EncodedTransform:
    """A :class:`PixelTransform` for encoded (log) footage: colour-science's decoding of
    ``encoding``, the post-correction exactly (float64), and the encoding again.

    Where a curve has no negative part (a power law), a negative corrected value is encoded
    mirrored, ``-f(-x)``, so that valid footage never becomes NaN.
    """

    correction: Any
    encoding: str
    band: int = 1 << 14

    def _encode(self, linear: np.ndarray) -> np.ndarray:
        import colour

        encoded = colour.cctf_encoding(linear, function=self.encoding)
        bad = ~np.isfinite(encoded) & np.isfinite(linear)
        if np.any(bad):
            mirrored = -colour.cctf_encoding(-linear[bad], function=self.encoding)
            encoded = np.where(bad, 0.0, encoded)
            encoded[bad] = mirrored
        return encoded

    def __call__(self, rgb: np.ndarray) -> None:
        import colour

        def step(block: np.ndarray) -> None:
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                linear = colour.cctf_decoding(block.astype(np.float64), function=self.encoding)
                block[...] = self._encode(self.correction.apply(linear))

        _in_bands(rgb, self.band, step)


#: How to build the per-pixel transform of a :class:`PostCorrection`, by its ``kind``: an OCIO
#: conversion in the solution's config, or the exact non-linear model (which the config can
#: only carry as a LUT bake). Another kind registers its factory here.
TRANSFORMS: dict[str, Callable[[PostCorrection], PixelTransform]] = {
    "ocio": lambda pc: OcioTransform(cpu_processor(pc), cpu_processor(pc, bit_depth="f16")),
    "model": lambda pc: ModelTransform(correction_from_dict(json.loads(pc.model))),
    "encoded": lambda pc: EncodedTransform(correction_from_dict(json.loads(pc.model)), pc.encoding),
}


@functools.lru_cache(maxsize=8)
def pixel_transform(pc: PostCorrection) -> PixelTransform:
    """The :class:`PixelTransform` of ``pc`` (cached per process)."""
    if pc.kind not in TRANSFORMS:
        raise ValueError(f"no pixel transform for post-correction kind {pc.kind!r}")
    return TRANSFORMS[pc.kind](pc)


_THREADS: dict[int, ThreadPoolExecutor] = {}


def apply_in_place(
    transform: Any,
    pixels: np.ndarray,
    *,
    rgb: tuple[int, int, int] = (0, 1, 2),
    threads: int = 1,
) -> np.ndarray:
    """Apply ``transform`` to the RGB channels of a (height, width, channels) image, in place.

    ``transform`` is a :class:`PixelTransform` or an OCIO float32 CPU processor; ``pixels`` is
    float32, or float16 when the transform handles half (:class:`OcioTransform` does). Other
    channels are not touched (not even through OCIO's alpha path, which turns alpha into NaN
    where RGB is infinite). A C-contiguous RGB image is processed with no copy; otherwise RGB
    is gathered into a scratch buffer and scattered back. ``threads`` > 1 splits the rows
    (OCIO releases the GIL while it works).

    Returns
    -------
    numpy.ndarray
        ``pixels``, modified.
    """
    if pixels.dtype not in (np.float32, np.float16) or pixels.ndim != 3:
        raise ValueError(
            "expected a (height, width, channels) float32 or float16 image, got "
            f"{pixels.dtype} {pixels.shape}"
        )
    if hasattr(transform, "applyRGB"):  # an OCIO float32 CPU processor, as cpu_processor's
        transform = OcioTransform(transform)
    direct = pixels.shape[2] == 3 and tuple(rgb) == (0, 1, 2) and pixels.flags.c_contiguous
    work = pixels if direct else np.ascontiguousarray(pixels[..., list(rgb)])
    if threads <= 1 or work.shape[0] < 2 * threads:
        transform(work)
    else:
        pool = _THREADS.setdefault(threads, ThreadPoolExecutor(threads))
        bounds = np.linspace(0, work.shape[0], threads + 1).astype(int)
        jobs = [pool.submit(transform, work[a:b]) for a, b in itertools.pairwise(bounds)]
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


def _read_type(spec, oiio):
    """The type to read a subimage in: its own when uniformly half or float, else float."""
    formats = {str(t) for t in spec.channelformats} or {str(spec.format)}
    return spec.format if formats in ({"half"}, {"float"}) else oiio.FLOAT


def load_frame(src: str | Path) -> list[tuple[Any, np.ndarray]]:
    """Every subimage of ``src`` as (spec, (h, w, channels) pixels), half or float32.

    Raises
    ------
    InputError
        Missing, unreadable, deep or corrupt frame.
    """
    import OpenImageIO as oiio

    src = Path(src)
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
            pixels = inp.read_image(index, 0, 0, spec.nchannels, _read_type(spec, oiio))
            if pixels is None or inp.has_error:
                raise InputError(f"corrupt or truncated frame: {inp.geterror()}", source=str(src))
            parts.append((spec, pixels.reshape(spec.height, spec.width, spec.nchannels)))
            index += 1
    finally:
        inp.close()
    return parts


def transform_frame(
    parts: list[tuple[Any, np.ndarray]], pc: PostCorrection, *, threads: int = 1, source: str = ""
) -> int:
    """Post-correct, in place, every subimage of ``parts`` that has R, G, B; returns how many.

    Raises
    ------
    InputError
        No subimage has R, G, B channels.
    """
    transform = pixel_transform(pc)
    done = 0
    for spec, pixels in parts:
        rgb = _rgb_channels(spec)
        if rgb is not None:
            apply_in_place(transform, pixels, rgb=rgb, threads=threads)
            exact = "" if pc.kind == "ocio" else f", {pc.kind} applied exactly"
            spec.attribute(MARK, f"{pc.source} -> {pc.target} ({pc.environment}{exact})")
            if pc.solution:
                spec.attribute(SOLUTION_MARK, pc.solution)
            done += 1
    if done == 0:
        raise InputError("no R, G, B channels to post-correct", source=source or None)
    return done


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


def store_frame(dst: str | Path, parts: list[tuple[Any, np.ndarray]]) -> None:
    """Write ``parts`` to ``dst`` atomically (a temporary name in its folder, then a rename).

    Raises
    ------
    OSError
        The output could not be written (disk full, read-only, no permission, a file where a
        folder should be...): ``filename`` is ``dst`` (never the temporary name) and
        ``strerror`` says why, in a few words.
    """
    dst = Path(dst)
    # Same folder (same file system) for an atomic rename; the extension picks the format.
    tmp = dst.with_name(f".{dst.stem}.partial-{os.getpid()}{dst.suffix}")
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
        _write_all(tmp, parts)
        os.replace(tmp, dst)
    except OSError as exc:
        reason = exc.strerror or str(exc).replace(f"{tmp}: ", "").replace(str(tmp), dst.name)
        raise OSError(exc.errno, reason, str(dst)) from exc
    finally:
        with contextlib.suppress(OSError):  # a folder that cannot be listed: nothing to remove
            tmp.unlink(missing_ok=True)


def apply_file(src: str | Path, dst: str | Path, pc: PostCorrection, *, threads: int = 1) -> int:
    """Post-correct one frame file into ``dst`` (atomically); returns the RGB layers processed.

    Raises
    ------
    InputError
        Missing, unreadable, corrupt frame, or no subimage with RGB channels.
    OSError
        The output could not be written.
    """
    parts = load_frame(src)
    done = transform_frame(parts, pc, threads=threads, source=str(src))
    store_frame(dst, parts)
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
    """What happened to one frame: ``status`` is done, skipped, input-error (this frame's
    input), write-error (the output could not be written: disk full, read-only, permissions;
    ``message`` is the reason, without the path) or error (a bug)."""

    src: str
    dst: str
    status: str
    message: str = ""
    seconds: float = 0.0


def existing_output(task: FrameTask) -> FrameResult | None:
    """The result that ends ``task`` before any work because its output exists, else None.

    An output ``ocio-vp apply`` wrote is done (``skipped``), unless the task overwrites it; any
    other file there is refused (``input-error``): neither replaced nor counted as done.
    """
    if not os.path.lexists(task.dst):
        return None
    foreign = foreign_output_error(task.dst)
    if foreign is not None:
        return FrameResult(task.src, task.dst, "input-error", foreign)
    if task.overwrite:
        return None
    made_by = output_solution(task.dst)
    wanted = task.post_correction.solution
    if wanted and made_by != wanted:
        return FrameResult(
            task.src, task.dst, "input-error", other_solution_reason(task.dst, made_by, wanted)
        )
    return FrameResult(task.src, task.dst, "skipped", "already written")


def other_solution_reason(dst: str | Path, made_by: str | None, wanted: str) -> str:
    """One line: ``dst`` was corrected with another post-correction than ``wanted``."""
    by = made_by or "an ocio-vp that did not record its solution"
    return f"{dst}: made with {by}, not {wanted}; --overwrite redoes it"


def run_task(task: FrameTask) -> FrameResult:
    """Do one :class:`FrameTask`, never raising: failures become a result."""
    set_io_threads(task.threads)
    start, parts = load_task(task)
    if isinstance(parts, FrameResult):
        return parts
    try:
        transform_frame(parts, task.post_correction, threads=task.threads, source=task.src)
    except Exception as exc:  # no RGB in this frame...: reported, the others go on
        return frame_failure(task, exc)
    return store_task(task, start, parts)


def load_task(task: FrameTask) -> tuple[float, Any]:
    """(start time, the frame's parts or the FrameResult that ends it: skipped or failed)."""
    start = time.perf_counter()
    ended = existing_output(task)
    if ended is not None:
        return start, ended
    try:
        return start, load_frame(task.src)
    except Exception as exc:  # reported in its result, the other frames go on
        return start, frame_failure(task, exc)


def store_task(task: FrameTask, start: float, parts: Any) -> FrameResult:
    """Write the transformed ``parts`` of ``task``: its result, timed from ``start``."""
    try:
        store_frame(task.dst, parts)
    except OSError as exc:  # out of disk, read-only...: the run stops after this frame
        return write_failure(task, exc)
    except Exception as exc:  # a bug: reported, the others go on
        return frame_failure(task, exc)
    return FrameResult(task.src, task.dst, "done", seconds=time.perf_counter() - start)


def frame_failure(task: FrameTask, exc: Exception) -> FrameResult:
    """The result of a frame whose reading or transform raised ``exc``."""
    if isinstance(exc, InputError):
        return FrameResult(task.src, task.dst, "input-error", str(exc))
    return FrameResult(task.src, task.dst, "error", f"{type(exc).__name__}: {exc}")


def write_failure(task: FrameTask, exc: OSError) -> FrameResult:
    """The result of a frame :func:`store_frame` could not write (``exc``)."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    return FrameResult(task.src, task.dst, "write-error", " ".join(str(reason).split()))


def set_io_threads(threads: int) -> None:
    """Cap OpenImageIO's thread pool and OpenEXR's own one (both) at ``threads``, so a task
    given one core (a pool or Dask worker) uses one core and workers do not oversubscribe."""
    import OpenImageIO as oiio

    oiio.attribute("threads", max(1, threads))
    oiio.attribute("exr_threads", max(1, threads))


def _root_polynomial_transform(coefficients: Any, band: int = 1 << 14) -> ModelTransform:
    """The deprecated ``RootPolynomialTransform(coefficients, band)``: the unbounded
    root-polynomial ``C e(x)`` as a :class:`ModelTransform`."""
    from ocio_vp.model.correction import RootPolynomialCorrection

    return ModelTransform(RootPolynomialCorrection(coefficients, np.eye(3)), band)


#: Names that left this module (:mod:`ocio_vp.deprecation`).
DEPRECATED = {
    "RootPolynomialTransform": (
        "ModelTransform(RootPolynomialCorrection(...)) (ocio_vp.model)",
        lambda: _root_polynomial_transform,
    )
}
__getattr__ = deprecated_names(__name__, DEPRECATED)
