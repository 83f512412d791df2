"""Fit an HDRI under the wall's peak: energy-preserving dilation of over-range light sources.

LED panels cannot emit more than their peak; as the paper spreads bright sources (Section
3.2), the *excess* of every over-range source moves, in its own colour, into the pixels closest
to it on the sphere, each filled up to the peak: no channel exceeds ``peak`` and the
solid-angle-weighted energy is kept per channel. docs/hdri.md gives the algorithm and what it
cannot keep.

References
----------
LeGendre, C., Lepicovsky, L., Debevec, P. (2022). Jointly Optimizing Color Rendition and
In-Camera Backgrounds in an RGB Virtual Production Stage. DigiPro '22, Section 3.2.
https://doi.org/10.1145/3543664.3543681
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ocio_vp.errors import InputError
from ocio_vp.formats.documents import check_regular_file
from ocio_vp.hdri.diffuse import (
    angles_to_directions,
    cosines_to,
    diffuse_integral,
    equirect_solid_angles,
    pixel_angles,
)
from ocio_vp.staging import check_not_input

__all__ = [
    "PreparedHDRI",
    "SpreadSource",
    "fit_under_peak",
    "label_sources",
    "minimum_cap_radius_deg",
    "prepare_hdri_file",
    "round_down_to",
]


@dataclass(frozen=True)
class SpreadSource:
    """One over-range source and where its excess went: ``direction`` its energy-weighted
    centre (unit vector); the largest angle to a pixel that received energy from the source's
    own pixels (``radius_deg``) and from ``direction`` (``centre_radius_deg``)."""

    pixels: int
    energy: np.ndarray
    excess: np.ndarray
    direction: np.ndarray
    radius_deg: float
    centre_radius_deg: float
    filled_pixels: int


@dataclass(frozen=True)
class PreparedHDRI:
    """The displayable map and a record of what was moved."""

    image: np.ndarray
    peak: float
    sources: tuple[SpreadSource, ...] = field(default_factory=tuple)
    #: {name: (w_avg before, w_avg after)} for the normals asked of :func:`prepare_hdri_file`.
    w_avg: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    @property
    def max_radius_deg(self) -> float:
        return max((s.radius_deg for s in self.sources), default=0.0)


def minimum_cap_radius_deg(excess: float, capacity: float) -> float:
    """Angular radius r of the cap with ``2 pi (1 - cos r) capacity = excess``: the smallest
    spread of a point source over a background with room ``capacity = peak - background``.

    Examples
    --------
    >>> round(minimum_cap_radius_deg(2 * np.pi, 1.0), 6)  # a hemisphere
    90.0
    """
    c = 1.0 - float(excess) / (2.0 * np.pi * float(capacity))
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def round_down_to(value: float, dtype: np.dtype | type) -> float:
    """The largest number representable in ``dtype`` that is <= ``value``."""
    v = np.asarray(value, dtype=dtype)
    if float(v) > value:
        v = np.nextafter(v, np.asarray(-np.inf, dtype=dtype))
    return float(v)


def label_sources(over: np.ndarray) -> tuple[np.ndarray, int]:
    """``(labels, count)`` as :func:`scipy.ndimage.label`: 8-connected components of a
    lat-long mask, joined across the longitude seam."""
    from scipy import ndimage

    labels, count = ndimage.label(over, structure=np.ones((3, 3), dtype=bool))
    if count == 0 or over.shape[1] < 2:
        return labels, count
    parent = np.arange(count + 1)

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = int(parent[a])
        return a

    left, right = labels[:, 0], labels[:, -1]
    for shift in (-1, 0, 1):  # column 0 touches column W-1 in rows r-1, r, r+1
        r = np.roll(right, shift)
        if shift == -1:
            r[-1] = 0
        elif shift == 1:
            r[0] = 0
        for a, b in {(int(x), int(y)) for x, y in zip(left, r, strict=True) if x and y}:
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([find(i) for i in range(count + 1)])
    _, dense = np.unique(roots, return_inverse=True)  # root 0 stays 0 (background)
    return dense[labels], int(dense.max())


def _check_map(rgb: np.ndarray, peak: float) -> None:
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise InputError(f"expected an (height, width, 3) image, got shape {rgb.shape}")
    height, width = rgb.shape[:2]
    if height < 2 or width != 2 * height:
        raise InputError(f"not an equirectangular (2:1) map: {width}x{height}")
    if not (np.isfinite(peak) and peak > 0):
        raise InputError(f"the peak must be a number > 0, got {peak!r}", key="--peak")


def fit_under_peak(
    rgb: ArrayLike, *, peak: float, storage_dtype: np.dtype | type | None = None
) -> PreparedHDRI:
    """Spread the excess of over-range sources so that no channel of any pixel exceeds ``peak``.

    Parameters
    ----------
    rgb
        (height, width, 3) linear equirectangular map, width = 2 height (:mod:`ocio_vp.hdri.diffuse`
        layout). Not modified.
    peak
        The largest value the wall can show, in the map's units (> 0).
    storage_dtype
        The type the result will be stored in (e.g. ``np.float16`` for a half EXR): the peak
        is rounded down to it (and to the working type) so that no stored value exceeds it.

    Returns
    -------
    PreparedHDRI
        The map (float32 if the input was, else float64) and its sources, largest first.

    Raises
    ------
    InputError
        When the map is not 2:1, has non-finite values, ``peak <= 0``, or cannot fit (its
        solid-angle-weighted mean of ``max(R, G, B)`` exceeds ``peak``).

    Examples
    --------
    >>> sky = np.full((16, 32, 3), 0.25); sky[8, 16] = 40.0
    >>> out = fit_under_peak(sky, peak=1.0)
    >>> bool(out.image.max() <= 1.0), len(out.sources)
    (True, 1)
    """
    src = np.asarray(rgb)
    _check_map(src, float(peak))
    out = src.astype(np.float32 if src.dtype == np.float32 else np.float64, copy=True)
    requested = float(peak)
    peak = _working_peak(requested, out.dtype, storage_dtype)
    height, width = out.shape[:2]
    row_omega = equirect_solid_angles(height, 1)[:, 0] / width
    brightness = np.maximum(np.maximum(out[..., 0], out[..., 1]), out[..., 2])
    if not np.all(np.isfinite(brightness)):
        raise InputError("the map has NaN or infinite pixels")
    over = brightness > peak
    if not over.any():
        return PreparedHDRI(image=out, peak=peak)
    mean = float(row_omega @ brightness.sum(axis=1, dtype=np.float64)) / (4.0 * np.pi)
    if mean > peak:
        raise InputError(
            f"the map cannot fit under peak {requested:g}: its solid-angle-weighted mean "
            f"max(R,G,B) is {mean:.6g}, above the peak (lower the exposure or raise --peak)",
            key="--peak",
        )
    del brightness
    # Remove each source's excess first (scale its pixels to the peak, chromaticity kept), so a
    # source never spreads into a neighbour that is still over range.
    pending = [
        _remove_excess(out, idx, peak=peak, row_omega=row_omega)
        for idx in _over_range_sources(over)
    ]
    pending.sort(key=lambda p: -p[0])
    sources = tuple(
        _spread(out, rows, cols, energy, excess, weight, peak=peak, row_omega=row_omega)
        for _, rows, cols, energy, excess, weight in pending
    )
    return PreparedHDRI(image=out, peak=peak, sources=sources)


def _working_peak(
    requested: float, dtype: np.dtype, storage_dtype: np.dtype | type | None
) -> float:
    """The peak rounded down to the working (and storage) type, so that values rounded to
    it stay <= peak (rounding is monotonic)."""
    peak = round_down_to(requested, dtype)
    if storage_dtype is not None:
        peak = min(peak, round_down_to(requested, storage_dtype))
    return peak


def _over_range_sources(over: np.ndarray) -> list[np.ndarray]:
    """Flat pixel indices of each over-range source (8-connected, across the seam)."""
    width = over.shape[1]
    # Label only the band of rows that holds over-range pixels (a sun is a few rows of 4096).
    band = np.flatnonzero(over.any(axis=1))
    first, last = int(band[0]), int(band[-1]) + 1
    labels, _ = label_sources(over[first:last])
    flat = np.flatnonzero(labels) + first * width
    lab = labels.ravel()[flat - first * width]
    order = np.argsort(lab, kind="stable")
    flat, lab = flat[order], lab[order]
    bounds = np.flatnonzero(np.diff(lab)) + 1
    return np.split(flat, bounds)


def _remove_excess(out: np.ndarray, idx: np.ndarray, *, peak: float, row_omega: np.ndarray):
    """Scale one source's pixels down to ``peak`` in place; return ``(max excess, rows, cols,
    energy, excess, weight)``: solid-angle-weighted RGB sums, and each pixel's largest removed
    channel energy."""
    rows, cols = np.divmod(idx, out.shape[1])
    v = out[rows, cols].astype(np.float64)
    scale = peak / v.max(axis=1)
    omega = row_omega[rows][:, None]
    moved = v * (1.0 - scale[:, None]) * omega
    excess = moved.sum(axis=0)
    energy = (v * omega).sum(axis=0)
    out[rows, cols] = (v * scale[:, None]).astype(out.dtype)
    return float(excess.max()), rows, cols, energy, excess, moved.max(axis=1)


def _pixel_directions(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    return angles_to_directions(*pixel_angles(rows, cols, shape[0], shape[1]))


@dataclass(frozen=True)
class _Candidates:
    """Pixels within ``reach`` of a source: where they are, how far, how much room they have."""

    rows: np.ndarray
    cols: np.ndarray
    dist: np.ndarray
    room: np.ndarray
    capacity: np.ndarray
    order: np.ndarray
    cumulative: np.ndarray


def _spread(
    out: np.ndarray,
    rows: np.ndarray,
    cols: np.ndarray,
    energy: np.ndarray,
    excess: np.ndarray,
    weight: np.ndarray,
    *,
    peak: float,
    row_omega: np.ndarray,
) -> SpreadSource:
    """Fill the pixels nearest to one source with its excess (docs/hdri.md, *Algorithm*)."""
    from scipy.spatial import cKDTree  # deferred: scipy is only needed when a map is over range

    amount = float(excess.max())
    if not amount > 0:  # only possible with large negative values beside the source
        raise InputError("an over-range source has no positive excess: negative pixels beside it")
    colour = excess / amount
    dirs = _pixel_directions(rows, cols, out.shape)
    centre = (dirs * weight[:, None]).sum(axis=0)  # excess-weighted centre of the source
    norm = float(np.linalg.norm(centre))
    centre = centre / norm if norm > 0 else dirs[np.argmax(weight)]
    source_radius = float(np.arccos(np.clip(dirs @ centre, -1.0, 1.0)).max())
    tree = cKDTree(dirs)
    # First guess: the cap the excess needs on a black background, then grow.
    reach = np.radians(minimum_cap_radius_deg(amount, peak)) + np.radians(0.1)
    while True:
        near = _candidates(out, tree, centre, source_radius, reach, colour, peak, row_omega)
        if near.cumulative.size and near.cumulative[-1] >= amount:
            break
        if reach >= np.pi:
            raise InputError(
                f"the map cannot fit under peak {peak:.9g}: no room left for a source's excess",
                key="--peak",
            )
        # Grow to the cap the excess needs at the room density seen so far (plus a margin).
        density = near.capacity.sum() / max(row_omega[near.rows].sum(), 1e-300)
        needed = np.radians(minimum_cap_radius_deg(amount, density)) if density > 0 else np.pi
        reach = min(np.pi, max(reach * 1.25, 1.1 * needed + source_radius))
    return _fill(out, near, amount, colour, centre, row_omega, rows.size, energy, excess)


def _window(
    centre: np.ndarray, outer: float, height: int, width: int
) -> tuple[np.ndarray, np.ndarray]:
    """Rows and (wrapped) columns of the lat-long box around the cap of radius ``outer``."""
    theta_c = float(np.arccos(np.clip(centre[1], -1.0, 1.0)))
    phi_c = float(np.arctan2(centre[0], centre[2]))
    r0 = max(0, int(np.floor((theta_c - outer) / np.pi * height)))
    r1 = min(height, int(np.ceil((theta_c + outer) / np.pi * height)) + 1)
    near_pole = theta_c - outer <= 0.0 or theta_c + outer >= np.pi
    sin_t = np.sin(theta_c)
    if near_pole or outer >= np.pi / 2 or np.sin(outer) >= sin_t:
        wcols = np.arange(width)
    else:
        half = np.arcsin(np.sin(outer) / sin_t)  # longitude half-width of the cap
        c0 = int(np.floor((phi_c - half) / (2 * np.pi) * width + width / 2)) - 1
        c1 = int(np.ceil((phi_c + half) / (2 * np.pi) * width + width / 2)) + 1
        wcols = np.arange(c0, c1 + 1) % width
        wcols = np.unique(wcols) if wcols.size >= width else wcols
    return np.arange(r0, r1), wcols


def _candidates(
    out: np.ndarray,
    tree,
    centre: np.ndarray,
    source_radius: float,
    reach: float,
    colour: np.ndarray,
    peak: float,
    row_omega: np.ndarray,
) -> _Candidates:
    """The pixels within angle ``reach`` of the source's own pixels, nearest first."""
    height, width = out.shape[:2]
    outer = min(np.pi, source_radius + reach)
    wrows, wcols = _window(centre, outer, height, width)
    th, ph = pixel_angles(wrows, wcols, height, width)
    cosine = cosines_to(centre, th, ph)
    rr, cc = np.nonzero(cosine >= np.cos(outer))
    chord, _ = tree.query(angles_to_directions(th[rr], ph[cc]), k=1)
    dist = 2.0 * np.arcsin(np.clip(chord / 2.0, 0.0, 1.0))
    keep = dist <= reach
    rr, cc, dist = wrows[rr[keep]], wcols[cc[keep]], dist[keep]
    current = out[rr, cc].astype(np.float64)
    room = np.full(rr.shape, np.inf)
    for k in range(3):
        if colour[k] > 0:
            room = np.minimum(room, (peak - current[:, k]) / colour[k])
    room = np.maximum(room, 0.0)
    capacity = room * row_omega[rr]
    order = np.argsort(dist, kind="stable")
    return _Candidates(rr, cc, dist, room, capacity, order, np.cumsum(capacity[order]))


def _fill(
    out: np.ndarray,
    near: _Candidates,
    amount: float,
    colour: np.ndarray,
    centre: np.ndarray,
    row_omega: np.ndarray,
    pixels: int,
    energy: np.ndarray,
    excess: np.ndarray,
) -> SpreadSource:
    """Fill the nearest candidates to their room until ``amount`` is placed; record it."""
    order, room = near.order, near.room
    last = int(np.searchsorted(near.cumulative, amount))
    fill = np.zeros(order.size)
    fill[order[:last]] = room[order[:last]]
    before = near.cumulative[last - 1] if last > 0 else 0.0
    fill[order[last]] = (amount - before) / row_omega[near.rows[order[last]]]
    touched = fill > 0
    rr, cc, fill = near.rows[touched], near.cols[touched], fill[touched]
    out[rr, cc] = (out[rr, cc].astype(np.float64) + fill[:, None] * colour).astype(out.dtype)
    filled_dirs = _pixel_directions(rr, cc, out.shape)
    return SpreadSource(
        pixels=int(pixels),
        energy=energy,
        excess=excess,
        direction=centre,
        radius_deg=float(np.degrees(near.dist[order[last]])),
        centre_radius_deg=float(
            np.degrees(np.arccos(np.clip(filled_dirs @ centre, -1.0, 1.0)).max())
        ),
        filled_pixels=int(touched.sum()),
    )


def _rgb_channels(names: list[str], source: str) -> list[int]:
    lower = [n.lower() for n in names]
    if all(c in lower for c in "rgb"):
        return [lower.index(c) for c in "rgb"]
    if len(names) >= 3:  # unnamed channels: the first three are RGB (OIIO's convention)
        return [0, 1, 2]
    raise InputError(f"an HDRI needs RGB, the file has channels {names}", source=source)


def _check_target(oiio, source: str, target: Path) -> None:
    """The output may replace neither the input nor an image prepare-hdri did not write."""
    check_not_input([target], [source])
    if not os.path.lexists(target):
        return
    if target.is_file() and not target.is_symlink():
        image = oiio.ImageInput.open(str(target))
        if image is not None:
            written = bool(image.spec().get_string_attribute("ocio_vp:prepare_hdri"))
            image.close()
            if written:
                return
        oiio.geterror()
    raise InputError(
        "exists and is not an image prepare-hdri wrote; move it away or choose another --out",
        source=str(target),
    )


def prepare_hdri_file(
    in_path: str | Path,
    out_path: str | Path,
    *,
    peak: float,
    normals: Mapping[str, ArrayLike] | None = None,
) -> PreparedHDRI:
    """Read an equirectangular HDRI, :func:`fit_under_peak` its RGB, write it (atomically).

    Other channels and metadata are copied, ``ocio_vp:prepare_hdri`` records the peak; the
    pixel type stays half or float (integers become half), the EXR compression stays (else
    zip). ``normals`` ({name: direction}) fills :attr:`PreparedHDRI.w_avg` before and after.

    Raises
    ------
    InputError
        Missing or unreadable file, not 2:1, no RGB, non-finite pixels, ``peak <= 0``, a map
        that cannot fit, or an output format OpenImageIO cannot write. Nothing is written then.
    """
    import OpenImageIO as oiio  # deferred: heavy, and only this verb writes images

    source, target = str(in_path), Path(out_path)
    if not (np.isfinite(peak) and peak > 0):
        raise InputError(f"the peak must be a number > 0, got {peak!r}", key="--peak")
    if not os.path.lexists(source):
        raise InputError("no such file", source=source)
    check_regular_file(source)  # a FIFO or device would block or never end
    _check_target(oiio, source, target)
    probe = oiio.ImageOutput.create(str(target))
    if probe is None:
        oiio.geterror()
        raise InputError("OpenImageIO cannot write this file type", source=str(target))
    spec, pixels = _read_image(oiio, source)
    rgb_index = _rgb_channels(list(spec.channelnames), source)
    half = oiio.TypeDesc(oiio.HALF)
    out_format = spec.format if spec.format.basetype in (oiio.HALF, oiio.FLOAT) else half
    storage = np.float16 if out_format.basetype == oiio.HALF else np.float32
    rgb = pixels[..., rgb_index]  # a copy: fit_under_peak leaves it as read
    try:
        prepared = fit_under_peak(rgb, peak=peak, storage_dtype=storage)
    except InputError as err:
        raise InputError(err.problem, source=source, key=err.key) from None
    w_avg = {
        name: (diffuse_integral(rgb, normal=n), diffuse_integral(prepared.image, normal=n))
        for name, n in (normals or {}).items()
    }
    pixels[..., rgb_index] = prepared.image
    prepared = dataclasses.replace(prepared, w_avg=w_avg)
    out_spec = oiio.ImageSpec(spec)
    out_spec.set_format(out_format)
    out_spec.tile_width = out_spec.tile_height = out_spec.tile_depth = 0
    if target.suffix.lower() == ".exr" and not str(spec.get_string_attribute("compression")):
        out_spec.attribute("compression", "zip")
    out_spec.attribute(
        "ocio_vp:prepare_hdri",
        f"peak={peak:.9g} (applied {prepared.peak:.9g}); sources={len(prepared.sources)}; "
        f"radius_deg={prepared.max_radius_deg:.4g} (energy-preserving spread, ocio-vp)",
    )
    _write_image_atomically(oiio, target, out_spec, pixels)
    return prepared


def _read_image(oiio, source: str):
    """(spec, (height, width, channels) float32 pixels) of the first subimage of ``source``."""
    inp = oiio.ImageInput.open(source)
    if inp is None:
        raise InputError(f"not an image OpenImageIO can read ({oiio.geterror()})", source=source)
    try:
        spec = oiio.ImageSpec(inp.spec())
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        error = inp.geterror()
    finally:
        inp.close()
    if pixels is None or error:
        raise InputError(f"cannot read the image: {error or 'no pixels'}", source=source)
    return spec, np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, -1)


def _write_image_atomically(oiio, target: Path, out_spec, pixels: np.ndarray) -> None:
    """Write to a hidden temporary beside ``target``, then rename it over (never half a file)."""
    tmp = target.with_name(f".{target.stem}.tmp-{os.getpid()}{target.suffix}")
    try:
        out = oiio.ImageOutput.create(str(tmp))
        ok = out is not None and out.open(str(tmp), out_spec)
        ok = ok and out.write_image(pixels)
        ok = out.close() and ok if out is not None else False
        if not ok:
            message = (out.geterror() if out is not None else "") or oiio.geterror()
            raise InputError(f"cannot write the image: {message}", source=str(target))
        os.replace(tmp, target)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
