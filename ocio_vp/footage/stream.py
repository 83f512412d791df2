"""A sequence of frames through one process: read ahead, transform, write behind.

Reading frame i+1 and writing frames i-1 and i-2 while frame i is transformed fills the serial
parts of OpenEXR's reads and writes (opening, headers, chunks in order, system calls) with
useful work, and one process pays the imports and OCIO set-up once. At most :data:`HELD` frames
are held at any time (one being read, one transformed, :data:`WRITERS` being written), whatever
the length of the sequence.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from ocio_vp.footage.apply import (
    FrameResult,
    FrameTask,
    frame_failure,
    load_task,
    set_io_threads,
    store_task,
    transform_frame,
)

__all__ = ["HELD", "WRITERS", "apply_frames"]

#: Frames written at once.
WRITERS = 2
#: The most frames held in memory at once: one being read, one transformed, the writers'.
HELD = 2 + WRITERS


def apply_frames(tasks: Sequence[FrameTask], *, threads: int) -> Iterator[tuple[int, FrameResult]]:
    """Do ``tasks`` in this process, pipelined; yield ``(index, FrameResult)`` as frames finish.

    ``threads`` is what OpenImageIO, OpenEXR and the transform may each use (the cores this
    process has). Never raises for a frame: failures become results, as with
    :func:`ocio_vp.footage.apply.run_task`.
    """
    tasks = list(tasks)
    if not tasks:
        return
    set_io_threads(threads)
    with ThreadPoolExecutor(1) as reader, ThreadPoolExecutor(WRITERS) as writer:
        ahead = reader.submit(load_task, tasks[0])
        behind: deque[tuple[int, Any]] = deque()  # frames being written, oldest first
        for i, task in enumerate(tasks):
            start, parts = ahead.result()
            if i + 1 < len(tasks):
                ahead = reader.submit(load_task, tasks[i + 1])
            if isinstance(parts, FrameResult):
                yield i, parts
                continue
            try:
                transform_frame(parts, task.post_correction, threads=threads, source=task.src)
            except Exception as exc:  # no RGB in this frame...: reported, the others go on
                yield i, frame_failure(task, exc)
                continue
            while len(behind) >= WRITERS:  # bounded memory: wait for the oldest write
                j, written = behind.popleft()
                yield j, written.result()
            behind.append((i, writer.submit(store_task, task, start, parts)))
            del parts  # the writer holds the frame now, and only it
        while behind:
            j, written = behind.popleft()
            yield j, written.result()
