"""The file formats people and other tools depend on: measurements and solutions, a module per
file or block (docs/architecture.md). The names below are imported on first use (PEP 562): a
reader of one format (``ocio_vp.formats.solution`` for export and apply) loads that module and
what it imports, not every format of the package.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ocio_vp.deprecation import published_on_first_use

#: Public name -> the module of this package that defines it.
_EXPORTS = {
    "MAX_DEPTH": "ocio_vp.formats.documents",
    "MAX_DOCUMENT_BYTES": "ocio_vp.formats.documents",
    "MAX_YAML_VALUES": "ocio_vp.formats.documents",
    "check_regular_file": "ocio_vp.formats.documents",
    "read_bounded": "ocio_vp.formats.documents",
    "CHANNELS": "ocio_vp.formats.measurements",
    "FORMAT": "ocio_vp.formats.measurements",
    "SAFE_NAME": "ocio_vp.formats.measurements",
    "VERSION": "ocio_vp.formats.measurements",
    "Environment": "ocio_vp.formats.measurements",
    "Measurements": "ocio_vp.formats.measurements",
    "PanelGeometry": "ocio_vp.formats.measurements",
    "Stage": "ocio_vp.formats.measurements",
    "Validator": "ocio_vp.formats.measurements",
    "check_measurements_part": "ocio_vp.formats.measurements",
    "check_safe_name": "ocio_vp.formats.measurements",
    "load_measurements": "ocio_vp.formats.measurements",
    "measurements_from_dict": "ocio_vp.formats.measurements",
    "measurements_to_dict": "ocio_vp.formats.measurements",
    "parse_stage": "ocio_vp.formats.measurements",
    "read_document": "ocio_vp.formats.measurements",
    "save_measurements": "ocio_vp.formats.measurements",
    "save_measurements_document": "ocio_vp.formats.measurements",
    "load_measurement_files": "ocio_vp.formats.merge",
    "merge_measurement_documents": "ocio_vp.formats.merge",
    "SOLUTION_FORMAT": "ocio_vp.formats.solution",
    "Diagnostics": "ocio_vp.formats.solution",
    "Solution": "ocio_vp.formats.solution",
    "load_solution": "ocio_vp.formats.solution",
    "solution_to_json": "ocio_vp.formats.solution",
    "SynthesisRecord": "ocio_vp.formats.synthesis",
}

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

if TYPE_CHECKING:  # what type checkers and IDEs see; at run time, __getattr__ below
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


__getattr__, __dir__ = published_on_first_use(__name__, _EXPORTS)
