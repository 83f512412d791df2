"""Post-correcting recorded footage with Q: frame sequences, ``apply`` and its distribution
over a local pool or a Dask cluster.
"""

from ocio_vp.footage.apply import (
    OPTIMIZATIONS,
    FrameResult,
    FrameTask,
    PostCorrection,
    apply_file,
    apply_in_place,
    cpu_processor,
    load_post_correction,
    run_task,
)
from ocio_vp.footage.distributed import (
    default_workers,
    map_unordered,
    solve_environments,
)
from ocio_vp.footage.sequences import (
    expand_frames,
    frame_pattern,
    output_paths,
    parse_frame_range,
)

__all__ = [
    "OPTIMIZATIONS",
    "FrameResult",
    "FrameTask",
    "PostCorrection",
    "apply_file",
    "apply_in_place",
    "cpu_processor",
    "default_workers",
    "expand_frames",
    "frame_pattern",
    "load_post_correction",
    "map_unordered",
    "output_paths",
    "parse_frame_range",
    "run_task",
    "solve_environments",
]
