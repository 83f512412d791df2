"""w_avg from an equirectangular HDRI: working resolution vs time and error (closed form).

The HDRI is generated here: sky of radiance A above the horizon, ground B below, and a small,
very bright sun (a disc of half-angle ``a``, radiance S). For a normal ``n`` with the sun fully
in its hemisphere, at angle ``t`` from it, the diffuse integral is exactly

    w_avg = B + (A - B) (1 + n_y) / 2 + (S - A) sin^2(a) cos(t)

(the tilted-surface sky view factor (1 + cos tilt)/2, and the cosine-weighted solid angle of a
spherical cap, pi sin^2(a) cos(t), divided by pi).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time

SKY = np.array([0.625, 0.8125, 1.0])
GROUND = np.array([0.3125, 0.25, 0.1875])
SUN = np.array([24576.0, 22528.0, 18432.0])
SUN_ELEVATION, SUN_AZIMUTH = np.radians(30.0), np.radians(40.0)
TILTS = (0.0, 45.0, 80.0)  # angle between the sun and the chart normal, degrees


def _sun_direction() -> np.ndarray:
    # Module convention of ocio_vp.hdri.diffuse: y up, azimuth from +z towards +x.
    ce = np.cos(SUN_ELEVATION)
    return np.array([ce * np.sin(SUN_AZIMUTH), np.sin(SUN_ELEVATION), ce * np.cos(SUN_AZIMUTH)])


def _normal(tilt_deg: float) -> np.ndarray:
    d = _sun_direction()
    u = np.cross(d, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    t = np.radians(tilt_deg)
    return np.cos(t) * d + np.sin(t) * u  # rotated about a horizontal axis: stays level-ish


def closed_form(normal: np.ndarray, half_angle: float) -> np.ndarray:
    d = _sun_direction()
    cos_t = float(normal @ d)
    return (
        GROUND
        + (SKY - GROUND) * (1 + normal[1]) / 2
        + (SUN - SKY) * np.sin(half_angle) ** 2 * cos_t
    )


def make_hdri(width: int, half_angle: float) -> np.ndarray:
    """(width/2, width, 3) float32: sky/ground split at the horizon plus an anti-aliased sun."""
    height = width // 2
    img = np.empty((height, width, 3), dtype=np.float32)
    img[: height // 2] = SKY
    img[height // 2 :] = GROUND
    # Sun: supersample 8x8 only the pixels around it.
    d = _sun_direction()
    theta = np.arccos(d[1])
    phi = np.arctan2(d[0], d[2])
    row = theta / np.pi * height
    col = (phi / (2 * np.pi) + 0.5) * width
    pad = half_angle / np.pi * height * 1.0 / max(np.sin(theta), 0.1) + 3
    r0, r1 = int(row - pad), int(row + pad) + 1
    c0, c1 = int(col - pad * 2), int(col + pad * 2) + 1
    s = 8
    # Directions of the supersamples of that window only (module convention of ocio_vp.hdri.diffuse).
    th = (np.arange(r0 * s, r1 * s) + 0.5) * (np.pi / (height * s))
    ph = ((np.arange(c0 * s, c1 * s) + 0.5) / (width * s) - 0.5) * (2 * np.pi)
    dirs = np.stack(
        [
            np.sin(th)[:, None] * np.sin(ph)[None, :],
            np.broadcast_to(np.cos(th)[:, None], (th.size, ph.size)),
            np.sin(th)[:, None] * np.cos(ph)[None, :],
        ],
        axis=-1,
    )
    inside = (dirs @ d) >= np.cos(half_angle)
    frac = inside.reshape(r1 - r0, s, c1 - c0, s).mean(axis=(1, 3))
    img[r0:r1, c0:c1] = SKY + frac[..., None] * (SUN - SKY)
    return img


def _write(path: Path, img: np.ndarray, *, mip: bool) -> None:
    import OpenImageIO as oiio

    h, w, c = img.shape
    spec = oiio.ImageSpec(w, h, c, oiio.FLOAT)
    spec.attribute("compression", "zip")
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(0, w, 0, h, 0, 1, 0, c), img)
    if mip:
        config = oiio.ImageSpec(w, h, c, oiio.FLOAT)
        config.attribute("compression", "zip")
        ok = oiio.ImageBufAlgo.make_texture(oiio.MakeTxEnvLatl, buf, str(path), config)
    else:
        ok = buf.write(str(path))
    if not ok:
        raise RuntimeError(oiio.geterror())


def run(quick: bool = False) -> str:
    from ocio_vp.hdri.diffuse import DEFAULT_HDRI_WIDTH, diffuse_integral, read_equirect

    full = 4096 if quick else 8192
    half_angle = np.radians(1.0 if quick else 0.5)
    repeats = 2 if quick else 3
    widths = [full, 2048, DEFAULT_HDRI_WIDTH, 512, 64]
    widths = sorted(set(w for w in widths if w <= full), reverse=True)
    normals = [_normal(t) for t in TILTS]
    expected = [closed_form(n, half_angle) for n in normals]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        flat, tx = Path(tmp) / "sun.exr", Path(tmp) / "sun.tx.exr"
        img = make_hdri(full, half_angle)
        _write(flat, img, mip=False)
        _write(tx, img, mip=True)
        del img
        for width in widths:
            cells = [f"{width}x{width // 2}" + (" (full)" if width == full else "")]
            cells[0] += " **default**" if width == DEFAULT_HDRI_WIDTH else ""
            errors = {}
            for label, path in (("flat", flat), ("mip", tx)):
                image = read_equirect(path, width=width)
                seconds = median_time(
                    lambda p=path, w=width: diffuse_integral(read_equirect(p, width=w)),
                    repeats=repeats,
                    warmup=0,
                )
                cells.append(fmt_ms(seconds))
                errors[label] = [
                    float(np.max(np.abs(diffuse_integral(image, normal=n) / e - 1)))
                    for n, e in zip(normals, expected, strict=True)
                ]
            for k in range(len(TILTS)):
                cells.append(f"{100 * errors['flat'][k]:.3f}% / {100 * errors['mip'][k]:.3f}%")
            rows.append(cells)
    header = [
        "working size",
        "time, flat EXR (read + resize + integrate)",
        "time, MIP-mapped .tx (read level + integrate)",
        *[f"error, sun {t:g}° from normal (flat / MIP)" for t in TILTS],
    ]
    sun_share = (SUN[1] - SKY[1]) * np.sin(half_angle) ** 2 / expected[0][1]
    return "\n".join(
        [
            "## w_avg from an HDRI: resolution vs time and error",
            "",
            f"Generated {full}x{full // 2} float EXR (zip): sky {SKY.tolist()}, ground "
            f"{GROUND.tolist()}, a sun of {np.degrees(2 * half_angle):.1f}° diameter and radiance "
            f"{SUN.tolist()} at {np.degrees(SUN_ELEVATION):.0f}° elevation (it gives "
            f"{100 * sun_share:.0f}% of w_avg when the chart faces it). Error: the largest "
            "channel's relative error against the closed form (module docstring of "
            "`benchmarks/bench_wavg.py`). Flat files are box-resized by OpenImageIO; the "
            "`.tx` copy (`maketx --envlatl`) is read at its MIP level of that width, no "
            "decode of the full image. Times: median of "
            f"{repeats}, cold reads of the file included.",
            "",
            markdown_table(header, rows),
            "",
            f"`ocio-vp solve --hdri ENV=FILE` integrates at {DEFAULT_HDRI_WIDTH} wide unless "
            "`--hdri-width` says otherwise.",
        ]
    )
