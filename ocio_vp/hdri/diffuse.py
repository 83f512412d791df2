"""w_avg from an equirectangular HDRI: the diffuse integral of the frontal hemisphere, for
``ocio-vp solve --hdri ENV=FILE`` (per panel type on a stage of several, from the directions
each covers). :func:`pixel_angles`, :func:`angles_to_directions` and :func:`cosines_to` are the
one place the lat-long direction formula lives (:mod:`ocio_vp.hdri.prepare` uses them).

Convention: y is up; row 0 is the zenith, the last row the nadir; the centre of the image
(u = 0.5, v = 0.5) looks along +z (:data:`FRONT`), and u increasing turns towards +x. A pixel
at (u, v) in [0, 1)^2 has polar angle ``theta = pi v`` from +y and azimuth ``phi = 2 pi (u -
0.5)`` from +z, direction ``(sin theta sin phi, cos theta, sin theta cos phi)``.

The HDRI must hold the same linear RGB as the measurements (the camera's native linear RGB,
as in the paper): no colour conversion is applied here.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, Section 3.3 ("the
diffuse integral of the frontal hemisphere of the HDRI map", w_avg).
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError
from ocio_vp.formats.documents import check_regular_file

__all__ = [
    "DEFAULT_HDRI_WIDTH",
    "FRONT",
    "angles_to_directions",
    "cosines_to",
    "diffuse_integral",
    "environments_with_hdri",
    "equirect_directions",
    "equirect_solid_angles",
    "panel_w_avg",
    "pixel_angles",
    "read_equirect",
    "region_mask",
    "w_avg_from_hdri",
]

#: Default working width for w_avg (its error per width: benchmarks/bench_wavg.py).
DEFAULT_HDRI_WIDTH = 1024

#: The direction of the image centre, the default normal of the chart.
FRONT = (0.0, 0.0, 1.0)

_ROWS_PER_BLOCK = 256  # bounds the temporary (rows, width) arrays at 8K to a few MB


def pixel_angles(
    rows: ArrayLike, cols: ArrayLike, height: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """Polar angle ``theta`` (from +Y) and longitude ``phi`` (from +Z) of pixel centres.

    ``rows`` and ``cols`` are pixel indices (any shapes); row ``r`` of ``height`` is centred at
    ``theta = (r + 1/2) pi / height``, column ``c`` of ``width`` at
    ``phi = ((c + 1/2) / width - 1/2) 2 pi`` (the image centre looks along +Z).

    Examples
    --------
    >>> theta, phi = pixel_angles(np.array([0]), np.array([2]), 2, 4)
    >>> float(theta[0] / np.pi), float(phi[0] / np.pi)
    (0.25, 0.25)
    """
    theta = (np.asarray(rows, dtype=np.float64) + 0.5) * (np.pi / height)
    phi = ((np.asarray(cols, dtype=np.float64) + 0.5) / width - 0.5) * (2.0 * np.pi)
    return theta, phi


def angles_to_directions(theta: ArrayLike, phi: ArrayLike) -> np.ndarray:
    """Unit vectors ``(sin t sin p, cos t, sin t cos p)`` of polar angles and longitudes
    (broadcast together; the result has one more axis of length 3).

    Examples
    --------
    >>> angles_to_directions(np.pi / 2, 0.0).round(12).tolist()
    [0.0, 0.0, 1.0]
    """
    theta, phi = np.broadcast_arrays(np.asarray(theta, np.float64), np.asarray(phi, np.float64))
    st = np.sin(theta)
    return np.stack([st * np.sin(phi), np.cos(theta), st * np.cos(phi)], axis=-1)


def cosines_to(direction: np.ndarray, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(len(theta), len(phi)) cosine between unit ``direction`` and each lat-long position.

    ``d.w = sin(theta) (dx sin(phi) + dz cos(phi)) + dy cos(theta)`` is separable in
    ``(theta, phi)``, so no (rows, cols, 3) direction array is built.

    Examples
    --------
    >>> cosines_to(np.array([0.0, 0.0, 1.0]), np.array([np.pi / 2]), np.array([0.0])).tolist()
    [[1.0]]
    """
    azimuthal = direction[0] * np.sin(phi) + direction[2] * np.cos(phi)
    return np.sin(theta)[:, None] * azimuthal[None, :] + direction[1] * np.cos(theta)[:, None]


def _angles(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    return pixel_angles(np.arange(height), np.arange(width), height, width)


def equirect_solid_angles(height: int, width: int) -> np.ndarray:
    """Solid angle (steradians) of each pixel of an equirectangular image.

    Exact for the lat-long cell: a row between polar angles theta0 and theta1 spans
    ``(2 pi / width) (cos theta0 - cos theta1)``. The values sum to 4 pi.

    Examples
    --------
    >>> round(float(equirect_solid_angles(4, 8).sum() / np.pi), 12)
    4.0
    """
    if height < 1 or width < 1:
        raise ValueError(f"expected height, width >= 1, got {height}, {width}")
    edges = np.cos(np.arange(height + 1, dtype=np.float64) * (np.pi / height))
    row = (edges[:-1] - edges[1:]) * (2.0 * np.pi / width)
    return np.broadcast_to(row[:, None], (height, width)).copy()


def equirect_directions(height: int, width: int) -> np.ndarray:
    """(height, width, 3) unit direction of each pixel centre (module convention)."""
    theta, phi = _angles(height, width)
    return angles_to_directions(theta[:, None], phi[None, :])


def _unit(normal: ArrayLike) -> np.ndarray:
    n = np.asarray(normal, dtype=np.float64).reshape(-1)
    norm = float(np.linalg.norm(n)) if n.shape == (3,) else 0.0
    if not np.isfinite(norm) or norm == 0.0:
        raise InputError(f"the normal must be a non-zero 3-vector, got {normal!r}")
    return n / norm


def diffuse_integral(image: ArrayLike, *, normal: ArrayLike = FRONT) -> np.ndarray:
    """The diffuse integral ``(1/pi) integral L(w) max(0, n.w) dw`` of an equirectangular image.

    This is the paper's w_avg (Section 3.3): the radiance a perfect white Lambertian patch
    facing ``normal`` would show. A uniform sky of radiance L gives exactly L; a small source
    of radiance L and solid angle Omega at angle t from the normal gives ``L Omega cos(t) / pi``.

    Parameters
    ----------
    image
        (height, width, channels) linear radiance in lat-long layout (module convention).
    normal
        Direction the patch faces (it receives light from that hemisphere); default the image
        centre, :data:`FRONT`.

    Returns
    -------
    numpy.ndarray
        (channels,) float64.

    Examples
    --------
    >>> sky = np.full((32, 64, 3), 2.0)
    >>> np.round(diffuse_integral(sky), 3).tolist()  # uniform sky -> its radiance
    [2.0, 2.0, 2.0]
    """
    img = np.asarray(image)
    if img.ndim != 3:
        raise ValueError(f"expected an image of shape (height, width, channels), got {img.shape}")
    n = _unit(normal)
    height, width, channels = img.shape
    theta, phi = _angles(height, width)
    row_omega = equirect_solid_angles(height, 1)[:, 0] / width
    total = np.zeros(channels, dtype=np.float64)
    for start in range(0, height, _ROWS_PER_BLOCK):
        rows = slice(start, min(start + _ROWS_PER_BLOCK, height))
        cosine = cosines_to(n, theta[rows], phi)
        weight = np.maximum(cosine, 0.0) * row_omega[rows, None]
        total += np.einsum("hw,hwc->c", weight, img[rows].astype(np.float64, copy=False))
    return total / np.pi


def read_equirect(path: str | Path, *, width: int | None = DEFAULT_HDRI_WIDTH) -> np.ndarray:
    """(height, width, 3) float32 RGB of an equirectangular HDRI at about ``width`` pixels
    wide: a MIP level of that width, else the nearest larger level box-filtered down (no
    negative lobes to lose a sun's energy); ``None`` (or wider than the file) reads it whole.

    Raises
    ------
    InputError
        Missing/unreadable file, fewer than 3 channels, not 2:1, or non-finite pixels.
    """
    import OpenImageIO as oiio

    source = str(path)
    if not os.path.lexists(source):
        raise InputError("no such HDRI file", source=source)
    check_regular_file(source)  # a FIFO or device would block or never end
    inp = oiio.ImageInput.open(source)
    if inp is None:
        raise InputError(f"cannot read the HDRI: {oiio.geterror()}", source=source)
    try:
        levels: list[tuple[int, int, int]] = []
        while inp.seek_subimage(0, len(levels)):
            spec = inp.spec()
            levels.append((spec.width, spec.height, spec.nchannels))
    finally:
        inp.close()
    full_w, full_h, nchannels = levels[0]
    if nchannels < 3:
        raise InputError(f"an HDRI needs RGB, the file has {nchannels} channel(s)", source=source)
    if abs(full_w - 2 * full_h) > 1:
        raise InputError(f"not an equirectangular (2:1) image: {full_w}x{full_h}", source=source)
    if width is not None and width < 4:
        raise InputError(f"the HDRI width must be >= 4, got {width}", source=source, key="width")
    target = full_w if width is None else min(int(width), full_w)
    level = max(i for i, (w, _, _) in enumerate(levels) if w >= target)
    buf = oiio.ImageBuf(source, 0, level)
    if target != levels[level][0]:
        roi = oiio.ROI(0, target, 0, max(1, round(target * full_h / full_w)), 0, 1, 0, 3)
        buf = oiio.ImageBufAlgo.resize(buf, "box", 0.0, roi)
    pixels = buf.get_pixels(oiio.FLOAT)
    if buf.has_error or pixels is None:
        raise InputError(f"cannot read the HDRI: {buf.geterror()}", source=source)
    pixels = np.asarray(pixels, dtype=np.float32)
    pixels = pixels.reshape(pixels.shape[0], pixels.shape[1], -1)[..., :3]
    if not np.all(np.isfinite(pixels)):
        raise InputError("the HDRI has NaN or infinite pixels", source=source)
    return pixels


def w_avg_from_hdri(
    path: str | Path, *, width: int | None = DEFAULT_HDRI_WIDTH, normal: ArrayLike = FRONT
) -> np.ndarray:
    """The paper's w_avg (Section 3.3), (3,) float64 in the HDRI's linear RGB: the
    :func:`diffuse_integral` about ``normal`` of the HDRI read at ``width``.

    Raises
    ------
    InputError
        When no channel of it is above zero (the frontal hemisphere is black).
    """
    w_avg = diffuse_integral(read_equirect(path, width=width), normal=normal)
    if not np.any(w_avg > 0):
        raise InputError(
            "the frontal hemisphere (the half of the map around its centre) is black: w_avg "
            "would be 0; check the map's orientation (its centre faces the wall) and exposure",
            source=path,
        )
    return w_avg


def region_mask(height: int, width: int, regions) -> np.ndarray:
    """(height, width) bool: the pixels whose centre lies in any of ``regions``
    (:class:`ocio_vp.formats.panels.PanelRegion`, degrees: elevation from the horizon,
    azimuth from the image centre towards +x). Intervals are half-open, closed at +90 and
    +180, so boxes that share an edge share no pixel.

    Examples
    --------
    >>> from ocio_vp.formats.panels import PanelRegion
    >>> int(region_mask(4, 8, [PanelRegion(elevation=(0.0, 90.0))]).sum())  # the upper half
    16
    """
    theta, phi = _angles(height, width)
    elevation = 90.0 - np.degrees(theta)[:, None]
    azimuth = np.degrees(phi)[None, :]
    mask = np.zeros((height, width), dtype=bool)
    for region in regions:
        (e0, e1), (a0, a1) = region.elevation, region.azimuth
        rows = (elevation >= e0) & ((elevation < e1) | (e1 >= 90.0))
        cols = (azimuth >= a0) & ((azimuth < a1) | (a1 >= 180.0))
        mask |= rows & cols
    return mask


def panel_w_avg(
    image: ArrayLike, panels, *, normal: ArrayLike = FRONT
) -> tuple[dict[str, np.ndarray], float]:
    """Each panel type's part of w_avg: :func:`diffuse_integral` over the directions of its
    regions only, and the share (0-1, green channel) of the whole diffuse integral that comes
    from directions no panel type covers (light the stage cannot give back).

    Raises
    ------
    InputError
        When a panel type has no region (``panels[i].region``).
    """
    img = np.asarray(image)
    height, width = img.shape[:2]
    parts = {}
    for i, panel in enumerate(panels):
        if not panel.regions:
            raise InputError(
                "no region: the HDRI's light cannot be split between the panel types without "
                "each one's place in the volume ({elevation: [min, max], azimuth: [min, max]})",
                key=f"panels[{i}].region",
            )
        mask = region_mask(height, width, panel.regions)
        parts[panel.name] = diffuse_integral(img * mask[..., None], normal=normal)
    total = diffuse_integral(img, normal=normal)
    covered = sum(parts.values(), np.zeros_like(total))
    uncovered = (total[1] - covered[1]) / total[1] if total[1] > 0 else 0.0
    return parts, float(max(uncovered, 0.0))


def environments_with_hdri(
    measurements, environments, hdri: Sequence[str], *, width: int | None = DEFAULT_HDRI_WIDTH
) -> tuple[tuple, list[str]]:
    """The environments, each named in ``hdri`` (``ENV=FILE``; a bare ``FILE`` when one
    environment is solved) with its HDRI's w_avg, and one line per HDRI for the user comparing
    it with the white-patch estimate."""
    from ocio_vp.calibration.geometry import w_avg_from_white_patch

    by_name = {env.name: env for env in environments}
    chosen: dict[str, str] = {}
    for item in hdri:
        name, sep, path = item.partition("=")
        if not sep:
            if len(environments) != 1:
                raise InputError(
                    f"name the environment: --hdri ENV=FILE (solving {len(environments)})",
                    key="--hdri",
                )
            name, path = environments[0].name, item
        if name not in by_name:
            raise InputError(
                f"no environment {name!r} is being solved; known: {', '.join(by_name)}",
                key="--hdri",
            )
        if name in chosen:
            raise InputError(f"two HDRIs for environment {name!r}", key="--hdri")
        chosen[name] = path
    notes = []
    out = []
    for env in environments:
        if env.name in chosen and measurements.panels:
            env, note = _panels_from_hdri(measurements, env, chosen[env.name], width)
            notes.append(note)
        elif env.name in chosen:
            w_avg = w_avg_from_hdri(chosen[env.name], width=width)
            stage = measurements.stage
            patch = w_avg_from_white_patch(
                env.target_chart, stage.white_patch, stage.white_reflectance
            )
            notes.append(
                f"{env.name}: w_avg from {chosen[env.name]} = {np.round(w_avg, 5).tolist()} "
                f"(white patch / reflectance gives {np.round(patch, 5).tolist()})"
            )
            env = dataclasses.replace(env, w_avg=w_avg)
        out.append(env)
    return tuple(out), notes


def _panels_from_hdri(measurements, env, path: str, width: int | None) -> tuple:
    """An environment of a stage of several panel types with each type's w_avg from ``path``."""
    try:
        parts, uncovered = panel_w_avg(read_equirect(path, width=width), measurements.panels)
    except InputError as error:
        raise InputError(error.problem, source=measurements.source, key=error.key) from None
    if not any(np.any(v > 0) for v in parts.values()):
        raise InputError("no light in any panel type's region", source=path, key="--hdri")
    values = ", ".join(f"{name} {np.round(v, 5).tolist()}" for name, v in parts.items())
    note = f"{env.name}: w_avg per panel type from {path}: {values}"
    if uncovered > 0.005:
        note += (
            f"; {100 * uncovered:.0f}% of the diffuse light comes from directions no panel type "
            "covers (the stage cannot give it back)"
        )
    return dataclasses.replace(env, panel_w_avg=parts), note
