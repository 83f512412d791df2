"""The file formats people and other tools depend on: measurements and solutions.

- :mod:`~ocio_vp.formats.measurements`: ``ocio-vp/measurements`` v1 (YAML/JSON), strictly validated;
- :mod:`~ocio_vp.formats.merge`: several measurements files (the wall, the charts) merged into one;
- :mod:`~ocio_vp.formats.solution`: ``solution.json``, one solved environment;
- :mod:`~ocio_vp.formats.synthesis`: the ``synthesized`` record of a computed target chart;
- :mod:`~ocio_vp.formats.documents`: bounded reading of YAML/JSON and other input files.
"""

from ocio_vp.formats.documents import (
    MAX_DEPTH,
    MAX_DOCUMENT_BYTES,
    MAX_YAML_VALUES,
    check_regular_file,
    read_bounded,
)
from ocio_vp.formats.measurements import (
    CHANNELS,
    FORMAT,
    SAFE_NAME,
    VERSION,
    Environment,
    Measurements,
    PanelGeometry,
    Stage,
    Validator,
    check_measurements_part,
    check_safe_name,
    load_measurements,
    measurements_from_dict,
    measurements_to_dict,
    parse_stage,
    read_document,
    save_measurements,
    save_measurements_document,
)
from ocio_vp.formats.merge import load_measurement_files, merge_measurement_documents
from ocio_vp.formats.solution import (
    SOLUTION_FORMAT,
    Diagnostics,
    Solution,
    load_solution,
    solution_to_json,
)
from ocio_vp.formats.synthesis import SynthesisRecord

__all__ = [
    "CHANNELS",
    "FORMAT",
    "MAX_DEPTH",
    "MAX_DOCUMENT_BYTES",
    "MAX_YAML_VALUES",
    "SAFE_NAME",
    "SOLUTION_FORMAT",
    "VERSION",
    "Diagnostics",
    "Environment",
    "Measurements",
    "PanelGeometry",
    "Solution",
    "Stage",
    "SynthesisRecord",
    "Validator",
    "check_measurements_part",
    "check_regular_file",
    "check_safe_name",
    "load_measurement_files",
    "load_measurements",
    "load_solution",
    "measurements_from_dict",
    "measurements_to_dict",
    "merge_measurement_documents",
    "parse_stage",
    "read_bounded",
    "read_document",
    "save_measurements",
    "save_measurements_document",
    "solution_to_json",
]
