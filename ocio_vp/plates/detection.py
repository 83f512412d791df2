"""Chart detection for a chart shot without ``corners``, on numpy and scipy (docs/capture.md,
*Chart detection*). The plate is block-averaged to at most :data:`WORKING_WIDTH` pixels across,
then:

1. **Patches**: regions of small log-colour gradient that are compact, about as full as the
   ellipse of their second moments, and not elongated.
2. **Grid**: from a candidate and its neighbours a lattice is grown ring by ring, a homography
   refitted each time; of a few seeds the lattice holding most candidates wins.
3. **Which way up**: a ColorChecker 24 by its neutral row; other grids must be complete, patch 0
   nearest the top-left.

The chart's corners follow from the grid homography; a failure says why (:class:`Detection`)
and :func:`detection_overlay` shows what was searched.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ocio_vp.deprecation import deprecated_names, warn_deprecated
from ocio_vp.errors import InputError
from ocio_vp.plates.reader import PlateInfo, block_means
from ocio_vp.plates.sampling import apply_homography

__all__ = [
    "MIN_PATCH_PIXELS",
    "WORKING_WIDTH",
    "Detection",
    "DetectionError",
    "detect_chart",
    "detect_chart_corners",
    "detection_overlay",
]

#: The widest image the search runs on (plates wider are block-averaged down to it).
WORKING_WIDTH = 1600
#: The smallest patch pitch (plate pixels) a found chart may have: below it the patches leave
#: too few pixels to sample after the inset.
MIN_PATCH_PIXELS = 12
#: Smallest share of the candidates' patches a grid needs, and smallest count.
_MIN_MEMBERS = 8
#: What the search tells a user to do instead (the capture file's key).
INSTEAD = "give its corners [[x, y] x 4]"


@dataclass(frozen=True)
class Detection:
    """What the search found on one plate.

    ``corners``: (4, 2) TL, TR, BR, BL in plate pixels, or ``None`` with ``reason`` (``too
    dark``, ``clipped``, ``too small``, ``not found``) and ``detail``. ``image`` is the working
    image (linear RGB) of the plate, ``scale`` plate pixels per working pixel; ``regions``
    labels its patch-like regions (0 = none, k = candidate k - 1) and ``members`` says which
    candidates are in the grid. ``residual``: RMS distance (plate pixels) of the grid's patch
    centres from the fitted grid.
    """

    corners: np.ndarray | None
    reason: str | None
    detail: str
    image: np.ndarray = field(repr=False)
    scale: int
    regions: np.ndarray = field(repr=False)
    members: np.ndarray
    residual: float = float("nan")
    #: Indices of the chart's patches found as patches (the others were covered, or as dark as
    #: the chart's frame: their samples are the corners' extrapolation, check the overlay).
    seen: tuple[int, ...] = ()

    @property
    def found(self) -> bool:
        """Deprecated (until :data:`ocio_vp.deprecation.REMOVED_IN`): ``corners is not None``."""
        warn_deprecated("Detection.found", "detection.corners is not None")
        return self.corners is not None

    @property
    def patches_found(self) -> int:
        return int(np.count_nonzero(self.members))

    def message(self) -> str:
        """One line: the reason and what to give instead."""
        return f"{self.reason}: chart not found, {INSTEAD} ({self.detail})"


class DetectionError(InputError):
    """Detection failed on a plate; ``detection`` holds what was searched (for the overlay),
    ``name`` the plate's short file-safe name."""

    def __init__(
        self,
        detection: Detection,
        *,
        source: object = None,
        key: str | None = None,
        name: str = "chart",
    ) -> None:
        super().__init__(detection.message(), source=source, key=key)
        self.detection = detection
        self.name = name


# -- the working image -------------------------------------------------------------------------


def _noise(lum: np.ndarray) -> float:
    """Per-pixel noise of ``lum``: robust spread of horizontal neighbour differences."""
    d = np.diff(lum, axis=1).ravel()
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


def _clipped_share(image: np.ndarray) -> float:
    """Share of pixels at the plate's maximum in some channel (a plateau = a clip)."""
    top = image.max()
    if not top > 0:
        return 0.0
    return float(np.mean(np.any(image >= top * (1 - 1e-4), axis=2)))


# -- patch candidates --------------------------------------------------------------------------


@dataclass(frozen=True)
class _Candidates:
    centres: np.ndarray  # (n, 2) working pixels, continuous coordinates
    areas: np.ndarray  # (n,)
    labels: np.ndarray  # (h, w) 0 none, k = candidate k - 1


def _candidates(image: np.ndarray, bright: float) -> _Candidates:
    """Compact regions of near-constant colour (see the module docstring, step 1)."""
    from scipy import ndimage

    logs = np.log(np.maximum(image, 0.0) + 0.02 * bright)
    grad = np.zeros(image.shape[:2])
    for c in range(3):
        smooth = ndimage.gaussian_filter(logs[..., c], 1.0)
        gx, gy = ndimage.sobel(smooth, axis=1) / 8, ndimage.sobel(smooth, axis=0) / 8
        grad = np.maximum(grad, np.hypot(gx, gy))
    threshold = max(0.08, 6 * float(np.median(grad)))
    labels, n = ndimage.label(grad < threshold)
    index = np.arange(1, n + 1)
    area = ndimage.sum_labels(np.ones_like(grad), labels, index)
    h, w = image.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w]
    sx, sy = ndimage.sum_labels(xs, labels, index), ndimage.sum_labels(ys, labels, index)
    sxx = ndimage.sum_labels(xs * xs, labels, index)
    syy = ndimage.sum_labels(ys * ys, labels, index)
    sxy = ndimage.sum_labels(xs * ys, labels, index)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx, my = sx / area, sy / area
        cxx, cyy, cxy = sxx / area - mx**2, syy / area - my**2, sxy / area - mx * my
        det = np.maximum(cxx * cyy - cxy**2, 0.0)
        fill = area / (4 * np.pi * np.sqrt(det))  # 1 for an ellipse, 0.955 for a square
        half = np.sqrt(((cxx - cyy) / 2) ** 2 + cxy**2)
        elongation = np.sqrt((cxx + cyy) / 2 + half) / np.sqrt(
            np.maximum((cxx + cyy) / 2 - half, 1e-12)
        )
    keep = (area >= 4) & (area <= grad.size / 20) & (fill > 0.8) & (fill < 1.05)
    keep &= elongation < 3.0
    kept = index[keep]
    relabel = np.zeros(n + 1, dtype=np.int32)
    relabel[kept] = np.arange(1, len(kept) + 1)
    centres = np.stack([mx[keep], my[keep]], axis=1) + 0.5
    return _Candidates(centres, area[keep], relabel[labels])


# -- the lattice -------------------------------------------------------------------------------


def fit_homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    """Least-squares homography ``dst ~ H src`` (normalised DLT); ``None`` if ill-conditioned.

    Examples
    --------
    >>> src = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]])
    >>> H = fit_homography(src, 2 * src + 3)
    >>> bool(np.allclose(H, [[2, 0, 3], [0, 2, 3], [0, 0, 1]]))
    True
    """

    def normaliser(p: np.ndarray) -> np.ndarray:
        centre, spread = p.mean(axis=0), np.sqrt(((p - p.mean(axis=0)) ** 2).sum(axis=1).mean())
        s = np.sqrt(2) / max(spread, 1e-12)
        return np.array([[s, 0, -s * centre[0]], [0, s, -s * centre[1]], [0, 0, 1]])

    if len(src) < 4:
        return None
    Ts, Td = normaliser(src), normaliser(dst)
    a = np.c_[src, np.ones(len(src))] @ Ts.T
    b = np.c_[dst, np.ones(len(dst))] @ Td.T
    rows = []
    for (u, v, _), (x, y, _) in zip(a, b, strict=True):
        rows.append([u, v, 1, 0, 0, 0, -x * u, -x * v, -x])
        rows.append([0, 0, 0, u, v, 1, -y * u, -y * v, -y])
    _, s, vt = np.linalg.svd(np.asarray(rows))
    if len(s) < 9 or s[-2] < 1e-6 * s[0]:  # the null space is not one line: degenerate points
        return None
    H = np.linalg.inv(Td) @ vt[-1].reshape(3, 3) @ Ts
    return H / H[2, 2] if abs(H[2, 2]) > 1e-12 else None


def _quad_centroids(quads: np.ndarray) -> np.ndarray:
    """Area centroids (n, 2) of quadrilaterals (n, 4, 2)."""
    x, y = quads[..., 0], quads[..., 1]
    xn, yn = np.roll(x, -1, axis=1), np.roll(y, -1, axis=1)
    cross = x * yn - xn * y
    area = cross.sum(axis=1) / 2
    cx = ((x + xn) * cross).sum(axis=1) / (6 * area)
    cy = ((y + yn) * cross).sum(axis=1) / (6 * area)
    return np.stack([cx, cy], axis=1)


def _grid_fit(ij: np.ndarray, centres: np.ndarray, areas: np.ndarray):
    """The homography lattice -> image fitted to the patches' centroids, and the centroids
    with the bias of perspective taken out (a projected square's centroid is not the projection
    of its centre: the fit is repeated with each patch's region modelled as a square of its own
    area about its lattice point), or ``None``."""
    src = ij.astype(float)
    H = fit_homography(src, centres)
    corrected = centres
    offsets = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    for _ in range(3):
        if H is None:
            return None
        det = np.array([abs(np.linalg.det(_jacobian(H, p))) for p in src])
        half = 0.5 * np.sqrt(areas / np.maximum(det, 1e-12))
        quads = src[:, None, :] + half[:, None, None] * offsets[None]
        projected = apply_homography(H, quads.reshape(-1, 2)).reshape(-1, 4, 2)
        corrected = centres - (_quad_centroids(projected) - apply_homography(H, src))
        H = fit_homography(src, corrected)
    return None if H is None else (H, corrected)


def _affine(src: np.ndarray, dst: np.ndarray) -> np.ndarray | None:
    """The affine map as a 3x3 homography, or ``None`` when the points are collinear."""
    A = np.c_[src, np.ones(len(src))]
    if len(src) < 3 or np.linalg.matrix_rank(A, tol=1e-9) < 3:
        return None
    coef = np.linalg.lstsq(A, dst, rcond=None)[0]
    return np.vstack([coef.T, [0, 0, 1]])


def _grow(c: _Candidates, seed: int, a: np.ndarray, b: np.ndarray) -> dict[tuple[int, int], int]:
    """Lattice coordinates -> candidate, grown from ``seed`` with first steps ``a``, ``b``."""
    pitch = min(np.hypot(*a), np.hypot(*b))
    H = np.array([[a[0], b[0], c.centres[seed, 0]], [a[1], b[1], c.centres[seed, 1]], [0, 0, 1]])
    members: dict[tuple[int, int], int] = {(0, 0): seed}
    for _ in range(12):
        ij = np.array(list(members))
        lo, hi = ij.min(axis=0) - 1, ij.max(axis=0) + 1
        grid = np.array([(i, j) for i in range(lo[0], hi[0] + 1) for j in range(lo[1], hi[1] + 1)])
        predicted = apply_homography(H, grid.astype(float))
        d = np.linalg.norm(predicted[:, None, :] - c.centres[None, :, :], axis=2)
        nearest = d.argmin(axis=1)
        close = d[np.arange(len(grid)), nearest] < 0.3 * pitch
        claimed: dict[int, tuple[float, tuple[int, int]]] = {}
        for g in np.flatnonzero(close):
            k, dist = int(nearest[g]), float(d[g, nearest[g]])
            if k not in claimed or dist < claimed[k][0]:
                claimed[k] = (dist, (int(grid[g, 0]), int(grid[g, 1])))
        new = {where: k for k, (_, where) in claimed.items()}
        src = np.array(list(new), dtype=float)
        dst = c.centres[list(new.values())]
        fit = fit_homography(src, dst) if len(new) >= 6 else None
        fit = fit if fit is not None else _affine(src, dst)
        if fit is None or new == members:
            members = new if fit is not None else members
            break
        members, H = new, fit
    return members


def _seeds(c: _Candidates, count: int = 10) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Up to ``count`` (candidate, step a, step b) to grow from: candidates with two
    near neighbours of similar size at about a right angle, most typical size first."""
    out = []
    size = np.sqrt(c.areas)
    order = np.argsort(np.abs(np.log(size / np.median(size))))
    for k in order:
        d = c.centres - c.centres[k]
        dist = np.hypot(d[:, 0], d[:, 1])
        similar = (size > 0.5 * size[k]) & (size < 2 * size[k])
        ok = similar & (dist > 0.9 * size[k]) & (dist < 3.0 * size[k])
        near = np.flatnonzero(ok)[np.argsort(dist[ok])]
        if len(near) < 2:
            continue
        a = d[near[0]]
        for j in near[1:]:
            cosine = abs(np.dot(a, d[j])) / (np.hypot(*a) * dist[j])
            if cosine < 0.5:
                out.append((int(k), a, d[j]))
                break
        if len(out) >= count:
            break
    return out


def _lattice(c: _Candidates, rows: int, columns: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(lattice coordinates (m, 2) from 0, candidate indices (m,)) of the best grid found."""
    best: tuple[np.ndarray, np.ndarray] | None = None
    for seed, a, b in _seeds(c):
        members = _grow(c, seed, a, b)
        ij = np.array(list(members))
        ij -= ij.min(axis=0)
        short, long = sorted(ij.max(axis=0) + 1)
        if short > min(rows, columns) or long > max(rows, columns):  # larger than the chart
            continue
        if best is None or len(members) > len(best[1]):
            best = ij, np.array(list(members.values()))
        if len(members) == rows * columns:
            break
    return best


# -- which way up ------------------------------------------------------------------------------

#: The 8 ways the chart's (column, row) axes can lie along the lattice's (i, j).
_AXES = [
    np.array(m)
    for m in (
        [[1, 0], [0, 1]], [[-1, 0], [0, 1]], [[1, 0], [0, -1]], [[-1, 0], [0, -1]],
        [[0, 1], [1, 0]], [[0, -1], [1, 0]], [[0, 1], [-1, 0]], [[0, -1], [-1, 0]],
    )
]  # fmt: skip


def _placements(ij: np.ndarray, rows: int, columns: int):
    """Every (3x3 chart -> lattice map) under which the found lattice lies inside the chart."""
    span = ij.max(axis=0)
    for R in _AXES:
        corners = np.array([[0, 0], [columns - 1, 0], [0, rows - 1], [columns - 1, rows - 1]]) @ R.T
        lo, hi = corners.min(axis=0), corners.max(axis=0)
        for oi in range(-hi[0], -lo[0] + 1):
            for oj in range(-hi[1], -lo[1] + 1):
                shift = np.array([oi, oj])
                if np.all(lo + shift <= 0) and np.all(hi + shift >= span):
                    yield np.array([[R[0, 0], R[0, 1], oi], [R[1, 0], R[1, 1], oj], [0, 0, 1]])


def _colours(image: np.ndarray, centres: np.ndarray, pitch: float) -> np.ndarray:
    """Median RGB in a small square about each (working-pixel) centre."""
    h, w = image.shape[:2]
    r = max(1, int(0.12 * pitch))
    out = np.zeros((len(centres), 3))
    for k, (x, y) in enumerate(centres):
        cx, cy = min(max(int(x), r), w - r - 1), min(max(int(y), r), h - r - 1)
        out[k] = np.median(image[cy - r : cy + r + 1, cx - r : cx + r + 1].reshape(-1, 3), 0)
    return out


def _ramp_score(row: list[np.ndarray | None]) -> float:
    """How much ``row`` (six RGB, ``None`` where not seen) looks like a ColorChecker's neutral
    row, white to black: the mean log-luminance step per patch (each step counted up to 0.3,
    a true ramp's steps are 0.4-1.1) less the spread of the patches' chromaticities."""
    seen = [(k, v) for k, v in enumerate(row) if v is not None]
    if len(seen) < 3:
        return -np.inf
    index = np.array([k for k, _ in seen])
    rgb = np.maximum(np.array([v for _, v in seen]), 1e-12)
    lum = np.log(rgb.sum(axis=1))
    steps = -np.diff(lum) / np.diff(index)
    brightest = rgb[0]
    strong = brightest >= 0.05 * brightest.max()
    spread = 0.0
    if strong.sum() > 1:
        ratios = np.log(rgb[1:4, strong] / brightest[strong])
        spread = float(np.mean(ratios.max(axis=1) - ratios.min(axis=1)))
    return float(np.mean(np.clip(steps, -1.0, 0.3)) / 0.3 - spread)


def _orient(image, H, ij, centres, rows, columns) -> tuple[np.ndarray | None, str]:
    """The chart's outer corners (working pixels) of the best placement, or a reason."""
    checker = (rows, columns) == (4, 6)
    full = len(ij) == rows * columns
    pitch = np.sqrt(abs(np.linalg.det(_jacobian(H, ij.mean(axis=0)))))
    colours = dict(zip(map(tuple, ij.tolist()), _colours(image, centres, pitch), strict=True))
    outer = np.array([[-0.5, -0.5], [columns - 0.5, -0.5], [columns - 0.5, rows - 0.5],
                      [-0.5, rows - 0.5]])  # fmt: skip
    scored = []
    for P in _placements(ij, rows, columns):
        corners = apply_homography(H @ P, outer)
        e1, e2 = corners[1] - corners[0], corners[3] - corners[0]
        if e1[0] * e2[1] - e1[1] * e2[0] <= 0:  # a mirror image: not a chart seen from the front
            continue
        if checker:
            cells = (np.array([[c, 3, 1] for c in range(6)]) @ P.T)[:, :2]
            row = [colours.get((int(i), int(j))) for i, j in cells]
            scored.append((_ramp_score(row), corners))
        elif full:
            scored.append((-float(corners[0].sum()), corners))
    if not scored:
        return None, "a grid of patches, not the chart's layout (or not all of it)"
    scored.sort(key=lambda s: -s[0])
    score, corners = scored[0]
    if checker and score < 0.5:
        return (
            None,
            "no neutral row where a ColorChecker 24 has one",
        )
    return corners, ""


def _jacobian(H: np.ndarray, point: np.ndarray) -> np.ndarray:
    """d(x, y)/d(i, j) of the homography at ``point``."""
    u, v = float(point[0]), float(point[1])
    w = H[2, 0] * u + H[2, 1] * v + H[2, 2]
    x, y = apply_homography(H, np.array([[u, v]]))[0]
    return (H[:2, :2] - np.outer([x, y], H[2, :2])) / w


# -- the search --------------------------------------------------------------------------------


def _small_grid(image: np.ndarray, bright: float, rows: int, columns: int) -> float | None:
    """The pitch (working pixels) of a grid of patches too small to be found as it is, found
    on the image enlarged 3x (so the smoothing and edges no longer swallow its patches)."""
    from scipy import ndimage

    if image.shape[1] > WORKING_WIDTH // 2:  # keep the enlarged search bounded
        return None
    c = _candidates(ndimage.zoom(image, (2, 2, 1), order=1), bright)
    found = _lattice(c, rows, columns) if len(c.areas) >= 4 else None
    if found is None or len(found[1]) < min(_MIN_MEMBERS, rows * columns):
        return None
    fitted = _grid_fit(found[0], c.centres[found[1]], c.areas[found[1]])
    if fitted is None:
        return None
    pitch = np.sqrt(abs(np.linalg.det(_jacobian(fitted[0], found[0].mean(axis=0))))) / 2
    return float(pitch) if pitch < MIN_PATCH_PIXELS else None


@dataclass(frozen=True)
class _Grid:
    """A grid found: its homography (lattice -> working pixels), lattice coordinates, member
    candidates and their RMS residual (working pixels)."""

    H: np.ndarray
    ij: np.ndarray
    members: np.ndarray
    rms: float


def _fit_grid(c: _Candidates, ij: np.ndarray, members: np.ndarray) -> _Grid | None:
    """The grid fitted to its members, refitted without those far off it (a patch partly
    covered has its centre moved)."""
    for _ in range(2):
        fitted = _grid_fit(ij, c.centres[members], c.areas[members])
        if fitted is None:
            return None
        H, centres = fitted
        residual = np.linalg.norm(apply_homography(H, ij.astype(float)) - centres, axis=1)
        keep = residual < max(0.5, 5 * float(np.median(residual)))
        if keep.all() or keep.sum() < _MIN_MEMBERS:
            break
        ij, members = ij[keep], members[keep]
    return _Grid(H, ij, members, float(np.sqrt(np.mean(residual**2))))


def _search(image: np.ndarray, f: int, rows: int, columns: int):
    """(corners in working pixels or None, reason, detail, candidates, grid or None)."""
    bright = float(np.percentile(image.mean(axis=2), 99))
    c = _candidates(image, bright)
    found = _lattice(c, rows, columns) if len(c.areas) >= 4 else None
    if found is None or len(found[1]) < min(_MIN_MEMBERS, rows * columns):
        small = _small_grid(image, bright, rows, columns)
        if small is not None:
            detail = f"{small * f:.1f} px pitch, need {MIN_PATCH_PIXELS}"
            return None, "too small", detail, c, None
        n = 0 if found is None else len(found[1])
        return None, "not found", f"{n} patches in a grid, {len(c.areas)} patch-like", c, None
    grid = _fit_grid(c, *found)
    if grid is None:
        return None, "not found", "the patches found do not span a grid", c, None
    pitch = f * np.sqrt(abs(np.linalg.det(_jacobian(grid.H, grid.ij.mean(axis=0)))))
    if pitch < MIN_PATCH_PIXELS:
        detail = f"{pitch:.1f} px pitch, need {MIN_PATCH_PIXELS}"
        return None, "too small", detail, c, grid
    corners, why = _orient(image, grid.H, grid.ij, c.centres[grid.members], rows, columns)
    return corners, "not found", why, c, grid


def _cells(corners: np.ndarray, points: np.ndarray, rows: int, columns: int) -> tuple[int, ...]:
    """The chart patches (reading order) holding ``points`` (plate pixels)."""
    from ocio_vp.plates.sampling import grid_homography

    G = grid_homography(corners, rows, columns)
    if not np.linalg.cond(G) < 1e12:
        return ()
    uv = apply_homography(np.linalg.inv(G), points)
    col, row = np.floor(uv[:, 0]).astype(int), np.floor(uv[:, 1]).astype(int)
    inside = (col >= 0) & (col < columns) & (row >= 0) & (row < rows)
    return tuple(sorted({int(v) for v in (row * columns + col)[inside]}))


def detect_chart(info: PlateInfo, *, rows: int = 4, columns: int = 6) -> Detection:
    """Search a plate for a chart of ``rows`` x ``columns`` patches (see the module docstring)."""
    f = max(1, -(-info.width // WORKING_WIDTH))  # at most WORKING_WIDTH across
    image = block_means(info, f)
    lum = image.mean(axis=2)
    bright, noise = float(np.percentile(lum, 99)), _noise(lum)
    early = None
    if not bright > 10 * noise or not bright > 0:
        early = "too dark", f"bright level {bright / max(noise, 1e-30):.2g}x the noise, need 10x"
    elif rows < 2 or columns < 2:
        early = "not found", f"a {rows} x {columns} strip has no grid to find"
    if early is not None:
        empty = np.zeros(lum.shape, np.int32)
        return Detection(None, *early, image.astype(np.float32), f, empty, np.zeros(0, bool))
    corners, reason, detail, c, grid = _search(image, f, rows, columns)
    image32 = image.astype(np.float32)
    used = np.zeros(len(c.areas), bool)
    if grid is not None:
        used[grid.members] = True
    if corners is None:
        clipped = _clipped_share(image)
        if reason == "not found" and clipped > 0.02:
            reason = "clipped"
            detail = f"{100 * clipped:.0f} % of the plate at its maximum"
        return Detection(None, reason, detail, image32, f, c.labels, used)
    assert grid is not None  # corners come from a grid
    plate = corners * f + [info.x, info.y]
    seen = _cells(plate, c.centres[grid.members] * f + [info.x, info.y], rows, columns)
    detail = f"{len(grid.members)} of {rows * columns} patches, grid residual {grid.rms * f:.2g} px"
    return Detection(plate, None, detail, image32, f, c.labels, used, grid.rms * f, seen)


def detect_chart_corners(info: PlateInfo, *, rows: int = 4, columns: int = 6) -> np.ndarray:
    """The chart's (4, 2) corners TL, TR, BR, BL on a plate.

    Raises
    ------
    DetectionError
        Not found: the message names the reason and what to give instead.
    """
    found = detect_chart(info, rows=rows, columns=columns)
    if found.corners is None:
        raise DetectionError(found, source=info.path)
    return found.corners


def detection_overlay(detection: Detection) -> np.ndarray:
    """(h, w, 3) uint8 picture of the search at working resolution: everything dimmed but the
    patch-like regions, those in the grid outlined green, the others yellow."""
    from ocio_vp.plates.overlay import overlay_image

    states = ["ok" if m else "clipped" for m in detection.members]
    labels = detection.regions.astype(np.int32) - 1
    white = float(np.percentile(detection.image.max(axis=2), 99.5)) or 1.0
    return overlay_image(detection.image, labels, states, white=white)


def _detector(*, source: object = None) -> Callable[..., Detection]:
    """What the deprecated ``detector`` did: return :func:`detect_chart`."""
    return detect_chart


#: Names served for one more release (ocio_vp.deprecation).
DEPRECATED = {"detector": ("detect_chart (called directly)", lambda: _detector)}
__getattr__ = deprecated_names(__name__, DEPRECATED)
