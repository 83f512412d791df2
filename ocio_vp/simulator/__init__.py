"""The spectral stage simulator: colour-science datasets, the simulated stage and its
measurements, the ground-truth prediction of what a solution does, evaluation, sample data,
sample calibration photographs (plates), a camera take of the wall playing patterns, and the
ground truth on colours the chart does not
contain (:mod:`ocio_vp.simulator.truth`).
"""

from ocio_vp.simulator.data import (
    DEFAULT_CAMERA,
    DEFAULT_CHART,
    DEFAULT_LEDS,
    ENVIRONMENTS,
    PAPER_ENVIRONMENTS,
    SPECTRAL_SHAPE,
    EnvironmentSpec,
    align,
    camera_sensitivities,
    chart_reflectances,
    gaussian_leds,
    wavelengths,
)
from ocio_vp.simulator.evaluate import (
    Evaluation,
    NoiseStudy,
    agreement_with_spectra,
    evaluate_solution,
    noise_study,
)
from ocio_vp.simulator.options import (
    environments_from_args,
    read_spectra_csv,
    stage_options_from_args,
)
from ocio_vp.simulator.plates import (
    PlateOptions,
    plate_count,
    render_chart,
    render_regions,
    write_capture,
    write_plate,
)
from ocio_vp.simulator.predict import (
    StagePrediction,
    predict_solution,
    predict_stage,
)
from ocio_vp.simulator.samples import (
    SAMPLE_METHOD,
    SAMPLE_NAME,
    simulate_and_solve,
    write_paper_samples,
)
from ocio_vp.simulator.stage import (
    DEFAULT_PANEL,
    DEFAULT_PANEL_ALBEDO,
    SpectralStage,
    camera_rgb,
    environment_spectrum,
    paper_stage,
    paper_stage_measurements,
    simulate_measurements,
    spectral_stage,
    white_reflectance,
)
from ocio_vp.simulator.take import (
    PanelResponse,
    TakeOptions,
    take_frame_count,
    take_signal,
    true_frame_times,
    write_take,
)
from ocio_vp.simulator.truth import (
    CHART_DUPLICATE_TOLERANCE,
    HeldOutErrors,
    held_out_errors,
    held_out_reflectances,
    noisy_measurements,
)

__all__ = [
    "CHART_DUPLICATE_TOLERANCE",
    "DEFAULT_CAMERA",
    "DEFAULT_CHART",
    "DEFAULT_LEDS",
    "DEFAULT_PANEL",
    "DEFAULT_PANEL_ALBEDO",
    "ENVIRONMENTS",
    "PAPER_ENVIRONMENTS",
    "SAMPLE_METHOD",
    "SAMPLE_NAME",
    "SPECTRAL_SHAPE",
    "EnvironmentSpec",
    "Evaluation",
    "HeldOutErrors",
    "NoiseStudy",
    "PanelResponse",
    "PlateOptions",
    "SpectralStage",
    "StagePrediction",
    "TakeOptions",
    "agreement_with_spectra",
    "align",
    "camera_rgb",
    "camera_sensitivities",
    "chart_reflectances",
    "environment_spectrum",
    "environments_from_args",
    "evaluate_solution",
    "gaussian_leds",
    "held_out_errors",
    "held_out_reflectances",
    "noise_study",
    "noisy_measurements",
    "paper_stage",
    "paper_stage_measurements",
    "plate_count",
    "predict_solution",
    "predict_stage",
    "read_spectra_csv",
    "render_chart",
    "render_regions",
    "simulate_and_solve",
    "simulate_measurements",
    "spectral_stage",
    "stage_options_from_args",
    "take_frame_count",
    "take_signal",
    "true_frame_times",
    "wavelengths",
    "white_reflectance",
    "write_capture",
    "write_paper_samples",
    "write_plate",
    "write_take",
]
