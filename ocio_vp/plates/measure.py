"""From a capture file to a measurements file: sample every plate, then write the results.

[SL] (paper Section 3.3) is built column by column from the primaries' regions, [SRL]_j from
the chart lit by each LED channel (eq. 3), p_j from each environment's chart (eq. 5) and
b_camera from the black-level region (Section 3.4). :func:`write_measure_outputs` writes the
measurements file, an overlay PNG per plate and ``samples.json`` all together or not at all.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ocio_vp.errors import InputError, format_key_path
from ocio_vp.formats.jsontypes import JsonObject
from ocio_vp.formats.measurements import (
    CHANNELS,
    FORMAT,
    REQUIRED_SECTIONS,
    VERSION,
    Measurements,
    check_measurements_part,
    measurements_from_dict,
)
from ocio_vp.plates.capture import Capture, ChartShot, PlateRef, RegionShot
from ocio_vp.plates.contact_sheet import SHEET
from ocio_vp.plates.detection import Detection, DetectionError, detect_chart
from ocio_vp.plates.raw import CameraSpace
from ocio_vp.plates.reader import PlateInfo, open_plate, read_region
from ocio_vp.plates.sampling import ChartSamples, patch_labels, sample_chart, sample_region
from ocio_vp.plates.take import TakeReading, measure_take

__all__ = [
    "MeasureResult",
    "PlateSampling",
    "measure_capture",
    "measure_steps",
    "write_measure_outputs",
]

_OVERLAY_MARGIN = 16


@dataclass(frozen=True)
class PlateSampling:
    """What was sampled on one plate: a chart (``corners``) or named regions."""

    name: str
    plate: PlateRef
    infos: tuple[PlateInfo, ...]
    samples: ChartSamples
    labels: tuple[str, ...]  # one per sample row: patch numbers or region names
    corners: np.ndarray | None = None
    regions: tuple[tuple[int, int, int, int], ...] = ()
    detected: bool = False
    grid: tuple[int, int] = (0, 0)  # rows, columns of a chart
    inset: float = 0.0
    #: The search that found the corners (``None`` when the capture file gave them).
    detection: Detection | None = None
    #: The conversion of a raw plate's sensor RGB to the camera gamut, when one was applied.
    camera_space: CameraSpace | None = None


@dataclass(frozen=True)
class MeasureResult:
    """The measurements plus everything needed for overlays and the user's report.

    ``measurements`` is None when the capture holds only some sections (a wall-only take, or
    charts only): ``document`` is then a valid part of a measurements file, merged with the
    others at solve time. ``take``: the take's reading, when the capture has one.
    """

    measurements: Measurements | None
    plates: tuple[PlateSampling, ...]
    detected: Mapping[tuple[str | int, ...], np.ndarray]
    warnings: tuple[str, ...]
    document: Mapping[str, Any] = field(default_factory=dict)
    take: TakeReading | None = None


#: Samples a chart shot: its (n, 3) patch means.
ChartSampler = Callable[[ChartShot], np.ndarray]


def _open(ref: PlateRef, demosaic: str | None = None) -> tuple[PlateInfo, ...]:
    infos = tuple(
        open_plate(p, encoding=ref.encoding, layer=ref.layer, demosaic=demosaic) for p in ref.paths
    )
    first = infos[0]
    for info in infos[1:]:
        if info.box != first.box:
            raise InputError(
                f"frame size {list(info.box)} differs from the first frame's {list(first.box)}",
                source=info.path,
                key=ref.key,
            )
    return infos


def _flat(ref: PlateRef) -> dict[str, Any]:
    """Flat-field keyword arguments for a plate (its encoding applies to the flat too)."""
    if ref.flat_field is None:
        return {}
    return {"flat_field": [str(p) for p in ref.flat_field], "encoding": ref.encoding}


def _camera_space(capture: Capture, info: PlateInfo) -> CameraSpace | None:
    """How a raw plate's sensor RGB becomes the camera gamut's (``raw.to_camera``), if asked."""
    from ocio_vp.plates.raw import sensor_to_camera

    to_camera = capture.raw.to_camera
    if to_camera is None or info.demosaic is None:  # not asked, or not a raw plate
        return None
    if isinstance(to_camera, str):  # "dng": the file's own ColorMatrix
        return sensor_to_camera(info.path, str(capture.stage["camera_colorspace"]))
    return CameraSpace(to_camera, "the capture file's raw.to_camera")


def _in_camera_space(samples: ChartSamples, space: CameraSpace | None) -> ChartSamples:
    """``samples`` with means (and spreads, channels taken as independent) in the camera
    gamut; clipping and outliers were judged on the sensor's values, as read."""
    if space is None:
        return samples
    M = space.matrix
    spreads = np.sqrt(np.square(samples.spreads) @ np.square(M).T)
    return dataclasses.replace(samples, means=samples.means @ M.T, spreads=spreads)


def _named(error: InputError, ref: PlateRef, key: str) -> InputError:
    """The same error, naming the plate and the capture-file key."""
    source = error.source or ref.label
    return InputError(error.problem, source=source, key=f"{key}.{error.key}" if error.key else key)


def _sample_chart(
    capture: Capture, shot: ChartShot, detect: Callable[..., Detection] | None
) -> tuple[PlateSampling, np.ndarray | None]:
    key = format_key_path(*shot.key)
    detection = None
    try:
        infos = _open(shot.plate, capture.raw.demosaic)
        space = _camera_space(capture, infos[0])
        corners, found = shot.corners, None
        if corners is None:
            detection = (detect or detect_chart)(
                infos[0], rows=capture.rows, columns=capture.columns
            )
            if detection.corners is None:
                raise DetectionError(detection, source=infos[0].path, key=key, name=shot.plate.name)
            corners = found = detection.corners
        samples = sample_chart(
            list(infos),
            corners,
            capture.rows,
            capture.columns,
            inset=capture.inset,
            source=infos[0].path,
            **_flat(shot.plate),
            **capture.sampling,
        )
        samples = _in_camera_space(samples, space)
    except DetectionError:
        raise  # already names the plate and key, and carries the search for its overlay
    except InputError as error:
        raise _named(error, shot.plate, key) from None
    labels = tuple(f"patch {j}" for j in range(capture.rows * capture.columns))
    sampling = PlateSampling(
        name=shot.plate.name,
        plate=shot.plate,
        infos=infos,
        samples=samples,
        labels=labels,
        corners=np.asarray(corners, dtype=np.float64),
        detected=found is not None,
        grid=(capture.rows, capture.columns),
        inset=capture.inset,
        detection=detection,
        camera_space=space,
    )
    return sampling, found


def _sample_regions(capture: Capture, shots: Mapping[str, RegionShot]) -> list[PlateSampling]:
    """Sample regions, grouping those that share a plate into one :class:`PlateSampling`."""
    groups: dict[PlateRef, list[tuple[str, RegionShot]]] = {}
    for label, shot in shots.items():
        groups.setdefault(shot.plate, []).append((label, shot))
    out = []
    for ref, members in groups.items():
        infos = _open(ref, capture.raw.demosaic)
        try:
            space = _camera_space(capture, infos[0])
        except InputError as error:
            raise _named(error, ref, format_key_path(*members[0][1].key)) from None
        rows = []
        for _label, shot in members:
            try:
                rows.append(
                    sample_region(
                        list(infos),
                        shot.region,
                        source=infos[0].path,
                        **_flat(ref),
                        **capture.sampling,
                    )
                )
            except InputError as error:
                raise _named(error, ref, format_key_path(*shot.key)) from None
        per_patch = [f.name for f in dataclasses.fields(ChartSamples) if f.type == "np.ndarray"]
        arrays: dict[str, Any] = {
            f: np.concatenate([getattr(r, f) for r in rows]) for f in per_patch
        }
        stacked = dataclasses.replace(rows[0], **arrays)
        stacked = _in_camera_space(stacked, space)
        out.append(
            PlateSampling(
                name=ref.name if len(members) > 1 else members[0][1].plate.name,
                plate=ref,
                infos=infos,
                samples=stacked,
                labels=tuple(label for label, _ in members),
                regions=tuple(shot.region for _, shot in members),
                camera_space=space,
            )
        )
    return out


def measure_steps(capture: Capture) -> int:
    """How many times :func:`measure_capture` calls ``on_step`` (the take's frames count apart)."""
    blacks = sum(env.black_level is not None for env in capture.environments)
    blacks += sum(len(env.panel_black_level or {}) for env in capture.environments)
    if capture.panels:
        walls = len(capture.panels) * (1 + len(CHANNELS))
    else:
        walls = int(bool(capture.primaries)) + len(capture.lit_chart)
    return walls + len(capture.environments) + blacks


def take_sections(reading: TakeReading) -> JsonObject:
    """``primaries`` (black subtracted) and ``ramps`` (each step, black subtracted; the drive
    of that channel as ``sequence.yaml`` gives it) from a measured take."""
    sequence = reading.sequence
    primaries = {p.channel: reading.net(p.name).tolist() for p in sequence.of_kind("primary")}
    out: dict[str, Any] = {}
    if set(primaries) == set(CHANNELS):
        out["primaries"] = {c: primaries[c] for c in CHANNELS}
    ramps: dict[str, Any] = {}
    for k, channel in enumerate(CHANNELS):
        steps = sorted(
            (p for p in sequence.of_kind("ramp") if p.channel == channel),
            key=lambda p: -1 if p.step is None else p.step,  # every ramp patch has its step
        )
        if steps:
            ramps[channel] = {
                "drive": [float(p.drive[k]) for p in steps],
                "camera": [reading.net(p.name).tolist() for p in steps],
            }
    if set(ramps) == set(CHANNELS):
        out["ramps"] = ramps
    return out


def _measure_take(capture: Capture, document: dict[str, Any], on_take) -> TakeReading:
    """Measure the take into ``document``: its sections, and the wall's encoding, peak and
    pattern size from its ``sequence.yaml`` in ``stage`` (they travel on to the solve)."""
    from ocio_vp.formats.wall_state import stage_with_sequence

    assert capture.take is not None  # the caller measures a take only when there is one
    reading = measure_take(capture.take, source=capture.source, on_progress=on_take)
    document.update(take_sections(reading))
    document["stage"] = stage_with_sequence(
        document["stage"], reading.sequence, source=capture.source
    )
    return reading


def measure_capture(
    capture: Capture,
    *,
    detect: Callable[..., Detection] | None = None,
    on_step: Callable[[], None] | None = None,
    on_take: Callable[[str, int], None] | None = None,
) -> MeasureResult:
    """Sample every plate of ``capture`` and build the measurements.

    Parameters
    ----------
    detect
        ``detect(plate_info, rows=, columns=) -> Detection`` for charts given without corners
        (default :func:`ocio_vp.plates.detection.detect_chart`); a chart not found raises
        :class:`~ocio_vp.plates.detection.DetectionError`, which carries the search.
    on_step
        Called with no argument after each step (the primaries, each chart, each black level):
        :func:`measure_steps` of them in all, for a progress bar.
    on_take
        Passed to :func:`ocio_vp.plates.take.measure_take` as ``on_progress``.

    Raises
    ------
    InputError
        Naming the plate and the capture-file key: unreadable plates, bad corners or regions,
        clipped charts, and measurements the measurements format rejects.
    """
    plates: list[PlateSampling] = []
    detected: dict[tuple[str | int, ...], np.ndarray] = {}
    step = on_step or (lambda: None)
    document: dict[str, Any] = {"format": FORMAT, "version": VERSION, "stage": dict(capture.stage)}
    reading = None
    if capture.take is not None:
        reading = _measure_take(capture, document, on_take)

    def chart(shot: ChartShot) -> np.ndarray:
        sampling, found = _sample_chart(capture, shot, detect)
        plates.append(sampling)
        if found is not None:
            detected[shot.key] = found
        step()
        return sampling.samples.means

    def regions(shots: Mapping[str, RegionShot]) -> dict[str, list[float]]:
        sampled = _sample_regions(capture, shots)
        plates.extend(sampled)
        step()
        return {
            label: mean.tolist()
            for s in sampled
            for label, mean in zip(s.labels, s.samples.means, strict=True)
        }

    if capture.panels:
        document["panels"] = [
            {"name": p.name, **p.settings, **_wall_values(p.primaries, p.lit_chart, chart, regions)}
            for p in capture.panels
        ]
    else:
        document |= _wall_values(capture.primaries, capture.lit_chart, chart, regions)
    if capture.environments:
        document["environments"] = [
            _environment(env, chart, regions) for env in capture.environments
        ]
    if "ramps" in document:  # the file's key order: ramps after environments
        document["ramps"] = document.pop("ramps")
    measurements = None
    if capture.panels or all(name in document for name in REQUIRED_SECTIONS):
        measurements = measurements_from_dict(document, source=capture.source)
    else:
        check_measurements_part(document, source=capture.source)
    warnings = [] if reading is None else list(reading.warnings)
    warnings += _plate_warnings(plates)
    return MeasureResult(measurements, tuple(plates), detected, tuple(warnings), document, reading)


def _plate_warnings(plates: list[PlateSampling]) -> list[str]:
    """Per plate: patches a detected chart's grid was found without, and flagged samples."""
    warnings = []
    for sampling in plates:
        found = sampling.detection
        if found is not None and len(found.seen) < len(sampling.labels):
            unseen = sorted(set(range(len(sampling.labels))) - set(found.seen))
            warnings.append(
                f"{sampling.plate.label}: patches {', '.join(map(str, unseen))} not seen by the "
                "chart detection (covered, or as dark as the chart's frame): check the overlay"
            )
        for index in np.flatnonzero(sampling.samples.flagged):
            flags = ", ".join(sampling.samples.flag_names(int(index)))
            warnings.append(f"{sampling.plate.label}: {sampling.labels[index]}: {flags}")
    return warnings


def _environment(env, chart, regions) -> JsonObject:
    """One environment's entry: its target chart, black level(s) and w_avg as given."""
    entry: dict[str, Any] = {"name": env.name, "target_chart": chart(env.target_chart).tolist()}
    if env.black_level is not None:
        entry["black_level"] = regions({"black_level": env.black_level})["black_level"]
    if env.panel_black_level:
        entry["black_level"] = {
            name: regions({"black_level": shot})["black_level"]
            for name, shot in env.panel_black_level.items()
        }
    if env.w_avg is not None:
        entry["w_avg"] = env.w_avg.tolist()
    if env.panel_w_avg is not None:
        entry["w_avg"] = dict(env.panel_w_avg)
    return entry


def _wall_values(
    primaries: Mapping[str, RegionShot],
    lit_chart: Mapping[str, ChartShot],
    chart: ChartSampler,
    regions: Callable[[Mapping[str, RegionShot]], dict[str, list[float]]],
) -> JsonObject:
    """``primaries`` and ``lit_chart`` of the wall (or of one panel type), sampled, each where
    it is given (a wall file from a take has no lit chart; a charts file no primaries)."""
    out: JsonObject = {}
    if primaries:
        means = regions(primaries)
        out["primaries"] = {c: means[c] for c in CHANNELS}
    if lit_chart:
        out["lit_chart"] = {c: chart(lit_chart[c]).tolist() for c in CHANNELS}
    return out


def _overlay(sampling: PlateSampling) -> np.ndarray:
    from ocio_vp.plates.overlay import overlay_image

    info = sampling.infos[0]
    px0, py0, px1, py1 = info.box
    x0, y0, x1, y1 = sampling.samples.box
    for r in sampling.regions:
        x0, y0, x1, y1 = min(x0, r[0]), min(y0, r[1]), max(x1, r[2]), max(y1, r[3])
    m = _OVERLAY_MARGIN
    box = (max(px0, x0 - m), max(py0, y0 - m), min(px1, x1 + m), min(py1, y1 + m))
    pixels = read_region(info, box)
    if sampling.corners is not None:
        labels = patch_labels(sampling.corners, *sampling.grid, inset=sampling.inset, box=box)
    else:
        labels = np.full((box[3] - box[1], box[2] - box[0]), -1, dtype=np.int32)
        for index, (rx0, ry0, rx1, ry1) in enumerate(sampling.regions):
            labels[ry0 - box[1] : ry1 - box[1], rx0 - box[0] : rx1 - box[0]] = index
    s = sampling.samples
    states = [
        "clipped" if s.clipped[j] else "high_spread" if s.high_spread[j] else "ok"
        for j in range(len(s.means))
    ]
    return overlay_image(pixels, labels, states)


def samples_document(result: MeasureResult, *, relative_to: str | Path) -> dict[str, Any]:
    """Per-plate, per-patch statistics (``samples.json`` beside the overlays).

    Plate paths are written relative to ``relative_to`` (the overlay folder), so the file does
    not depend on where the project lives.
    """

    def where(path: Path) -> str:
        return Path(os.path.relpath(os.path.abspath(path), os.path.abspath(relative_to))).as_posix()

    plates = []
    for sampling in result.plates:
        s = sampling.samples
        plates.append(
            {
                "plate": [where(p) for p in sampling.plate.paths],
                "key": sampling.plate.key,
                "overlay": f"{sampling.name}.png",
                "box": list(s.box),
                "method": s.method,
                "frames": s.frames,
                "corners": None if sampling.corners is None else sampling.corners.tolist(),
                "detected": sampling.detected,
                **_detection_record(sampling),
                **_raw_record(sampling),
                "samples": [
                    {
                        "label": sampling.labels[j],
                        "mean": s.means[j].tolist(),
                        "spread": s.spreads[j].tolist(),
                        "pixels": int(s.counts[j]),
                        "clipped_fraction": float(s.clipped_fraction[j]),
                        "outlier_fraction": float(s.outlier_fraction[j]),
                        "flags": s.flag_names(j),
                    }
                    for j in range(len(s.means))
                ],
            }
        )
    out: dict[str, Any] = {"format": "ocio-vp/samples", "version": 1, "plates": plates}
    if result.take is not None:
        out["take"] = take_document(result.take, where)
    return out


def _raw_record(sampling: PlateSampling) -> JsonObject:
    """A raw plate's demosaicing and conversion to the camera gamut (``samples.json``)."""
    info = sampling.infos[0]
    if info.demosaic is None:
        return {}
    out: dict[str, Any] = {"demosaic": info.demosaic}
    space = sampling.camera_space
    out["to_camera"] = None if space is None else {
        "from": space.source,
        "matrix": np.round(space.matrix, 6).tolist(),
    }  # fmt: skip
    return out


def _detection_record(sampling: PlateSampling) -> JsonObject:
    """How a chart's corners were found (``samples.json``), when they were searched for."""
    found = sampling.detection
    if found is None:
        return {}
    return {
        "detection": {
            "overlay": f"{sampling.name}.detection.png",
            "patches_found": found.patches_found,
            "patches_not_seen": sorted(set(range(len(sampling.labels))) - set(found.seen)),
            "grid_residual_px": round(found.residual, 2),
            "working_scale": found.scale,
        }
    }


def take_document(reading: TakeReading, where: Any = str) -> dict[str, Any]:
    """The take's alignment and every patch's frames and statistics (``samples.json``)."""
    a = reading.alignment
    movie = reading.movie
    decoded = {}
    if movie is not None:  # how the movie's pixels became R'G'B' (and who said so)
        decoded = {
            "movie": {
                "codec": movie.codec,
                "pixel_format": movie.pix_fmt,
                "matrix": movie.matrix,
                "range": movie.range,
                "matrix_and_range_from": movie.tags_from,
                "frame_rate": str(movie.rate),
                "start_timecode": movie.timecode,
                "encoding": movie.encoding,
            }
        }
    return {
        "frames": where(reading.take.frames),
        "sequence": where(reading.take.sequence),
        **decoded,
        "contact_sheet": SHEET,
        "region": list(reading.region),
        "region_found": reading.region_found,
        "frame_count": len(reading.numbers),
        "camera_frames_per_player_frame": a.rate,
        "sync_marks_found": list(a.marks_found),
        "sync_marks_expected": a.marks_expected,
        "patch_changes_timed": a.changes_used,
        "steps": [{"player_frame": T, "camera_frames": n} for T, n in a.steps],
        "clip_level": reading.clip_level,
        "patches": [
            {
                "name": p.name,
                "kind": p.kind,
                "mean": p.mean.tolist(),
                "spread": p.spread.tolist(),
                "frames": list(p.frames),
                "rejected": list(p.rejected),
                "pixels_per_frame": p.pixels,
            }
            for p in reading.patches.values()
        ],
    }


def overlay_folder(out: str | Path, overlays: str | Path | None = None) -> Path:
    """Where the overlays of ``measure --out OUT`` go: ``overlays`` or ``OUT_STEM.overlays``."""
    out = Path(out)
    return Path(overlays) if overlays is not None else out.with_name(f"{out.stem}.overlays")


def write_measure_outputs(
    result: MeasureResult, out: str | Path, *, overlays: str | Path | None = None
) -> Path:
    """Write the measurements file and ``<out stem>.overlays/`` (PNGs + samples.json).

    Everything is rendered into a staging folder first; the measurements file is written
    atomically and the overlay folder published only when all of it succeeded.
    """
    from ocio_vp.formats.measurements import save_measurements, save_measurements_document
    from ocio_vp.plates.overlay import write_png
    from ocio_vp.staging import (
        check_file_replaceable,
        check_replaceable,
        publish_dir,
        staged_dir,
        write_file_atomically,
    )

    out = Path(out)
    folder = overlay_folder(out, overlays)
    check_replaceable(folder)  # both outputs checked before either is written
    check_file_replaceable(out)
    with staged_dir(folder.parent) as staged:
        for sampling in result.plates:
            write_png(staged / f"{sampling.name}.png", _overlay(sampling))
            if sampling.detection is not None:
                from ocio_vp.plates.detection import detection_overlay

                image = detection_overlay(sampling.detection)
                write_png(staged / f"{sampling.name}.detection.png", image)
        if result.take is not None:
            from ocio_vp.plates.contact_sheet import write_contact_sheet

            write_contact_sheet(result.take, staged / SHEET)
        text = json.dumps(samples_document(result, relative_to=folder), indent=2) + "\n"
        write_file_atomically(staged / "samples.json", text)
        if result.measurements is not None:
            save_measurements(result.measurements, out)
        else:
            save_measurements_document(result.document, out)
        publish_dir(staged, folder)
    return folder
