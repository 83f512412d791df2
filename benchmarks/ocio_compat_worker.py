"""Evaluate every processor of exported OCIO configs with whichever PyOpenColorIO is installed.

Run by :mod:`benchmarks.ocio_compat` inside throwaway venvs (one per OCIO version), so it imports
nothing but the standard library, numpy and PyOpenColorIO::

    python ocio_compat_worker.py INPUTS.npy RESULT.npz ROOT [ROOT ...]

For every ``*.ocio`` and ``*.ocioz`` under each ROOT it loads the config, validates it, and
builds every processor a host can ask for: each colorspace to each other one, each colorspace
to each display/view (both directions), each named transform (both directions), and every
``.clf`` / ``.cube`` file under the ROOTs as a FileTransform (CLF both directions, except the
inverse of a CLF that is a singular matrix, which is undefined: the post-correction Q of a
rank-1 environment, and of a CLF holding a 3D LUT, which OCIO inverts by search: the configs
give that direction explicitly as its own file). Each colorspace's two directions against the
reference and each named transform's two directions are also built from cold (every cache
cleared), and the slowest such build is reported. Each is
applied on the CPU to the rows of INPUTS (float32 RGB), and its GPU shader text is extracted as
Unreal's OpenColorIO plugin does (HLSL for DirectX 11; this machine has no GPU, so the shader
is generated but not run). RESULT.npz holds one array per processor, named
``<file>|<kind>|<src>|<dst>``, plus a JSON ``problems`` list: load/validate failures, shader
extraction failures, non-finite or over-bound outputs, and copies of one config (the solve's
``config.ocio``, its export copies, its ``.ocioz``) that disagree.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO

#: No processor may return more than this for inputs in [-1, 16].
BOUND = 1e6


def apply(processor, rgb: np.ndarray) -> np.ndarray:
    """``processor`` on the CPU (float32, OCIO's default optimisation, as hosts run it)."""
    pixels = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    processor.getDefaultCPUProcessor().applyRGB(pixels)
    return pixels


def hlsl_shader(processor) -> str:
    """The HLSL shader text Unreal would compile for ``processor``."""
    desc = OCIO.GpuShaderDesc.CreateShaderDesc(
        language=OCIO.GPU_LANGUAGE_HLSL_DX11,
        functionName="OCIOConvert",
        resourcePrefix="ocio_",
    )
    if hasattr(desc, "setAllowTexture1D"):  # OCIO 2.3+: Unreal samples 1D LUTs as 2D textures
        desc.setAllowTexture1D(False)
    processor.getOptimizedGPUProcessor(OCIO.OPTIMIZATION_DEFAULT).extractGpuShaderInfo(desc)
    text = desc.getShaderText()
    if "OCIOConvert" not in text:
        raise RuntimeError("shader text lacks its entry point")
    return text


def colorspace_names(config) -> list[str]:
    return [cs.getName() for cs in config.getColorSpaces()]


def cold_builds(config) -> dict[str, float]:
    """Seconds to build (from cold: OCIO's caches cleared) each colorspace <-> the reference
    and each named transform, both directions, with its CPU processor."""
    import time

    reference = config.getColorSpace("reference") or config.getColorSpaces()[0]
    reference = reference.getName()
    jobs = []
    for name in colorspace_names(config):
        if name != reference:
            jobs += [(f"{name} -> {reference}", (name, reference)),
                     (f"{reference} -> {name}", (reference, name))]  # fmt: skip
    for named in config.getNamedTransforms():
        for label, direction in (("forward", OCIO.TRANSFORM_DIR_FORWARD),
                                 ("inverse", OCIO.TRANSFORM_DIR_INVERSE)):  # fmt: skip
            jobs.append((f"{named.getName()} {label}", (named, direction)))
    seconds = {}
    for label, args in jobs:
        OCIO.ClearAllCaches()
        start = time.perf_counter()
        config.getProcessor(*args).getDefaultCPUProcessor()
        seconds[label] = time.perf_counter() - start
    return seconds


def has_lut3d(path: Path) -> bool:
    return path.suffix.lower() == ".clf" and "<LUT3D" in path.read_text(errors="replace")


def config_processors(config) -> dict[str, object]:
    """``kind|src|dst`` -> processor for everything a host can build from ``config``."""
    procs: dict[str, object] = {}
    spaces = colorspace_names(config)
    for src in spaces:
        for dst in spaces:
            if src != dst:
                procs[f"colorspace|{src}|{dst}"] = config.getProcessor(src, dst)
    for display in config.getDisplays():
        for view in config.getViews(display):
            for src in spaces:
                for name, direction in (("view", OCIO.TRANSFORM_DIR_FORWARD),
                                        ("view-inverse", OCIO.TRANSFORM_DIR_INVERSE)):  # fmt: skip
                    procs[f"{name}|{src}|{display}/{view}"] = config.getProcessor(
                        src, display, view, direction
                    )
    for named in config.getNamedTransforms():
        name = named.getName()
        fwd = named.getTransform(OCIO.TRANSFORM_DIR_FORWARD)
        inv = named.getTransform(OCIO.TRANSFORM_DIR_INVERSE)
        procs[f"named|{name}|forward"] = (
            config.getProcessor(fwd)
            if fwd is not None
            else config.getProcessor(inv, OCIO.TRANSFORM_DIR_INVERSE)
        )
        procs[f"named|{name}|inverse"] = (
            config.getProcessor(inv)
            if inv is not None
            else config.getProcessor(fwd, OCIO.TRANSFORM_DIR_INVERSE)
        )
    return procs


#: A file whose forward transform has a Jacobian (at black) worse conditioned than this has no
#: inverse (the CLF of a rank-1 post-correction Q): its inverse is not built.
MAX_CONDITION = 1e3


def invertible(processor) -> bool:
    """False when ``processor`` is (locally at black) a singular linear map."""
    probe = np.vstack([np.zeros(3), np.eye(3) * 1e-2]).astype(np.float32)
    out = apply(processor, probe).astype(np.float64)
    jacobian = (out[1:] - out[0]).T / 1e-2
    return bool(np.linalg.cond(jacobian) <= MAX_CONDITION)


def file_processors(path: Path) -> dict[str, object]:
    """A LUT file as a FileTransform (a CLF both directions unless its forward transform is
    singular; a 3D ``.cube`` forward only)."""
    raw = OCIO.Config.CreateRaw()
    procs = {}
    directions = [OCIO.TRANSFORM_DIR_FORWARD]
    forward = raw.getProcessor(OCIO.FileTransform(src=str(path.resolve())))
    if path.suffix.lower() == ".clf" and not has_lut3d(path) and invertible(forward):
        directions.append(OCIO.TRANSFORM_DIR_INVERSE)
    for direction in directions:
        transform = OCIO.FileTransform(
            src=str(path.resolve()), interpolation=OCIO.INTERP_LINEAR, direction=direction
        )
        kind = "file" if direction == OCIO.TRANSFORM_DIR_FORWARD else "file-inverse"
        procs[f"{kind}|{path.name}|"] = raw.getProcessor(transform)
    return procs


def evaluate(procs: dict[str, object], rgb: np.ndarray, label: str, problems: list) -> dict:
    """Apply each processor; record bound/finiteness and shader problems."""
    out = {}
    for key, processor in procs.items():
        values = apply(processor, rgb)
        if not np.all(np.isfinite(values)):
            problems.append(f"{label} {key}: non-finite output")
        elif np.abs(values).max() > BOUND:
            worst = int(np.argmax(np.abs(values).max(axis=1)))
            problems.append(
                f"{label} {key}: output {np.abs(values).max():.3g} > {BOUND:g} "
                f"for input {rgb[worst].tolist()}"
            )
        try:
            hlsl_shader(processor)
        except Exception as error:  # every failure is a finding, reported not raised
            problems.append(f"{label} {key}: HLSL shader extraction failed: {error}")
        out[key] = values
    return out


def config_files(roots: list[Path]) -> list[Path]:
    files = []
    for root in roots:
        files += sorted(p for p in root.rglob("*") if p.suffix in (".ocio", ".ocioz"))
    return files


def lut_files(roots: list[Path]) -> list[Path]:
    files = []
    for root in roots:
        files += sorted(p for p in root.rglob("*") if p.suffix.lower() in (".clf", ".cube"))
    return files


def group_key(path: Path) -> str:
    """Copies of one solved config share a key: the environment folder holding ``solution.json``."""
    for parent in path.parents:
        if (parent / "solution.json").is_file():
            return str(parent)
    return str(path)


def run(rgb: np.ndarray, roots: list[Path]) -> tuple[dict[str, np.ndarray], list[str], int, list]:
    """All results (by ``<relative file>|kind|src|dst``), problems, the processor count, and
    the slowest cold build (seconds, what)."""
    results: dict[str, np.ndarray] = {}
    problems: list[str] = []
    firsts: dict[str, dict[str, np.ndarray]] = {}
    count = 0
    slowest = [0.0, ""]
    for path in config_files(roots):
        label = str(path)
        try:
            config = OCIO.Config.CreateFromFile(str(path))  # .ocio or .ocioz
            config.validate()
            procs = config_processors(config)
            for what, seconds in cold_builds(config).items():
                if seconds > slowest[0]:
                    slowest = [seconds, f"{label}: {what}"]
        except Exception as error:
            problems.append(f"{label}: does not load: {error}")
            continue
        values = evaluate(procs, rgb, label, problems)
        count += len(values)
        key = group_key(path)
        if key not in firsts:  # the first copy is compared across versions, the others to it
            firsts[key] = values
            results.update({f"{key}|{k}": v for k, v in values.items()})
            continue
        for name, value in values.items():
            first = firsts[key].get(name)
            if first is None or not np.array_equal(first, value, equal_nan=True):
                problems.append(f"{label} {name}: differs from another copy of the config")
    for path in lut_files(roots):
        try:
            procs = file_processors(path)
        except Exception as error:
            problems.append(f"{path}: does not load: {error}")
            continue
        values = evaluate(procs, rgb, str(path), problems)
        count += len(values)
        results.update({f"{path}|{k}": v for k, v in values.items()})
    return results, problems, count, slowest


def main(argv: list[str]) -> int:
    inputs, output, *roots = argv
    rgb = np.load(inputs)
    results, problems, count, slowest = run(rgb, [Path(r) for r in roots])
    meta = {"version": OCIO.__version__, "problems": problems, "processors": count,
            "slowest_build": slowest}  # fmt: skip
    np.savez_compressed(output, __meta__=np.array(json.dumps(meta)), **results)
    print(f"OpenColorIO {OCIO.__version__}: {count} processors, {len(problems)} problems")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
