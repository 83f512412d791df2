"""What the wall's soft clip (``solve --soft-clip KNEE``) costs below the peak and gains above it.

    python -m benchmarks.softclip_trade [--write docs/headroom.md]

Two simulated stages, each solved by least squares for its seven environments: the sample
stage with its wall's peak at the location's white (``paper_stage(wall_gain=1.0)``: no
headroom, so content white already needs more than the peak, the case a soft clip is for) and a stage of narrower LEDs (620/530/465 nm)
filmed by another camera. Content, in camera RGB with content white = (1, 1, 1): the chart's
24 reflectances under the environment (white-balanced to content white), 12 saturated hues
(HSV saturation 0.9) and a blue sky (CIE daylight at 20000 K, balanced like the chart), each at
0.25x, 0.5x, 1x, 2x, 4x and 8x. The wall shows it inside the frustum: drive ``N c + offset``,
then hard clip (``[0, 1]``, the default), the per-channel soft clip at knees 0.6, 0.8, 0.9
(:func:`ocio_vp.wall.softclip.forward`, then black below 0), or, for comparison only, a
hue-preserving max-RGB compression (the drive scaled by ``f(max) / max``, knee 0.8). The
camera sees ``[SL] out + b`` (the simulator's true [SL]; ``b = -[SL] offset``, the black the
offset cancels) and the post-correction Q is applied: without clipping that is ``c``, the
content as intended. Errors against it: ΔE2000 (CIE Lab through the stage camera's RGB -> XYZ,
Lab white = content white, so L* > 100 above it) and the CIE LCh hue angle error (degrees,
samples with C* > 10 in both).

Rows split the samples by the drive they need: "below the peak" (largest channel <= 1, where a
hard clip changes nothing and any error is the soft clip's cost) and "above the peak".
Prints Markdown; ``--write FILE`` replaces the section between the ``softclip_trade`` markers.
"""

from __future__ import annotations

import argparse
import colorsys
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from ocio_vp.simulator.data import PAPER_ENVIRONMENTS  # noqa: E402
from ocio_vp.wall.softclip import forward  # noqa: E402

LEVELS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
KNEES = (0.6, 0.8, 0.9)
MAX_RGB_KNEE = 0.8
BEGIN, END = "<!-- softclip_trade: begin -->", "<!-- softclip_trade: end -->"


def stages():
    from ocio_vp.simulator.stage import paper_stage, spectral_stage

    other = spectral_stage(
        camera="Nikon 5100 (NPL)",
        leds=((620.0, 18.0), (530.0, 30.0), (465.0, 20.0)),
        name="narrow-led-stage",
    )
    # wall_gain 1: the wall's peak at the location's white, the stage without headroom.
    return {
        "sample stage (paper_stage)": paper_stage(wall_gain=1.0),
        "narrow LEDs, Nikon 5100": other,
    }


def content_colours(stage, environment) -> tuple[np.ndarray, list[str]]:
    """(n, 3) camera RGB at content white = 1 and each row's group name."""
    import colour

    from ocio_vp.simulator.data import align
    from ocio_vp.simulator.stage import camera_rgb, environment_spectrum

    light = environment_spectrum(stage, environment)
    white = camera_rgb(stage, stage.reflectances[stage.white_patch] * light)
    chart = camera_rgb(stage, stage.reflectances * light) / white
    hues = np.array([colorsys.hsv_to_rgb(h / 12, 0.9, 1.0) for h in range(12)])
    xy = colour.temperature.CCT_to_xy_CIE_D(20000.0)
    sky = camera_rgb(stage, align(colour.sd_CIE_illuminant_D_series(xy))) / camera_rgb(stage, light)
    sky = (sky / sky.max())[None]  # relative to the environment's white, brightest channel 1
    colours = np.concatenate([chart, hues, sky])
    groups = ["chart"] * len(chart) + ["saturated"] * len(hues) + ["sky"]
    return colours, groups


def wall_out(drive: np.ndarray, mode: str, knee: float | None) -> np.ndarray:
    if mode == "hard":
        return np.clip(drive, 0.0, 1.0)
    if mode == "soft":
        return np.clip(forward(drive, knee), 0.0, None)
    peak = drive.max(axis=1, keepdims=True)  # max-RGB: one gain per pixel, hue kept
    safe = np.where(peak > 0, peak, 1.0)
    gain = np.where(peak > knee, forward(peak, knee) / safe, 1.0)
    return np.clip(drive * gain, 0.0, None)


def lab(stage, rgb: np.ndarray) -> np.ndarray:
    import colour

    from ocio_vp.simulator.truth import camera_matrix

    to_xyz = camera_matrix(stage)
    white = to_xyz @ np.ones(3)
    return colour.XYZ_to_Lab(rgb @ to_xyz.T / white[1], colour.XYZ_to_xy(white))


def errors(stage, seen: np.ndarray, intended: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ΔE2000, hue angle error in degrees, NaN where either chroma is below 10)."""
    import colour

    a, b = lab(stage, seen), lab(stage, intended)
    de = colour.delta_E(a, b, method="CIE 2000")
    ha, hb = (np.degrees(np.arctan2(x[:, 2], x[:, 1])) for x in (a, b))
    hue = np.abs((ha - hb + 180.0) % 360.0 - 180.0)
    chroma = np.minimum(np.hypot(a[:, 1], a[:, 2]), np.hypot(b[:, 1], b[:, 2]))
    return de, np.where(chroma > 10.0, hue, np.nan)


MODES = [("hard clip", "hard", None)]
MODES += [(f"soft clip, knee {k:g}", "soft", k) for k in KNEES]
MODES += [(f"max-RGB, knee {MAX_RGB_KNEE:g} (not shipped)", "maxrgb", MAX_RGB_KNEE)]


def measure(stage) -> dict:
    """Per mode and band: ΔE2000 and hue errors pooled over environments, colours and levels."""
    from ocio_vp.pipeline import solve_measurements
    from ocio_vp.simulator.stage import simulate_measurements

    measurements = simulate_measurements(PAPER_ENVIRONMENTS, stage=stage)
    solutions = solve_measurements(measurements, method="least-squares")
    SL = stage.SL
    out = {name: {band: ([], []) for band in BANDS} for name, _, _ in MODES}
    white_drives = []
    skipped = [s.environment for s in solutions if s.N is None]
    for solution in (s for s in solutions if s.N is not None):
        colours, _ = content_colours(stage, solution.environment)
        content = np.concatenate([colours * level for level in LEVELS])
        offset = np.zeros(3) if solution.black_level_offset is None else solution.black_level_offset
        drive = content @ np.asarray(solution.N).T + offset
        white_drives.append(float((solution.N @ np.ones(3) + offset).max()))
        band = _bands(drive)
        for name, mode, knee in MODES:
            seen = (wall_out(drive, mode, knee) - offset) @ SL.T
            corrected = solution.correction.apply(seen)
            de, hue = errors(stage, corrected, content)
            for key in BANDS:
                out[name][key][0].append(de[band == key])
                out[name][key][1].append(hue[band == key])
    return {
        "modes": out,
        "white_drive": (min(white_drives), max(white_drives)),
        "skipped": skipped,
        "environments": len(solutions) - len(skipped),
    }


#: Bands of the drive a sample needs (its largest channel, in units of the panel's peak).
BANDS = {"below": "in [0, 1]", "near": "1-2x the peak", "far": "over 2x the peak"}


def _bands(drive: np.ndarray) -> np.ndarray:
    """Each sample's band; "" for one that needs negative drive but no more than the peak
    (both clips send that channel as black: they do not differ there)."""
    top, bottom = drive.max(axis=1), drive.min(axis=1)
    band = np.where(top > 2.0, "far", np.where(top > 1.0, "near", "below"))
    return np.where((top <= 1.0) & (bottom < 0.0), "", band)


def _stats(values: list[np.ndarray]) -> tuple[str, str, int]:
    v = np.concatenate(values)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return "-", "-", 0
    return f"{np.mean(v):.2f}", f"{np.percentile(v, 95):.2f}", v.size


def table(name: str, result: dict) -> list[str]:
    lo, hi = result["white_drive"]
    head = " | ".join(f"{text}: ΔE2000 mean / p95 | hue ° mean / p95" for text in BANDS.values())
    lines = [
        f"**{name}** (content white needs {100 * lo:.0f}-{100 * hi:.0f}% of the peak in its "
        "worst channel inside the frustum):",
        "",
        f"| wall | {head} |",
        "|---|" + "---|" * (2 * len(BANDS)),
    ]
    counts = {}
    for mode, bands in result["modes"].items():
        cells = []
        for key in BANDS:
            de_mean, de_p95, counts[key] = _stats(bands[key][0])
            hue_mean, hue_p95, _ = _stats(bands[key][1])
            cells += [f"{de_mean} / {de_p95}", f"{hue_mean} / {hue_p95}"]
        lines.append(f"| {mode} | " + " | ".join(cells) + " |")
    skipped = ", ".join(result["skipped"])
    skipped = (
        f"; left out (N not solved, no in-frustum drive of its own): {skipped}" if skipped else ""
    )
    samples = ", ".join(f"{counts[k]} {text}" for k, text in BANDS.items())
    lines += ["", f"({result['environments']} environments; samples {samples}{skipped}.)", ""]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--write", type=Path, help="replace the softclip_trade section of FILE")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    lines = []
    for name, stage in stages().items():
        lines += table(name, measure(stage))
    lines.append(f"_(python -m benchmarks.softclip_trade, {time.perf_counter() - start:.0f} s)_")
    text = "\n".join(lines)
    print(text)
    if args.write:
        doc = args.write.read_text(encoding="utf-8")
        head, _, rest = doc.partition(BEGIN)
        _, _, tail = rest.partition(END)
        args.write.write_text(f"{head}{BEGIN}\n{text}\n{END}{tail}", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
