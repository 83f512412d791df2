"""Calibration photographs of a simulated stage, as a stage engineer would shoot them.

From a measurements file's exact values this renders the plates of ``docs/capture.md`` (listed
in docs/simulator.md) as OpenEXR with perspective, vignetting and sensor noise, and the capture
file that points at them, so ``ocio-vp measure`` can be run on them. The chart's homography is
fitted here as the null space of the DLT system (SVD), independently of the direct solve
:mod:`ocio_vp.plates.sampling` uses, so the two check each other.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.formats.jsontypes import JsonObject, JsonValue
from ocio_vp.formats.measurements import CHANNELS, Measurements
from ocio_vp.simulator.take import take_frame_count, write_plate, write_take

if TYPE_CHECKING:
    from ocio_vp.patterns.sequence import PatternSequence

__all__ = [
    "CHART_CORNERS",
    "DEGRADATIONS",
    "PATCH_GAP",
    "PLATE_SIZE",
    "PlateOptions",
    "homography",
    "plate_count",
    "practice_sequence",
    "raw_clip_note",
    "render_chart",
    "render_regions",
    "vignetting_gain",
    "write_capture",
    "write_plate",
]

#: (width, height) of the rendered plates: small, so a whole stage renders quickly.
PLATE_SIZE = (600, 400)
#: The chart's four outer corners (TL, TR, BR, BL) on a 600 x 400 plate, seen at an angle.
CHART_CORNERS = np.array([[128.0, 82.0], [478.0, 104.0], [466.0, 322.0], [140.0, 306.0]])
#: Black border between patches, as a fraction of a cell (``measure``'s default inset is 0.25).
PATCH_GAP = 0.08
#: Degraded chart plates (keyword arguments of :func:`render_chart`, on top of the plates'
#: usual 1 % noise and 5 % fall-off) that chart detection must see through, by name.
DEGRADATIONS: dict[str, dict[str, Any]] = {
    # Defocus: a Gaussian of 2.5 pixels' standard deviation (a patch is ~50 pixels across).
    "blur": {"blur": 2.5},
    # Five times the plates' noise: 5 % relative and 0.2 % of white absolute, per pixel.
    "noise": {"noise": 0.05, "read_noise": 0.002},
    # A chart at 45 degrees or so: its far side 40 % shorter than its near side.
    "perspective": {
        "corners": np.array([[90.0, 60.0], [500.0, 130.0], [500.0, 280.0], [90.0, 350.0]])
    },
    # Half the light lost at the frame's corners (1 - 0.5 (r / r_corner)^2).
    "vignetting": {"vignetting": 0.5},
    # A stand in front of the chart covering most of two bottom-row patches and part of a third.
    "occlusion": {"occluder": (300.0, 250.0, 420.0, 340.0)},
}
#: Where the panel (primaries) and the dark in-frustum panel (black level) are on their plates.
PANEL_REGION = (180, 100, 420, 300)


def homography(corners: ArrayLike, rows: int, columns: int) -> np.ndarray:
    """(3, 3) map from grid coordinates (u right, v down, in cells) to pixel (x, y).

    The null-space fit of the four correspondences ``(0, 0), (columns, 0), (columns, rows),
    (0, rows)`` -> ``corners`` (SVD of the 8 x 9 DLT system), normalised so ``H[2, 2] = 1``.

    Examples
    --------
    >>> H = homography([[0, 0], [6, 0], [6, 4], [0, 4]], 4, 6)
    >>> bool(np.allclose(H, np.eye(3)))
    True
    """
    src = [(0, 0), (columns, 0), (columns, rows), (0, rows)]
    A = []
    for (u, v), (x, y) in zip(src, np.asarray(corners, dtype=np.float64), strict=True):
        A.append([u, v, 1, 0, 0, 0, -x * u, -x * v, -x])
        A.append([0, 0, 0, u, v, 1, -y * u, -y * v, -y])
    h = np.linalg.svd(np.asarray(A, dtype=np.float64))[2][-1]
    return h.reshape(3, 3) / h[-1]


def vignetting_gain(size: tuple[int, int], vignetting: float) -> np.ndarray:
    """(h, w) lens gain ``1 - v (r / r_corner)^2`` about the image centre."""
    width, height = size
    ys, xs = np.mgrid[0:height, 0:width]
    r2 = ((xs + 0.5 - width / 2) ** 2 + (ys + 0.5 - height / 2) ** 2) / (
        (width / 2) ** 2 + (height / 2) ** 2
    )
    return 1 - vignetting * r2


def _sensor(
    image: np.ndarray, *, vignetting: float, noise: float, read_noise: float, seed: int
) -> np.ndarray:
    """Lens fall-off, then shot and read noise; float32 like a camera's linear output."""
    height, width = image.shape[:2]
    image = image * vignetting_gain((width, height), vignetting)[..., None]
    if noise or read_noise:
        sigma = np.sqrt((noise * image) ** 2 + read_noise**2)
        image = image + sigma * np.random.default_rng(seed).standard_normal(image.shape)
    return image.astype(np.float32)


def render_chart(
    values: ArrayLike,
    *,
    corners: ArrayLike = CHART_CORNERS,
    rows: int = 4,
    columns: int = 6,
    size: tuple[int, int] = PLATE_SIZE,
    background: float = 0.01,
    vignetting: float = 0.0,
    noise: float = 0.0,
    read_noise: float = 0.0,
    highlight: int | None = None,
    highlight_value: float = 8.0,
    highlight_radius: float = 3.5,
    blur: float = 0.0,
    occluder: tuple[float, float, float, float] | None = None,
    occluder_value: float = 0.02,
    seed: int = 0,
) -> np.ndarray:
    """(h, w, 3) float32 linear plate of a chart whose patches have ``values`` (rows*columns, 3).

    ``vignetting`` v: gain ``1 - v (r / r_corner)^2``. ``noise``: relative Gaussian std;
    ``read_noise``: absolute std. ``highlight``: index of a patch that gets a clipped disc
    (a specular glint) of ``highlight_value`` and ``highlight_radius`` pixels at its centre.
    ``occluder``: a rectangle ``(x0, y0, x1, y1)`` (pixels) in front of the chart, of flat
    ``occluder_value`` (a stand, a hand). ``blur``: the lens's defocus, a Gaussian of that
    standard deviation in pixels, before the sensor's noise. :data:`DEGRADATIONS` names the
    amounts the detection tests use.
    """
    width, height = size
    values = np.asarray(values, dtype=np.float64)
    H = homography(corners, rows, columns)
    ys, xs = np.mgrid[0:height, 0:width]
    centres = np.stack([xs + 0.5, ys + 0.5, np.ones_like(xs, dtype=float)], axis=-1)
    uvw = centres @ np.linalg.inv(H).T
    u, v = uvw[..., 0] / uvw[..., 2], uvw[..., 1] / uvw[..., 2]
    col, row = np.floor(u).astype(int), np.floor(v).astype(int)
    fu, fv = u - col, v - row
    inside = (col >= 0) & (col < columns) & (row >= 0) & (row < rows)
    gap = PATCH_GAP
    on_patch = inside & (fu > gap) & (fu < 1 - gap) & (fv > gap) & (fv < 1 - gap)
    image = np.full((height, width, 3), background, dtype=np.float64)
    image[inside & ~on_patch] = 0.005  # the chart's black frame
    image[on_patch] = values[(row * columns + col)[on_patch]]
    if occluder is not None:
        x0, y0, x1, y1 = occluder
        image[(xs + 0.5 >= x0) & (xs + 0.5 < x1) & (ys + 0.5 >= y0) & (ys + 0.5 < y1)] = (
            occluder_value
        )
    if blur > 0:
        from scipy.ndimage import gaussian_filter

        image = gaussian_filter(image, (blur, blur, 0), mode="nearest")
    image = _sensor(image, vignetting=vignetting, noise=noise, read_noise=read_noise, seed=seed)
    if highlight is not None:
        r, c = divmod(highlight, columns)
        p = H @ [c + 0.5, r + 0.5, 1.0]
        disc = (xs + 0.5 - p[0] / p[2]) ** 2 + (ys + 0.5 - p[1] / p[2]) ** 2 <= highlight_radius**2
        image[disc] = highlight_value
    return image


def render_regions(
    regions: Mapping[str, tuple[tuple[int, int, int, int], ArrayLike]],
    *,
    size: tuple[int, int] = PLATE_SIZE,
    background: float = 0.002,
    vignetting: float = 0.0,
    noise: float = 0.0,
    read_noise: float = 0.0,
    seed: int = 0,
) -> np.ndarray:
    """A plate of flat rectangles ``name -> ((x0, y0, x1, y1), rgb)`` (end-exclusive)."""
    width, height = size
    image = np.full((height, width, 3), background, dtype=np.float64)
    for (x0, y0, x1, y1), rgb in regions.values():
        image[y0:y1, x0:x1] = np.asarray(rgb, dtype=np.float64)
    return _sensor(image, vignetting=vignetting, noise=noise, read_noise=read_noise, seed=seed)


@dataclass(frozen=True)
class PlateOptions:
    """How the simulated camera shoots: lens fall-off, noise, flat-field and footage frames.

    ``take``: film the wall playing the patterns in one take (:mod:`ocio_vp.simulator.take`)
    for [SL] and the ramps, instead of photographing each primary; ``take_format``: ``exr``
    (linear half-float frames) or a camera movie (``prores4444``, ``prores422``: ARRI LogC3,
    Rec.709 legal range, :mod:`ocio_vp.simulator.movie`); ``lit_format``: the lit-chart plates
    as ``exr`` or as camera raw, ``dng`` (the Bayer mosaic, the sensor clipping at 1.0 camera
    unit as the take does, :mod:`ocio_vp.simulator.raw`).
    """

    vignetting: float = 0.05
    noise: float = 0.01
    read_noise: float = 1e-4
    flat_frames: int = 4
    footage_frames: int = 3
    seed: int = 0
    take: Any = None
    take_format: str = "exr"
    lit_format: str = "exr"


def _grid(patches: int) -> tuple[int, int]:
    """(rows, columns) of a chart: a ColorChecker's 4 x 6, otherwise one row."""
    return (4, 6) if patches == 24 else (1, patches)


class _Camera:
    """Shoots the plates in a fixed order: each shot takes the next seed, so a plate's noise
    depends only on its position."""

    def __init__(self, measurements: Measurements, options: PlateOptions) -> None:
        self.rows, self.columns = _grid(measurements.SRL.shape[0])
        self.seed = iter(range(options.seed * 1000, options.seed * 1000 + 1000))
        self.sensor: dict[str, Any] = {
            "vignetting": options.vignetting,
            "noise": options.noise,
            "read_noise": options.read_noise,
        }

    def chart(self, values: ArrayLike) -> np.ndarray:
        return render_chart(
            values, rows=self.rows, columns=self.columns, seed=next(self.seed), **self.sensor
        )

    def panel(self, rgb: ArrayLike) -> np.ndarray:
        return render_regions({"panel": (PANEL_REGION, rgb)}, seed=next(self.seed), **self.sensor)


def _plates(measurements: Measurements, options: PlateOptions) -> Iterator[tuple[str, np.ndarray]]:
    """(file name, image) of every plate, in a fixed order (seeds depend on the position). On a
    stage of several panel types, each type's primaries and lit charts are prefixed with its
    name, each in-frustum type has a black level per environment, and the footage is lit by
    every type through its own M."""
    from ocio_vp.calibration.equations import predict_lit_chart, solve_M
    from ocio_vp.calibration.geometry import environment_panel_w_avg, stage_beta
    from ocio_vp.calibration.panels import panel_lights

    camera = _Camera(measurements, options)
    yield from _flat_fields(options, camera.seed)
    panels = measurements.panels
    walls = [(f"{p.name}_", p.SL, p.SRL) for p in panels]
    for prefix, SL, SRL in walls or [("", measurements.SL, measurements.SRL)]:
        for k, channel in enumerate(CHANNELS):
            image = camera.panel(SL[:, k])
            if panels or options.take is None:
                yield f"{prefix}primary_{channel}.exr", image
        for k, channel in enumerate(CHANNELS):
            yield f"{prefix}lit_{channel}.exr", camera.chart(SRL[:, :, k])
    M = None if panels else solve_M(measurements.SL)
    for env in measurements.environments:
        yield f"{env.name}.exr", camera.chart(env.target_chart)
        if panels:
            for name, black in (env.panel_black_level or {}).items():
                yield f"{env.name}_{name}_black.exr", camera.panel(black)
        elif env.black_level is not None:
            yield f"{env.name}_black.exr", camera.panel(env.black_level)
        if not options.footage_frames or (env.panel_w_avg if panels else env.w_avg) is None:
            continue
        # Footage: the chart lit by the wall (each panel type) through M alone (Q post-corrects).
        if panels:
            lights = panel_lights(measurements, environment_panel_w_avg(measurements, env))
            lit = sum(light.lit() for light in lights)
        else:
            assert M is not None  # a stage of one panel type
            drive = np.clip(M @ np.asarray(env.w_avg, dtype=np.float64), 0.0, None)
            lit = predict_lit_chart(measurements.SRL, stage_beta(measurements), np.eye(3), drive)
        for frame in range(1, options.footage_frames + 1):
            yield f"footage/{env.name}.{frame:04d}.exr", camera.chart(lit)


def _flat_fields(options: PlateOptions, seed: Iterator[int]) -> Iterator[tuple[str, np.ndarray]]:
    """``flat.####.exr``: the evenly lit white frames that remove the lens fall-off."""
    white = {"flat": ((0, 0, *PLATE_SIZE), (0.5, 0.5, 0.5))}
    for i in range(options.flat_frames):
        flat = render_regions(white, vignetting=options.vignetting, noise=0.003, seed=next(seed))
        yield f"flat.{i + 1:04d}.exr", flat


def _chart(plate: str) -> JsonObject:
    return {"plate": plate, "corners": CHART_CORNERS.tolist()}


def _region(plate: str) -> JsonObject:
    return {"plate": plate, "region": list(PANEL_REGION)}


def _environments(measurements: Measurements, names: set[str]) -> list[JsonValue]:
    """The capture document's ``environments``: each one's plates (those written) and w_avg,
    per panel type on a stage of several."""
    from ocio_vp.formats.panels import panel_values_to_dict

    environments: list[JsonValue] = []
    for env in measurements.environments:
        entry: JsonObject = {"name": env.name, "target_chart": _chart(f"{env.name}.exr")}
        black: JsonValue
        w_avg: JsonValue
        if measurements.panels:
            plates = {n: f"{env.name}_{n}_black.exr" for n in (env.panel_black_level or {})}
            black = {n: _region(plate) for n, plate in plates.items() if plate in names}
            w_avg = None if env.panel_w_avg is None else panel_values_to_dict(env.panel_w_avg)
        else:
            black = _region(f"{env.name}_black.exr") if f"{env.name}_black.exr" in names else None
            w_avg = None if env.w_avg is None else [float(v) for v in env.w_avg]
        if black:
            entry["black_level"] = black
        if w_avg is not None:
            entry["w_avg"] = w_avg
        environments.append(entry)
    return environments


def _capture_document(
    measurements: Measurements,
    names: set[str],
    options: PlateOptions,
    sequence_ref: str | None = None,
) -> dict:
    """The ``ocio-vp/capture`` document pointing at the plates (paths relative to it)."""
    from ocio_vp.formats.measurements import measurements_to_dict
    from ocio_vp.formats.panels import panels_to_dict

    rows, columns = _grid(measurements.SRL.shape[0])
    stage = measurements_to_dict(measurements)["stage"]
    document: dict[str, Any] = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": stage,
        "chart": {"rows": rows, "columns": columns, "inset": 0.25},
    }
    flats = sorted(n for n in names if n.startswith("flat."))
    if flats:
        document["flat_field"] = flats
    if measurements.panels:
        panels = panels_to_dict(measurements.panels)
        for entry in panels:
            name = entry["name"]
            entry["primaries"] = {c: _region(f"{name}_primary_{c}.exr") for c in CHANNELS}
            entry["lit_chart"] = {c: _chart(f"{name}_lit_{c}.exr") for c in CHANNELS}
        return document | {"panels": panels, "environments": _environments(measurements, names)}
    if options.take is None:
        document["primaries"] = {c: _region(f"primary_{c}.exr") for c in CHANNELS}
    else:
        movie = options.take_format != "exr"
        frames = f"{TAKE_FOLDER}/{TAKE_MOVIE if movie else TAKE_NAME}"
        document["take"] = {"frames": frames, "sequence": sequence_ref}
        if movie:
            from ocio_vp.simulator.movie import MOVIE_ENCODING

            document["take"]["encoding"] = MOVIE_ENCODING
    document["lit_chart"] = {c: _chart(f"lit_{c}.{options.lit_format}") for c in CHANNELS}
    document["environments"] = _environments(measurements, names)
    return document


def write_capture(
    measurements: Measurements,
    folder: str | Path,
    options: PlateOptions = PlateOptions(),
    *,
    bar=None,
    sequence: PatternSequence | None = None,
    sequence_ref: str | None = None,
) -> Path:
    """Render every plate of ``measurements`` into ``folder`` and write ``folder/capture.yaml``.

    ``folder`` must be new or empty (callers stage it and rename it into place). ``bar``: an
    optional progress bar (``update(1)`` per plate and per take frame). Returns the capture
    file's path.

    With ``options.take``, the wall is filmed playing ``sequence`` (a
    :class:`~ocio_vp.patterns.sequence.PatternSequence`, named in the capture file as
    ``sequence_ref``, relative to it) into ``folder/take/``; without a sequence, the small
    built-in one (:func:`practice_sequence`) is written to ``folder/patterns/`` and filmed.

    The values are those of ``measurements`` exactly, before lens and sensor: ``measure`` on
    these plates gives them back within the noise (the vignetting is removed by the flat
    fields when ``flat_frames`` > 0).
    """
    import yaml  # deferred like the other writers of YAML in the package

    folder = Path(folder)
    (folder / "footage").mkdir(parents=True, exist_ok=True)
    names = set()
    for name, image in _plates(measurements, options):
        if options.lit_format == "dng" and name.startswith("lit_"):
            from ocio_vp.simulator.raw import write_dng

            name = name.removesuffix(".exr") + ".dng"
            write_dng(folder / name, image)
        else:
            write_plate(folder / name, image)
        names.add(name)
        if bar is not None:
            bar.update(1)
    if not options.footage_frames or not any(n.startswith("footage/") for n in names):
        (folder / "footage").rmdir()
    if options.take is not None and not measurements.panels:  # a take films one wall
        sequence_ref = _film_patterns(measurements, folder, options, sequence, sequence_ref, bar)
    document = _capture_document(measurements, names, options, sequence_ref)
    path = folder / "capture.yaml"
    header = (
        "# Simulated calibration plates (ocio-vp simulate --plates): `ocio-vp measure` reads\n"
        "# this file; the format is described in docs/capture.md.\n"
        "# On a real stage, name the camera's gamut under stage: (camera_colorspace: ARRI Wide\n"
        "# Gamut 4, or solve --camera-colorspace NAME) so the configs carry working spaces, log\n"
        "# footage and ACES monitor views; the simulated camera has no named gamut.\n"
    )
    path.write_text(
        header + yaml.safe_dump(document, sort_keys=False, default_flow_style=None),
        encoding="utf-8",
    )
    return path


def raw_clip_note(measurements: Measurements, options: PlateOptions) -> str | None:
    """With the lit charts as DNG: why the location charts stay EXR, when one of them would
    pass the raw sensor's clip (1.0 camera unit) at the simulated exposure; else ``None``."""
    if options.lit_format != "dng" or not measurements.environments:
        return None
    peaks = {e.name: float(np.max(e.target_chart)) for e in measurements.environments}
    name = max(peaks, key=lambda n: peaks[n])
    if peaks[name] <= 1.0:
        return None
    lit = float(np.max(measurements.SRL))
    return (
        f"note: the location charts stay EXR: {name}'s brightest patch is {peaks[name]:.2g} "
        f"camera units, above the DNG sensor's clip (1.0; the lit charts peak at {lit:.2g})"
    )


#: Where the take goes in the plates folder, and its frames' names.
TAKE_FOLDER = "take"
TAKE_NAME = "A001.####.exr"
#: The take as a camera movie (``PlateOptions.take_format``).
TAKE_MOVIE = "A001.mov"


def practice_sequence() -> PatternSequence:
    """The built-in sequence a simulated stage films when none is given: the calibration
    sequence at 64x36 pixels, 8 frames a patch."""
    from ocio_vp.patterns.design import PatternOptions, calibration_sequence

    return calibration_sequence(PatternOptions(size=(64, 36), hold=8))


def _film_patterns(measurements, folder: Path, options: PlateOptions, sequence, ref, bar) -> str:
    """Write the take (and the built-in patterns when no sequence is given); return the
    capture file's reference to the sequence."""
    from ocio_vp.patterns.frames import write_sequence_folder
    from ocio_vp.patterns.sequence import load_sequence

    if sequence is None:
        path = write_sequence_folder(practice_sequence(), folder / "patterns")
        sequence, ref = load_sequence(path), "patterns/sequence.yaml"
    on_frame = None if bar is None else (lambda: bar.update(1))
    if options.take_format != "exr":
        from ocio_vp.simulator.movie import write_movie

        write_movie(
            sequence,
            measurements.SL,
            folder / TAKE_FOLDER / TAKE_MOVIE,
            options.take,
            codec=options.take_format,
            on_frame=on_frame,
        )
    else:
        write_take(sequence, measurements.SL, folder / TAKE_FOLDER, options.take, on_frame=on_frame)
    return ref


def plate_count(
    measurements: Measurements,
    options: PlateOptions = PlateOptions(),
    sequence: PatternSequence | None = None,
) -> int:
    """How many plates (and take frames) :func:`write_capture` writes (for a progress bar)."""
    panels = measurements.panels
    per_env = sum(
        1
        + (len(e.panel_black_level or {}) if panels else e.black_level is not None)
        + (options.footage_frames if (e.panel_w_avg if panels else e.w_avg) is not None else 0)
        for e in measurements.environments
    )
    plates = options.flat_frames + 6 * max(1, len(panels)) + per_env
    if panels or options.take is None:  # a take films one wall
        return plates
    return plates - 3 + take_frame_count(sequence or practice_sequence(), options.take)
