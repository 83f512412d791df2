"""Does the show config equal each environment's own config, in OCIO 2.2 and 2.6?

    python -m benchmarks.show_compat [--versions 2.2.1 2.6.0] [--venvs DIR] [--out FILE]

Solves the demo stage with a camera gamut (``--camera-colorspace "ARRI Wide Gamut 4"``; the
default method, so several environments get a root-polynomial Q baked as LUTs, and sodium's
rank-1 Q), once with a linear wall and once with a PQ wall with a linearity LUT, exports one
show config of all seven environments per solve on each of OCIO's built-in ACES CG and
studio configs (``--base-config``), then, in a throwaway venv per OCIO version (``pip install
opencolorio==V numpy``), runs :mod:`benchmarks.show_compat_worker`: every show config loads and
validates, and per environment (``VP_ENVIRONMENT``) ACEScg -> each wall space, Stage Footage ->
ACEScg and Stage Footage (LogC4) -> ACEScg are compared with the environment's own config on
6000 linear inputs in [0, 1] and [-0.25, 16] (4000 log inputs in [0, 1]). Prints the Markdown
table of docs/exports.md (worst difference per version and pair kind) and exits 1 when any
exceeds 1e-4 (relative to max(1, |value|)).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.ocio_compat import add_ramps, make_venv  # noqa: E402

WORKER = Path(__file__).resolve().parent / "show_compat_worker.py"
VERSIONS = ("2.2.1", "2.6.0")
TOLERANCE = 1e-4
CAMERA = "ARRI Wide Gamut 4"
#: (label, --base-config or None for the default) of the show configs per solve.
BASES = (("ACES CG", None), ("ACES studio", "ocio://studio-config-v1.0.0_aces-v1.3_ocio-v2.1"))


def build(root: Path) -> list[tuple[str, Path, list[Path]]]:
    """(label, calibration folder, [show configs]) for a linear and a PQ wall."""
    from ocio_vp.cli import main as cli

    def run(*args: str) -> None:
        if cli(list(args)) != 0:
            raise SystemExit(f"ocio-vp {' '.join(args)} failed")

    run("demo", "--out", str(root / "demo"), "--no-report")
    stage = root / "demo" / "paper_stage.yaml"
    ramps = root / "ramps.yaml"
    ramps.write_text(yaml.safe_dump(add_ramps(yaml.safe_load(stage.read_text()))))
    cases = []
    for label, measurements, wall in (
        ("linear wall", stage, "linear"),
        ("PQ wall, LUT", ramps, "pq"),
    ):
        calib = root / wall
        run("solve", str(measurements), "--out", str(calib), "--camera-colorspace", CAMERA,
            "--wall-encoding", wall)  # fmt: skip
        shows = []
        for i, (_, base) in enumerate(BASES):
            out = root / f"show-{wall}-{i}"
            run("export", str(calib), "--target", "show", "--out", str(out),
                *(("--base-config", base) if base else ()))  # fmt: skip
            shows.append(out / "show" / "config.ocio")
        cases.append((label, calib, shows))
    return cases


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--versions", nargs="+", default=list(VERSIONS))
    parser.add_argument("--venvs", type=Path, help="keep the venvs here and reuse them")
    args = parser.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="show-compat-"))
    try:
        cases = build(work)
        lines = ["| OCIO | wall | base config | ACEScg -> wall | footage -> ACEScg | LogC4 footage -> ACEScg | result |",
                 "|---|---|---|---|---|---|---|"]  # fmt: skip
        failed = False
        for version in args.versions:
            python = make_venv((args.venvs or work / "venvs") / f"ocio-{version}", version)
            for label, calib, shows in cases:
                result = work / f"{version}-{calib.name}.json"
                subprocess.run([str(python), str(WORKER), str(result), *map(str, shows), "--",
                                str(calib)], check=True)  # fmt: skip
                data = json.loads(result.read_text())
                for show, (how, _) in zip(shows, BASES, strict=True):
                    rows = data["shows"][str(show)]
                    worst = [max((v for k, v in rows.items() if test(k)), default=0.0) for test in (
                        lambda k: "LED Wall" in k,
                        lambda k: k.split(": ")[1].startswith("Stage Footage ->"),
                        lambda k: "(LogC4)" in k)]  # fmt: skip
                    ok = max(worst) <= TOLERANCE
                    failed |= not ok
                    lines.append(f"| {data['version']} | {label} | {how} | "
                                 + " | ".join(f"{w:.1e}" for w in worst)
                                 + f" | {'pass' if ok else 'FAIL'} |")  # fmt: skip
        print("\n".join(lines))
        return 1 if failed else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
