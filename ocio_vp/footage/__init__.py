"""Post-correcting recorded footage with Q: frame sequences, ``apply`` and its distribution
over a local pool or a Dask cluster.
"""

from ocio_vp.deprecation import deprecated_names
from ocio_vp.footage.apply import DEPRECATED as _DEPRECATED
from ocio_vp.footage.apply import (
    OPTIMIZATIONS,
    TRANSFORMS,
    FrameResult,
    FrameTask,
    ModelTransform,
    OcioTransform,
    PixelTransform,
    PostCorrection,
    apply_file,
    apply_in_place,
    cpu_processor,
    existing_output,
    load_frame,
    load_post_correction,
    pixel_transform,
    run_task,
    set_io_threads,
    store_frame,
    transform_frame,
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
from ocio_vp.footage.stream import apply_frames

__getattr__ = deprecated_names(__name__, _DEPRECATED)

__all__ = [
    "OPTIMIZATIONS",
    "TRANSFORMS",
    "FrameResult",
    "FrameTask",
    "ModelTransform",
    "OcioTransform",
    "PixelTransform",
    "PostCorrection",
    "apply_file",
    "apply_frames",
    "apply_in_place",
    "cpu_processor",
    "default_workers",
    "existing_output",
    "expand_frames",
    "frame_pattern",
    "load_frame",
    "load_post_correction",
    "map_unordered",
    "output_paths",
    "parse_frame_range",
    "pixel_transform",
    "run_task",
    "set_io_threads",
    "solve_environments",
    "store_frame",
    "transform_frame",
]
