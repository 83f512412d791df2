"""Measuring a movie take (ProRes 4444 in QuickTime) against decoding it with PyAV alone.

A movie must be decoded frame by frame, so the floor is FFmpeg's own decoding time. The
question is what ``measure_take`` adds on top of it: finding the wall (16 frames decoded by
seeking), converting the rows it reads from Y'CbCr, decoding the log curve, the statistics
and the alignment. Both run in fresh processes, alternately, twice each, on the same file:

- **plain**: ``for frame in container.decode(stream)`` with FFmpeg's threads on
  (``thread_type = "AUTO"``, as ``measure_take`` uses), touching nothing;
- **measure**: ``measure_take`` on the take (the ``take:`` of ``ocio-vp measure``).

The take is the calibration sequence (5 ramp steps, 24 fps, 12 frames a patch) filmed at
25 fps with one dropped frame (the simulator's per-frame wall colours: blends at every change,
no flicker or noise), the wall over 60 % of the frame, ARRI LogC3, Rec.709 legal range,
10-bit ProRes 4444 (``prores_ks`` profile 4). ProRes is intra-only, so every distinct picture
is encoded once and its packet muxed wherever the take repeats it: the file is what an encoder
would write for such a take, in a fraction of the encoding time. Peak memory (``VmHWM``) is
measured for two take lengths at 1080p.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import time
from fractions import Fraction
from pathlib import Path

import numpy as np

from benchmarks.child import memory_rows, run_child

SIZE_4K = (3840, 2160)
SIZE_HD = (1920, 1080)
SL = np.array([[0.5, 0.08, 0.01], [0.2, 0.6, 0.08], [0.02, 0.1, 0.55]])
CAMERA_FPS = 25
ENCODING = "ARRI LogC3"

#: Run by :func:`benchmarks.child.run_child` (``hwm()`` is its prelude's).
_CHILD = r"""
import json, sys, time
mode, movie, sequence = sys.argv[1], sys.argv[2], sys.argv[3]
from pathlib import Path

import av, numpy as np
from ocio_vp.plates.take import TakeRef, measure_take
base = hwm()
start = time.perf_counter()
result = {}
if mode == "measure":
    reading = measure_take(TakeRef(frames=Path(movie), sequence=Path(sequence), encoding="ARRI LogC3"))
    result["white"] = reading.net("white").tolist()
    result["steps"] = list(reading.alignment.steps)
    result["frames"] = len(reading.numbers)
else:
    with av.open(movie) as container:
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        result["frames"] = sum(1 for _ in container.decode(stream))
result.update(total=time.perf_counter() - start, peak=hwm(), base=base)
print(json.dumps(result))
"""


def _sequence(folder: Path, steps: int):
    from ocio_vp.patterns.design import PatternOptions, calibration_sequence
    from ocio_vp.patterns.frames import write_sequence_folder
    from ocio_vp.patterns.sequence import load_sequence

    path = write_sequence_folder(
        calibration_sequence(PatternOptions(steps=steps, size=(16, 9))), folder, frames=False
    )
    return load_sequence(path)


def _codes(colours: np.ndarray) -> np.ndarray:
    """10-bit legal Rec.709 Y'CbCr code values of linear colours (n, 3), LogC3-encoded."""
    import colour

    encoded = colour.cctf_encoding(np.maximum(colours, 0.0), function=ENCODING)
    return np.asarray(
        colour.RGB_to_YCbCr(
            np.clip(encoded, 0, 1),
            K=colour.WEIGHTS_YCBCR["ITU-R BT.709"],
            out_bits=10,
            out_legal=True,
            out_int=True,
        ),
        dtype=np.uint16,
    )


def _picture(size, wall: np.ndarray, set_codes: np.ndarray):  # -> av.VideoFrame
    import av

    width, height = size
    x0, y0, x1, y1 = (int(0.2 * width), int(0.2 * height), int(0.8 * width), int(0.8 * height))
    frame = av.VideoFrame(width, height, "yuv444p10le")
    for k, plane in enumerate(frame.planes):
        values = np.full((height, plane.line_size // 2), set_codes[k], dtype=np.uint16)
        values[y0:y1, x0:x1] = wall[k]
        plane.update(values.tobytes())
    return frame


def _write_movie(sequence, path: Path, size: tuple[int, int]) -> tuple[int, int]:
    """The take as ProRes 4444 (module docstring); returns (frames, distinct pictures)."""
    import av

    from ocio_vp.simulator.take import TakeOptions, take_signal

    options = TakeOptions(
        fps=CAMERA_FPS, noise=0.0, flicker=0.0, preroll=0.5, postroll=0.3, dropped=(300,)
    )
    _, colours = take_signal(sequence, SL, options)
    codes = _codes(colours)
    set_codes = _codes(np.array([[0.03, 0.03, 0.03]]))[0]
    keys = [tuple(int(v) for v in c) for c in codes]
    distinct = list(dict.fromkeys(keys))
    with av.open(str(path), "w", format="mov") as container:
        stream = container.add_stream("prores_ks", rate=CAMERA_FPS)
        stream.width, stream.height, stream.pix_fmt = size[0], size[1], "yuv444p10le"
        stream.options = {"profile": "4", "vendor": "apl0"}
        ctx = stream.codec_context
        ctx.colorspace, ctx.color_range, ctx.color_primaries, ctx.color_trc = 1, 1, 1, 1
        packets: list[bytes] = []
        for i, key in enumerate(distinct):
            frame = _picture(size, np.array(key), set_codes)
            frame.pts = i
            packets += [bytes(p) for p in stream.encode(frame)]
        packets += [bytes(p) for p in stream.encode()]
        by_key = dict(zip(distinct, packets, strict=True))
        for k, key in enumerate(keys):
            packet = av.Packet(by_key[key])
            packet.stream = stream
            packet.pts = packet.dts = k
            packet.time_base = Fraction(1, CAMERA_FPS)
            container.mux(packet)
    return len(keys), len(distinct)


def _child(mode: str, movie: Path, sequence) -> dict:
    return json.loads(run_child(_CHILD, mode, str(movie), str(sequence.source)))


def run(quick: bool = False) -> str:
    size = SIZE_HD if quick else SIZE_4K
    root = Path(tempfile.mkdtemp(prefix="ocio-vp-bench-movie-"))
    try:
        sequence = _sequence(root / "seq", 5)
        t = time.perf_counter()
        count, distinct = _write_movie(sequence, root / "A001.mov", size)
        write_s = time.perf_counter() - t
        megabytes = (root / "A001.mov").stat().st_size / 2**20
        runs: dict[str, list[dict]] = {"plain": [], "measure": []}
        for _ in range(2):
            for mode in ("plain", "measure"):
                runs[mode].append(_child(mode, root / "A001.mov", sequence))
        memory = []
        for steps in (5, 17):
            seq = _sequence(root / f"seq{steps}", steps)
            n, _ = _write_movie(seq, root / f"hd{steps}.mov", SIZE_HD)
            memory.append((n, _child("measure", root / f"hd{steps}.mov", seq)))
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return _report(size, count, distinct, write_s, megabytes, runs, memory)


def _report(size, count, distinct, write_s, megabytes, runs, memory) -> str:
    plain = min(r["total"] for r in runs["plain"])
    measure = min(r["total"] for r in runs["measure"])
    width, height = size
    lines = [
        "## Movie take: measuring a ProRes 4444 take against decoding it with PyAV alone",
        "",
        f"A {width}x{height} 10-bit ProRes 4444 take (LogC3, Rec.709 legal; {count} frames, "
        f"{distinct} distinct pictures, {megabytes:.0f} MiB, written in {write_s:.0f} s), decoded "
        "by PyAV alone and measured by `measure_take`, alternately in fresh processes, twice "
        f"each, on {os.cpu_count()} cores (`python -m benchmarks.run --only movie`).",
        "",
        "| | run 1 (s) | run 2 (s) | per frame, best (ms) |",
        "|---|---:|---:|---:|",
    ]
    for mode, label, best in (
        ("plain", "PyAV decode of every frame (FFmpeg threads on)", plain),
        ("measure", "`measure_take` (find the wall, one decoding pass, align, check)", measure),
    ):
        a, b = (r["total"] for r in runs[mode])
        lines.append(f"| {label} | {a:.1f} | {b:.1f} | {1000 * best / count:.1f} |")
    white = runs["measure"][0]["white"]
    pairs = ", ".join(
        f"{m['total'] / p['total']:.2f}x"
        for p, m in zip(runs["plain"], runs["measure"], strict=True)
    )
    lines += [
        "",
        f"- Measuring costs **{measure / plain:.2f}x** decoding alone (best of two each, side by "
        f"side in this run; target: at most 1.25x); run by run (each measure against the decode "
        f"just before it): {pairs}. The machine is shared: the spread between two runs of the "
        "same thing is the noise of this figure.",
        f"- Checked: the dropped frame is found ({runs['measure'][0]['steps']}), white reads "
        f"{', '.join(f'{v:.4f}' for v in white)} (simulated: "
        f"{', '.join(f'{v:.4f}' for v in SL.sum(axis=1))}).",
        "",
        "Peak memory of `measure_take` (1920x1080 ProRes 4444 takes of two lengths, `VmHWM`):",
        "",
        "| frames | peak RSS (MiB) | after imports (MiB) | added by measuring (MiB) |",
        "|---:|---:|---:|---:|",
    ]
    rows, growth = memory_rows(memory)
    lines += [*rows, "", f"{growth}.", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run(quick="--quick" in sys.argv))
