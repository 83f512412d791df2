"""LUT sizes vs the exact chain: the panel-linearity 1D LUT, and baked .cube 17/33/65.

Linearity LUT (``ocio_vp.wall.encoding.lut_table``): a panel too dark in the shadows, as real
walls are, inverted exactly by bisection on its PCHIP model; the LUT samples that inverse,
spaced evenly in drive (the previous sidecar) or in the wall's own signal (shipped). Error: the
relative error ``|r(LUT(x)) - x| / x`` in three bands from 0.1% to 100% of peak, run by OCIO.

Baked cubes (issue 6, ``ocio_vp.exports.resolve.bake_cube``, OCIO's Baker with a linear
shaper over the HDR input range): read back by OCIO's own .cube reader and compared with the
config's exact processor on random inputs over the whole range and over [0, 1].
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from benchmarks import fmt_ms, markdown_table, median_time


def _apply(processor, rgb: np.ndarray) -> np.ndarray:
    import PyOpenColorIO as OCIO

    data = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    cpu = processor.getDefaultCPUProcessor()
    cpu.apply(OCIO.PackedImageDesc(data, data.shape[0], 1, 3))
    return data.astype(np.float64)


#: Simulated shadows as measured on real walls (13-36% dark at 2% of peak): channel k shows
#: ``d (1 - DARK[k] exp(-d / 0.02))``, normalised at drive 1.
SHADOW_DARK = (0.30, 0.15, 0.35)


def shadow_linearity() -> dict:
    """The ``linearity`` block of a noiseless 30-step ramp, evenly spaced in PQ code values."""
    from ocio_vp.wall.encoding import decode, encode
    from ocio_vp.wall.linearity import CHANNELS, fit_linearity, parse_ramps

    drive = decode(np.linspace(0.0, float(encode(1.0, "pq")), 30), "pq")
    drive[-1] = 1.0
    ramps = {}
    for k, name in enumerate(CHANNELS):
        level = drive * (1 - SHADOW_DARK[k] * np.exp(-drive / 0.02))
        ramps[name] = {
            "drive": drive.tolist(),
            "camera": np.outer(level / level[-1], np.eye(3)[k]).tolist(),
        }
    return fit_linearity(parse_ramps(ramps), np.eye(3))


def _even_drive_lut(linearity, domain_max: float, size: int):
    """The previous sidecar: a scale by 1/H then a LUT sampled evenly in linear drive."""
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio.config import matrix_transform
    from ocio_vp.wall.linearity import CHANNELS, inverse_response

    n = (size - 1) // int(domain_max) * int(domain_max) + 1
    x = np.linspace(0.0, domain_max, n)
    lut = OCIO.Lut1DTransform(length=n, inputHalfDomain=False)
    for i, row in enumerate(
        np.stack(
            [
                inverse_response(
                    linearity.channels[c].drive,
                    linearity.channels[c].response,
                    x,
                )
                for c in CHANNELS
            ],
            axis=1,
        )
    ):
        lut.setValue(i, *map(float, row))
    return [matrix_transform(np.eye(3) / domain_max), lut]


def _relative_errors(linearity, transforms, encoding: str) -> list[float]:
    """Worst ``|r(drive) - x| / x`` per accuracy band, the chain run by OCIO (default
    optimisation, as hosts run it)."""
    import PyOpenColorIO as OCIO

    from ocio_vp.wall.encoding import ACCURACY_BANDS, decode
    from ocio_vp.wall.linearity import CHANNELS, response_model

    x = np.geomspace(ACCURACY_BANDS[0][0], 1.0, 20001)
    processor = OCIO.Config.CreateRaw().getProcessor(OCIO.GroupTransform(transforms))
    signal = _apply(processor, np.repeat(x[:, None], 3, axis=1))
    drive = decode(signal, encoding)
    error = np.zeros_like(x)
    for k, c in enumerate(CHANNELS):
        channel = linearity.channels[c]
        model = response_model(channel.drive, channel.response)
        error = np.maximum(error, np.abs(model(np.clip(drive[:, k], 0, 1)) / x - 1))
    return [float(np.max(error[(x >= lo) & (x <= hi)])) for lo, hi in ACCURACY_BANDS]


def linearity_luts(quick: bool) -> str:
    from ocio_vp.ocio.wall import encoding_transforms, lut_transform
    from ocio_vp.wall.encoding import lut_table

    linearity = shadow_linearity()
    rows = []
    sizes = (257, 4095) if quick else (65, 257, 1025, 4095)
    domains = {"linear": 16.0, "gamma2.4": 1.0, "srgb": 1.0, "pq": 10.0}
    for encoding, domain_max in domains.items():
        encoded = [] if encoding == "linear" else encoding_transforms(encoding)
        for size in sizes:
            even = _even_drive_lut(linearity, domain_max, size) + encoded
            errors = _relative_errors(linearity, even, encoding)
            rows.append((encoding, "even in drive (before)", size, "-", *_pct(errors)))
            seconds = median_time(
                lambda s=size, e=encoding: lut_table(linearity, e, size=s),
                repeats=1 if quick else 3,
                warmup=0,
            )
            lut = lut_table(linearity, encoding, size=size)
            spaced = [*encoded, lut_transform(lut)]
            errors = _relative_errors(linearity, spaced, encoding)
            shaped = "log2 shaper" if encoding == "linear" else "its own signal"
            rows.append((encoding, f"in {shaped}", size, fmt_ms(seconds), *_pct(errors)))
    return "\n".join(
        [
            "### Panel-linearity 1D LUT: size and spacing vs the error in the shadows",
            "",
            "A wall 15-35% dark near black (`d (1 - a exp(-d / 0.02))`, a noiseless 30-step "
            "ramp spaced in PQ code values). Error: the worst `|r(LUT(x)) - x| / x`, relative "
            "to the level x, against the exact inverse of the fitted response, with the wall "
            "chain (encoding and LUT) run by OCIO. *Even in drive* is the previous sidecar (a "
            "scale by 1/H, entries evenly spaced in linear drive over [0, H]); the shipped one "
            "spaces them in the wall's signal, 4095 entries (the largest 1D texture on GPU hosts).",
            "",
            markdown_table(
                [
                    "encoding",
                    "LUT entries spaced",
                    "entries",
                    "time to build",
                    "0.1-0.2% of peak",
                    "0.2-2% of peak",
                    "2-100% of peak",
                ],
                rows,
            ),
        ]
    )


def _noisy_linearity(relative: float, floor: float, seed: int) -> dict:
    """:func:`shadow_linearity` from a ramp with noise (``relative`` of the level plus
    ``floor`` of peak, the zero step too) and a camera black of -0.3% of peak."""
    from ocio_vp.wall.encoding import decode, encode
    from ocio_vp.wall.linearity import CHANNELS, fit_linearity, parse_ramps

    rng = np.random.default_rng(seed)
    drive = decode(np.linspace(0.0, float(encode(1.0, "pq")), 30), "pq")
    drive[-1] = 1.0
    ramps = {}
    for k, name in enumerate(CHANNELS):
        level = _shadow_wall(drive, k)
        level = level * (1 + rng.normal(0, relative, 30)) + rng.normal(0, floor, 30)
        level[-1] = 1.0
        ramps[name] = {
            "drive": drive.tolist(),
            "camera": np.outer(level - 0.003, np.eye(3)[k]).tolist(),
        }
    return fit_linearity(parse_ramps(ramps), np.eye(3))


def _shadow_wall(d: np.ndarray, k: int) -> np.ndarray:
    return d * (1 - SHADOW_DARK[k] * np.exp(-d / 0.02)) / (1 - SHADOW_DARK[k] * np.exp(-50))


def noisy_ramps(quick: bool) -> str:
    """Error of the corrected wall against its true curve, for ramps with camera noise."""
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio.wall import encoding_transforms, lut_transform
    from ocio_vp.wall.encoding import decode, lut_table

    x = np.geomspace(0.002, 1.0, 4001)
    seeds = range(3 if quick else 10)
    rows = []
    cases = [(0.0, 0.0)] + [(r, f) for f in (1e-5, 1e-4) for r in (0.001, 0.005, 0.01, 0.02)]
    for relative, floor in cases:
        worst = []
        for seed in seeds:
            linearity = _noisy_linearity(relative, floor, seed)
            chain = [*encoding_transforms("pq"), lut_transform(lut_table(linearity, "pq"))]
            processor = OCIO.Config.CreateRaw().getProcessor(OCIO.GroupTransform(chain))
            drive = decode(_apply(processor, np.repeat(x[:, None], 3, axis=1)), "pq")
            emitted = np.stack([_shadow_wall(drive[:, k], k) for k in range(3)], axis=1)
            error = np.max(np.abs(emitted / x[:, None] - 1), axis=1)
            worst.append([np.max(error[x < 0.02]), np.max(error[x >= 0.02])])
        worst = np.array(worst)
        noise = f"{100 * relative:g}% + {100 * floor:g}% of peak" if relative else "none"
        rows.append(
            (
                noise,
                f"{100 * np.median(worst[:, 0]):.2g}% ({100 * worst[:, 0].max():.2g}%)",
                f"{100 * np.median(worst[:, 1]):.2g}% ({100 * worst[:, 1].max():.2g}%)",
            )
        )
    uncorrected = np.max(np.abs(_shadow_wall(x, 2) / x - 1)[x < 0.02])
    return "\n".join(
        [
            "### Noisy ramps: the corrected wall against its true curve",
            "",
            "The same wall, a 30-step PQ-spaced ramp read with camera noise (a fraction of each "
            "level plus a floor, the zero step included; OpenVPCal's real ROE ramp shows about "
            "0.5% + 0.001% of peak) and a camera black of -0.3% of "
            "peak, solved as captured (PQ, 1000 cd/m2, the chain run by OCIO). Error: the worst "
            "relative deviation of the wall's *true* output from linear; median over "
            f"{len(seeds)} noise draws (worst draw). Uncorrected, the wall is up to "
            f"{100 * uncorrected:.0f}% dark between 0.2% and 2% of peak. The LUT follows the "
            "measured ramp (previous table), so the ramp's own noise is what remains.",
            "",
            markdown_table(["ramp noise", "0.2-2% of peak", "2-100% of peak"], rows),
        ]
    )


def _pct(errors: list[float]) -> list[str]:
    return [f"{100 * e:.3g}%" for e in errors]


def baked_cubes(quick: bool, configs: dict[str, Path], folder: Path) -> str:
    import PyOpenColorIO as OCIO

    from ocio_vp.exports.cube import bake_cube
    from ocio_vp.exports.source import DEFAULT_CUBE_RANGE
    from ocio_vp.ocio.config import IN_FRUSTUM, POST_CORRECTION_COLORSPACE, REFERENCE

    lo, hi = DEFAULT_CUBE_RANGE
    rng = np.random.default_rng(0)
    full = rng.uniform(lo, hi, size=(20000, 3))
    unit = rng.uniform(0.0, 1.0, size=(20000, 3))
    frame = rng.uniform(0.0, 1.5, size=(2160 * 4096 // 4, 3)).astype(np.float32)  # 1/4 frame
    raw = OCIO.Config.CreateRaw()
    rows = []
    for label, encoding, a, b in (
        ("post-correction Q", "pq", POST_CORRECTION_COLORSPACE, REFERENCE),
        ("wall, Inner Frustum, linear drive + linearity LUT", "linear", REFERENCE, IN_FRUSTUM),
        ("wall, Inner Frustum, PQ + linearity LUT", "pq", REFERENCE, IN_FRUSTUM),
    ):
        config = OCIO.Config.CreateFromFile(str(configs[encoding]))
        exact = config.getProcessor(a, b)
        exact_cpu = exact.getDefaultCPUProcessor()
        t_exact = median_time(lambda c=exact_cpu: c.applyRGB(frame.copy()), repeats=3)
        for size in (17, 33, 65):
            path = folder / f"{encoding}_{a == REFERENCE}_{size}.cube"
            seconds = median_time(
                lambda s=size, p=path, e=exact: bake_cube(
                    e, p, size=s, input_range=DEFAULT_CUBE_RANGE
                ),
                repeats=1 if (quick or size == 65) else 3,
                warmup=0,
            )
            cube = raw.getProcessor(
                OCIO.FileTransform(src=str(path), interpolation=OCIO.INTERP_LINEAR)
            )
            cube_cpu = cube.getDefaultCPUProcessor()
            t_cube = median_time(lambda c=cube_cpu: c.applyRGB(frame.copy()), repeats=3)
            err_full = np.abs(_apply(cube, full) - _apply(exact, full)).max()
            err_unit = np.abs(_apply(cube, unit) - _apply(exact, unit)).max()
            rows.append(
                (
                    label,
                    size,
                    f"{path.stat().st_size / 1024:.0f} KiB",
                    fmt_ms(seconds),
                    f"{t_cube / t_exact:.2f}",
                    f"{err_full:.2e}",
                    f"{err_unit:.2e}",
                )
            )
    return "\n".join(
        [
            "### Baked .cube (Resolve) size vs the exact chain",
            "",
            f"Input range [{lo}, {hi}] through a linear shaper (as exported). Error: max abs "
            "difference from the config's exact processor (output units: linear camera RGB for "
            "Q, PQ signal for the wall), 20000 random inputs over the whole range and over "
            "[0, 1]. Speed: cube / exact processor time on the same pixels (`applyRGB`). A "
            "linear shaper bakes an affine transform (Q) exactly, but it samples a PQ curve "
            "every (16.25 / (size - 1)) of linear input: a PQ wall chain cannot be baked to a "
            "usable cube this way (it needs a log or PQ shaper).",
            "",
            markdown_table(
                [
                    "transform",
                    "cube size",
                    "file",
                    "bake time",
                    "time cube / exact",
                    f"max error, inputs in [{lo}, {hi}]",
                    "max error, inputs in [0, 1]",
                ],
                rows,
            ),
        ]
    )


def run(quick: bool = False) -> str:
    from benchmarks.bench_ocio_optim import wall_config

    with tempfile.TemporaryDirectory() as tmp:
        config_path, _ = wall_config(Path(tmp) / "calib")
        linear_path, _ = wall_config(Path(tmp) / "calib_linear", encoding="linear")
        parts = [
            "## LUT sizes vs the exact chain",
            "",
            linearity_luts(quick),
            "",
            noisy_ramps(quick),
            "",
            baked_cubes(quick, {"pq": config_path, "linear": linear_path}, Path(tmp)),
        ]
    return "\n".join(parts)
