"""Run inside a throwaway venv (OpenColorIO + numpy only) by :mod:`benchmarks.show_compat`.

    python show_compat_worker.py RESULT.json SHOW_CONFIG... -- CALIB_DIR

Loads and validates each show config, and for every environment of CALIB_DIR (set through the
context variable VP_ENVIRONMENT) compares the show config's processors with the environment's
own config: ACEScg -> each wall colour space, Stage Footage -> ACEScg, and the camera's log
footage -> ACEScg. Writes the worst difference per pair, relative to max(1, |standalone|).
"""

from __future__ import annotations

import copy
import json
import sys
from pathlib import Path

import numpy as np
import PyOpenColorIO as OCIO

RNG = np.random.default_rng(0)
LINEAR = np.concatenate([RNG.uniform(0, 1, (4000, 3)), RNG.uniform(-0.25, 16, (2000, 3))])
LOG = RNG.uniform(0, 1, (4000, 3))


def _run(config, context, src, dst, rgb):
    out = np.ascontiguousarray(rgb, dtype=np.float32).copy()
    config.getProcessor(context, src, dst).getDefaultCPUProcessor().applyRGB(out)
    return out.astype(np.float64)


def _pairs(own: OCIO.Config) -> list[tuple[str, str, np.ndarray]]:
    spaces = own.getColorSpaces(OCIO.SEARCH_REFERENCE_SPACE_SCENE, OCIO.COLORSPACE_ALL)
    walls = [cs.getName() for cs in spaces if cs.getFamily() == "ocio-vp/LED Wall"]
    pairs = [("ACEScg", wall, LINEAR) for wall in walls]
    pairs.append(("Stage Footage", "ACEScg", LINEAR))
    logs = [cs.getName() for cs in spaces if cs.getName().startswith("Stage Footage (")]
    return pairs + [(log, "ACEScg", LOG) for log in logs]


def main() -> None:
    result, *rest = sys.argv[1:]
    split = rest.index("--")
    shows, calib = rest[:split], Path(rest[split + 1])
    out = {"version": OCIO.__version__, "shows": {}}
    for show_path in shows:
        show = OCIO.Config.CreateFromFile(show_path)
        show.validate()
        rows = {}
        for folder in sorted(p.parent for p in calib.glob("*/config.ocio")):
            own = OCIO.Config.CreateFromFile(str(folder / "config.ocio"))
            context = copy.deepcopy(show.getCurrentContext())
            context["VP_ENVIRONMENT"] = folder.name
            for src, dst, rgb in _pairs(own):
                want = _run(own, own.getCurrentContext(), src, dst, rgb)
                got = _run(show, context, src, dst, rgb)
                error = np.abs(got - want) / np.maximum(1.0, np.abs(want))
                rows[f"{folder.name}: {src} -> {dst}"] = float(error.max())
        out["shows"][show_path] = rows
    Path(result).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
