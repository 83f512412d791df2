"""LUT sizes vs the exact chain: the panel-linearity 1D LUT, and baked .cube 17/33/65.

Linearity LUT (issue 5, ``ocio_vp.wall.encoding.lut_table``): the panel's measured response
``r`` (a simulated panel, ``PANEL_GAMMA`` of ``bench_ocio_optim``) is inverted exactly by
bisection on its PCHIP model; the LUT samples that inverse. Error: how far the corrected panel
is from linear, ``max |r(LUT(x)) - x|`` over drive x in [0, 1] with the LUT run by OCIO.

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


def linearity_luts(quick: bool, solution) -> str:
    import PyOpenColorIO as OCIO

    from ocio_vp.ocio.wall import lut_transform
    from ocio_vp.wall.encoding import LINEAR_HEADROOM, lut_table
    from ocio_vp.wall.linearity import CHANNELS, response_model

    linearity = solution.linearity
    x = np.linspace(0.0, 1.0, 20001)
    rgb = np.repeat(x[:, None], 3, axis=1)
    models = {
        k: response_model(
            np.asarray(linearity["channels"][c]["drive"]),
            np.asarray(linearity["channels"][c]["response"]),
        )
        for k, c in enumerate(CHANNELS)
        if linearity["channels"][c]["corrected"]
    }
    raw = OCIO.Config.CreateRaw()
    rows = []
    for domain_max, encoding in (
        (1.0, "gamma 2.4 / SDR (domain [0, 1])"),
        (LINEAR_HEADROOM, "linear HDR (domain [0, 16])"),
    ):
        for size in (65, 257, 1025, 4095):
            seconds = median_time(
                lambda s=size, h=domain_max: lut_table(linearity, domain_max=h, size=s),
                repeats=1 if quick else 3,
                warmup=0,
            )
            table = lut_table(linearity, domain_max=domain_max, size=size)
            out = _apply(raw.getProcessor(lut_transform(table, domain_max)), rgb)
            error = max(
                float(np.max(np.abs(model(np.clip(out[:, k], 0, 1)) - x)))
                for k, model in models.items()
            )
            rows.append((encoding, table.shape[0], fmt_ms(seconds), f"{100 * error:.4f}%"))
    corrected = ", ".join(c for c in CHANNELS if linearity["channels"][c]["corrected"])
    return "\n".join(
        [
            "### Panel-linearity 1D LUT size vs the exact inverse",
            "",
            f"Corrected channels: {corrected}. Error: max |r(LUT(x)) - x| as a fraction of the "
            "top step (drive 1.0), LUT evaluated by OCIO (shaper + Lut1D, linear "
            "interpolation). The shipped size is 4095 (the largest 1D texture on GPU hosts).",
            "",
            markdown_table(
                [
                    "LUT domain",
                    "entries",
                    "time to build (exact inverse at every entry)",
                    "max deviation from linear",
                ],
                rows,
            ),
        ]
    )


def baked_cubes(quick: bool, configs: dict[str, Path], folder: Path) -> str:
    import PyOpenColorIO as OCIO

    from ocio_vp.exports.resolve import DEFAULT_CUBE_RANGE, bake_cube
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
                lambda s=size, p=path, a=a, b=b, c=config: bake_cube(
                    c, a, b, p, reference=REFERENCE, size=s
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
        config_path, solution = wall_config(Path(tmp) / "calib")
        linear_path, _ = wall_config(Path(tmp) / "calib_linear", encoding="linear")
        parts = [
            "## LUT sizes vs the exact chain",
            "",
            linearity_luts(quick, solution),
            "",
            baked_cubes(quick, {"pq": config_path, "linear": linear_path}, Path(tmp)),
        ]
    return "\n".join(parts)
