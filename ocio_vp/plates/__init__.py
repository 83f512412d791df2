"""From calibration photographs to measurements: reading plates and frames, the capture file,
chart sampling and patch statistics, chart detection, overlays, and ``measure``.
"""

from ocio_vp.deprecation import deprecated_names
from ocio_vp.plates.alignment import Alignment, align_take, kept_frames
from ocio_vp.plates.capture import (
    FORMAT,
    VERSION,
    Capture,
    ChartShot,
    EnvironmentCapture,
    PlateRef,
    RegionShot,
    capture_from_dict,
    load_capture,
    save_capture_document,
)
from ocio_vp.plates.detection import DEPRECATED as _DEPRECATED
from ocio_vp.plates.detection import (
    Detection,
    DetectionError,
    detect_chart,
    detect_chart_corners,
)
from ocio_vp.plates.frames import (
    flat_field_gain,
    frames_pixels,
)
from ocio_vp.plates.measure import (
    MeasureResult,
    PlateSampling,
    measure_capture,
    write_measure_outputs,
)
from ocio_vp.plates.overlay import (
    OUTLINE_COLOURS,
    overlay_image,
    tone_map,
    write_png,
)
from ocio_vp.plates.reader import (
    DISPLAY_FORMATS,
    ENCODINGS,
    PlateInfo,
    canonical_encoding,
    linearise,
    open_plate,
    read_region,
)
from ocio_vp.plates.sampling import (
    ChartSamples,
    chart_box,
    grid_homography,
    patch_labels,
    sample_chart,
    sample_region,
)
from ocio_vp.plates.statistics import (
    ROBUST_MEAN_METHODS,
    clip_levels,
    patch_statistics,
)
from ocio_vp.plates.take import PatchReading, TakeReading, TakeRef, measure_take
from ocio_vp.plates.wall_region import find_wall

__getattr__ = deprecated_names(__name__, _DEPRECATED)

__all__ = [
    "DISPLAY_FORMATS",
    "ENCODINGS",
    "FORMAT",
    "OUTLINE_COLOURS",
    "ROBUST_MEAN_METHODS",
    "VERSION",
    "Alignment",
    "Capture",
    "ChartSamples",
    "ChartShot",
    "Detection",
    "DetectionError",
    "EnvironmentCapture",
    "MeasureResult",
    "PatchReading",
    "PlateInfo",
    "PlateRef",
    "PlateSampling",
    "RegionShot",
    "TakeReading",
    "TakeRef",
    "align_take",
    "canonical_encoding",
    "capture_from_dict",
    "chart_box",
    "clip_levels",
    "detect_chart",
    "detect_chart_corners",
    "find_wall",
    "flat_field_gain",
    "frames_pixels",
    "grid_homography",
    "kept_frames",
    "linearise",
    "load_capture",
    "measure_capture",
    "measure_take",
    "open_plate",
    "overlay_image",
    "patch_labels",
    "patch_statistics",
    "read_region",
    "sample_chart",
    "sample_region",
    "save_capture_document",
    "tone_map",
    "write_measure_outputs",
    "write_png",
]
