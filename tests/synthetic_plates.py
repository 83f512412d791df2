"""Synthetic calibration plates for the plate/sampling/measure tests (not a test module).

A plate is rendered from known patch values by mapping every pixel centre through the inverse
of the chart's homography (computed here independently of ocio_vp, from the four corner
correspondences with numpy's least squares), so perspective is exact. On top: mild radial
vignetting, per-pixel sensor noise (relative "shot" part plus an absolute read-noise part), and
optionally a clipped specular glint (a small disc) on one patch.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

SIZE = (600, 400)  # width, height: small so the tests are fast
# A 4 x 6 chart seen at an angle: TL, TR, BR, BL (not a rectangle, so perspective matters).
CORNERS = np.array([[128.0, 82.0], [478.0, 104.0], [466.0, 322.0], [140.0, 306.0]])
GAP = 0.08  # black border between patches, as a fraction of a cell (sampling insets 0.25)


def homography(corners: np.ndarray, rows: int, columns: int) -> np.ndarray:
    """Grid (u, v) -> pixel (x, y), from a 9-unknown null-space fit (SVD), not ocio_vp's DLT."""
    src = [(0, 0), (columns, 0), (columns, rows), (0, rows)]
    A = []
    for (u, v), (x, y) in zip(src, corners, strict=True):
        A.append([u, v, 1, 0, 0, 0, -x * u, -x * v, -x])
        A.append([0, 0, 0, u, v, 1, -y * u, -y * v, -y])
    h = np.linalg.svd(np.asarray(A, dtype=np.float64))[2][-1]
    return h.reshape(3, 3) / h[-1]


def vignetting_gain(size: tuple[int, int], vignetting: float) -> np.ndarray:
    """(h, w) gain 1 - v (r / r_corner)^2 about the image centre."""
    width, height = size
    ys, xs = np.mgrid[0:height, 0:width]
    r2 = ((xs + 0.5 - width / 2) ** 2 + (ys + 0.5 - height / 2) ** 2) / (
        (width / 2) ** 2 + (height / 2) ** 2
    )
    return 1 - vignetting * r2


def render_chart(
    values: np.ndarray,
    *,
    corners: np.ndarray = CORNERS,
    rows: int = 4,
    columns: int = 6,
    size: tuple[int, int] = SIZE,
    background: float = 0.01,
    vignetting: float = 0.0,
    noise: float = 0.0,
    read_noise: float = 0.0,
    highlight: int | None = None,
    highlight_value: float = 8.0,
    highlight_radius: float = 3.5,
    seed: int = 0,
) -> np.ndarray:
    """(h, w, 3) float32 linear plate of a chart with ``values`` (rows*columns, 3).

    ``vignetting`` v: gain 1 - v (r / r_corner)^2 about the image centre. ``noise``: relative
    Gaussian std; ``read_noise``: absolute std. ``highlight``: patch index that gets a clipped
    disc of ``highlight_value`` and ``highlight_radius`` pixels at its centre.
    """
    width, height = size
    values = np.asarray(values, dtype=np.float64)
    H = homography(np.asarray(corners, dtype=np.float64), rows, columns)
    ys, xs = np.mgrid[0:height, 0:width]
    centres = np.stack([xs + 0.5, ys + 0.5, np.ones_like(xs, dtype=float)], axis=-1)
    uvw = centres @ np.linalg.inv(H).T
    u, v = uvw[..., 0] / uvw[..., 2], uvw[..., 1] / uvw[..., 2]
    col, row = np.floor(u).astype(int), np.floor(v).astype(int)
    fu, fv = u - col, v - row
    inside = (col >= 0) & (col < columns) & (row >= 0) & (row < rows)
    on_patch = inside & (fu > GAP) & (fu < 1 - GAP) & (fv > GAP) & (fv < 1 - GAP)
    image = np.full((height, width, 3), background, dtype=np.float64)
    image[inside & ~on_patch] = 0.005  # the chart's black frame
    image[on_patch] = values[(row * columns + col)[on_patch]]
    image *= vignetting_gain(size, vignetting)[..., None]
    rng = np.random.default_rng(seed)
    if noise or read_noise:
        sigma = np.sqrt((noise * image) ** 2 + read_noise**2)
        image = image + sigma * rng.standard_normal(image.shape)
    if highlight is not None:
        r, c = divmod(highlight, columns)
        p = H @ [c + 0.5, r + 0.5, 1.0]
        cx, cy = p[0] / p[2], p[1] / p[2]
        disc = (xs + 0.5 - cx) ** 2 + (ys + 0.5 - cy) ** 2 <= highlight_radius**2
        image[disc] = highlight_value
    return image.astype(np.float32)


def render_regions(
    regions: dict[str, tuple[tuple[int, int, int, int], np.ndarray]],
    *,
    size: tuple[int, int] = SIZE,
    background: float = 0.002,
    vignetting: float = 0.0,
    noise: float = 0.0,
    read_noise: float = 0.0,
    seed: int = 0,
) -> np.ndarray:
    """A plate of flat rectangles ``name -> ((x0, y0, x1, y1), rgb)`` (e.g. the primaries)."""
    width, height = size
    image = np.full((height, width, 3), background, dtype=np.float64)
    for (x0, y0, x1, y1), rgb in regions.values():
        image[y0:y1, x0:x1] = rgb
    image *= vignetting_gain(size, vignetting)[..., None]
    rng = np.random.default_rng(seed)
    sigma = np.sqrt((noise * image) ** 2 + read_noise**2)
    return (image + sigma * rng.standard_normal(image.shape)).astype(np.float32)


def write_image(
    path: Path,
    image: np.ndarray,
    *,
    dtype: str = "half",
    channels: tuple[str, ...] = ("R", "G", "B"),
    scale: float = 1.0,
    tile: int = 0,
) -> Path:
    """Write ``image * scale`` with OpenImageIO as ``dtype`` ("half", "float", "uint16", ...).

    Extra channel names beyond the image's 3 get zeros; a different order is honoured by name.
    """
    import OpenImageIO as oiio

    data = np.asarray(image, dtype=np.float32) * np.float32(scale)
    h, w, _ = data.shape
    planes = []
    for name in channels:
        index = {"R": 0, "G": 1, "B": 2}.get(name.rpartition(".")[2])
        planes.append(data[..., index] if index is not None else np.zeros((h, w), np.float32))
    full = np.ascontiguousarray(np.stack(planes, axis=-1))
    if dtype.startswith("uint"):
        full = np.clip(full, 0, 1)
    spec = oiio.ImageSpec(w, h, len(channels), dtype)
    spec.channelnames = channels
    if tile:
        spec.tile_width = spec.tile_height = tile
    out = oiio.ImageOutput.create(str(path))
    assert out is not None and out.open(str(path), spec), oiio.geterror()
    assert out.write_image(full), out.geterror()
    out.close()
    return path
