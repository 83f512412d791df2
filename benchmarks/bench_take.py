"""Measuring a camera take: time per frame and peak memory, against a plain OpenImageIO read.

A 3-minute 4K take is ~4,300 frames (~90 GB of half-float EXR): too big to keep on disk here,
so a shorter 4K take of a calibration sequence is written (ZIP, half float, 0.5 % noise, the
wall over 60 % of the frame's width and height), measured by ``measure_take`` in a fresh
process, and read whole by ``ImageInput.read_image`` (float32) in another, frame for frame. The
per-frame times of both passes of ``measure_take`` are taken from its own progress callbacks,
so the time of a 4,300-frame take is extrapolated from what each frame costs:
``fixed + frames x pass-1 + kept frames x pass-2``, with the kept fraction of the default
calibration sequence (12 frames a patch at 24 fps, filmed at 25 fps) counted by the aligner
on a simulated take of it. Peak memory (``VmHWM``) is measured for two take lengths at 1080p:
it must not grow with the take.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.child import memory_rows, run_child

SIZE_4K = (4096, 2160)
SIZE_HD = (1920, 1080)
REAL_TIME_FRAMES = 4300
#: The simulated stage's [SL] (camera RGB of each primary at full drive).
SL = np.array([[0.5, 0.08, 0.01], [0.2, 0.6, 0.08], [0.02, 0.1, 0.55]])
CAMERA_FPS = 25.0

#: Run by :func:`benchmarks.child.run_child` (``hwm()`` is its prelude's).
_CHILD = r"""
import json, sys, time
mode, frames, sequence = sys.argv[1], sys.argv[2], sys.argv[3]
from pathlib import Path

import numpy as np, OpenImageIO as oiio
from ocio_vp.plates.take import TakeRef, measure_take
from ocio_vp.plates.take_reader import list_take_frames
base = hwm()
marks = []
def progress(stage, n):
    if stage != "frame":
        marks.append((stage, n, time.perf_counter()))
start = time.perf_counter()
if mode == "measure":
    reading = measure_take(TakeRef(frames=Path(frames), sequence=Path(sequence)), on_progress=progress)
    end = time.perf_counter()
    result = {"marks": [(s, n, t - start) for s, n, t in marks], "total": end - start,
              "kept": sum(len(p.frames) for p in reading.patches.values()),
              "white": reading.net("white").tolist(), "steps": list(reading.alignment.steps)}
else:
    total = 0.0
    for _, path in list_take_frames(frames):
        inp = oiio.ImageInput.open(str(path))
        pixels = inp.read_image(0, 0, 0, 3, oiio.FLOAT)
        inp.close()
        total += float(np.mean(pixels[..., 1]))
    result = {"total": time.perf_counter() - start}
result.update(peak=hwm(), base=base)
print(json.dumps(result))
"""


def _sequence(folder: Path, steps: int):
    """A calibration sequence for the benchmark: the default timing (24 fps, 12 frames a
    patch) with ``steps`` ramp steps, its frames not written (only sequence.yaml)."""
    from ocio_vp.patterns.design import PatternOptions, calibration_sequence
    from ocio_vp.patterns.frames import write_sequence_folder
    from ocio_vp.patterns.sequence import load_sequence

    path = write_sequence_folder(
        calibration_sequence(PatternOptions(steps=steps, size=(16, 9))), folder, frames=False
    )
    return load_sequence(path)


def _write_take(sequence, folder: Path, size: tuple[int, int]) -> int:
    """Frames of a take of ``sequence``: per-frame wall colours from the simulator (blends,
    flicker, a dropped frame), painted into a static set with repeating noise tiles."""
    import OpenImageIO as oiio

    from ocio_vp.simulator.take import TakeOptions, take_signal

    options = TakeOptions(
        fps=CAMERA_FPS, noise=0.0, flicker=0.01, preroll=0.5, postroll=0.3, dropped=(300,)
    )
    _, colours = take_signal(sequence, SL, options)
    width, height = size
    x0, y0, x1, y1 = (int(0.2 * width), int(0.2 * height), int(0.8 * width), int(0.8 * height))
    rng = np.random.default_rng(0)
    tiles = [
        1 + 0.005 * rng.standard_normal((y1 - y0, x1 - x0, 1)).astype(np.float32) for _ in range(3)
    ]
    background = np.full((height, width, 3), 0.03, dtype=np.float32)
    folder.mkdir(parents=True, exist_ok=True)
    for k, colour in enumerate(colours):
        frame = background.copy()
        frame[y0:y1, x0:x1] = colour.astype(np.float32) * tiles[k % 3]
        path = folder / f"A001.{k + 1:04d}.exr"
        spec = oiio.ImageSpec(width, height, 3, "half")
        spec.attribute("compression", "zip")
        out = oiio.ImageOutput.create(str(path))
        out.open(str(path), spec)
        out.write_image(frame)
        out.close()
    return len(colours)


def _child(mode: str, folder: Path, sequence) -> dict:
    return json.loads(run_child(_CHILD, mode, str(folder / "A001.####.exr"), str(sequence.source)))


def _default_kept_fraction() -> tuple[float, int]:
    """(frames kept / frames, frames) for the default calibration sequence filmed at 25 fps,
    and the number of ramp steps making it ~3 minutes."""
    from ocio_vp.patterns.design import PatternOptions, calibration_sequence
    from ocio_vp.plates.alignment import align_take, kept_frames
    from ocio_vp.simulator.take import TakeOptions, take_signal

    SL = np.eye(3) * 0.5 + 0.05
    # 3 minutes at 24 fps, 12 frames a patch: about 115 ramp steps per channel
    sequence = calibration_sequence(PatternOptions(steps=115))
    numbers, signal = take_signal(sequence, SL, TakeOptions(fps=CAMERA_FPS))
    alignment = align_take(signal, numbers, sequence)
    kept = sum(
        len(kept_frames(alignment, p, numbers))
        for p in sequence.of_kind("black", "primary", "white", "ramp")
    )
    return kept / len(numbers), len(numbers)


def _passes(result: dict) -> tuple[float, float, float]:
    """(fixed seconds, pass-1 seconds per frame, pass-2 seconds per kept frame)."""
    (_, n1, t1), (_, n2, t2) = result["marks"]
    per_1 = (t2 - t1) / n1
    per_2 = (result["total"] - t2) / n2
    fixed = result["total"] - per_1 * n1 - per_2 * n2
    return fixed, per_1, per_2


def run(quick: bool = False) -> str:
    size = SIZE_HD if quick else SIZE_4K
    fraction, default_frames = _default_kept_fraction()
    root = Path(tempfile.mkdtemp(prefix="ocio-vp-bench-take-"))
    try:
        sequence = _sequence(root / "seq", 5)
        t = time.perf_counter()
        count = _write_take(sequence, root / "take", size)
        write_s = time.perf_counter() - t
        disk = sum(p.stat().st_size for p in (root / "take").iterdir()) / 2**30
        measured = _child("measure", root / "take", sequence)
        plain = _child("plain", root / "take", sequence)
        shutil.rmtree(root / "take")
        memory = []
        for steps in (5, 17):
            seq = _sequence(root / f"seq{steps}", steps)
            n = _write_take(seq, root / f"hd{steps}", SIZE_HD)
            memory.append((n, _child("measure", root / f"hd{steps}", seq)))
            shutil.rmtree(root / f"hd{steps}")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    fixed, per_1, per_2 = _passes(measured)
    per_plain = plain["total"] / count
    extrapolated = fixed + REAL_TIME_FRAMES * (per_1 + fraction * per_2)
    real_time = REAL_TIME_FRAMES / CAMERA_FPS
    width, height = size
    lines = [
        "## Take: measuring a camera take of the calibration sequence",
        "",
        f"A {width}x{height} half-float EXR take (ZIP, {count} frames, {disk:.1f} GiB, written in "
        f"{write_s:.0f} s; 25 fps camera against the 24 fps default sequence, one dropped frame, "
        "1 % flicker, the wall over 60 % of the width and height), measured by `measure_take` "
        "(the `take:` of `ocio-vp measure`) and read whole by OpenImageIO, each in a fresh "
        f"process on {os.cpu_count()} cores. Pass 1 reads one band of rows per frame (alignment), "
        "pass 2 eight bands of the wall's rows per kept frame.",
        "",
        "| | seconds | per frame (ms) |",
        "|---|---:|---:|",
        f"| plain OpenImageIO read of every frame (`read_image`, float32) | {plain['total']:.1f} | {1000 * per_plain:.1f} |",
        f"| `measure_take`, all of it | {measured['total']:.1f} | {1000 * measured['total'] / count:.1f} |",
        f"| of which pass 1 (alignment band, every frame) | {per_1 * count:.1f} | {1000 * per_1:.2f} |",
        f"| of which pass 2 (wall bands, {measured['kept']} kept frames) | {per_2 * measured['kept']:.1f} | {1000 * per_2:.2f} per kept frame |",
        f"| of which fixed (finding the wall: 16 whole frames; alignment) | {fixed:.1f} | |",
        "",
        f"- Measuring costs **{measured['total'] / plain['total']:.2f}x** a plain read of the same "
        "frames, side by side in this run.",
        f"- A 3-minute take, {REAL_TIME_FRAMES} frames (the default sequence with 115 ramp steps "
        f"keeps {100 * fraction:.0f} % of its {default_frames} frames): extrapolated "
        f"{fixed:.0f} s + {REAL_TIME_FRAMES} x {1000 * per_1:.1f} ms + "
        f"{fraction * REAL_TIME_FRAMES:.0f} x {1000 * per_2:.1f} ms = **{extrapolated:.0f} s**, "
        f"against {real_time:.0f} s of take: **{extrapolated / real_time:.2f}x real time** "
        f"({'faster' if extrapolated < real_time else 'slower'} than the take lasts). Extrapolated, "
        "not measured: such a take does not fit on this machine's disk; the per-frame costs do "
        "not depend on the take's length (below).",
        "",
        "Peak memory of `measure_take` (1920x1080 takes of two lengths, `VmHWM` of the process):",
        "",
        "| frames | peak RSS (MiB) | after imports (MiB) | added by measuring (MiB) |",
        "|---:|---:|---:|---:|",
    ]
    rows, growth = memory_rows(memory)
    lines += [
        *rows,
        "",
        f"{growth}: per frame only a few numbers are kept.",
        f"- Checked: the dropped frame is found ({measured['steps']}), white reads "
        f"{', '.join(f'{v:.4f}' for v in measured['white'])} (simulated: "
        f"{', '.join(f'{v:.4f}' for v in SL.sum(axis=1))}, within the 1 % flicker).",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick="--quick" in sys.argv))
