"""The committed sample data (sample_configs/paper_stage*) is what the code generates now.

Source: the generator itself, run in a temporary folder; the committed files must match it
byte for byte or, on another BLAS build or CPU (``OPENBLAS_CORETYPE``,
``NPY_DISABLE_CPU_FEATURES``), differ only by rounding, each number compared at the
tolerance its quantity deserves:

- camera-linear values, matrices and drives (white = 1): 1e-9 relative or 1e-12 absolute,
  a millionth of a 16-bit code value, far above rounding on a condition number of ~1e3;
- ΔE2000 figures (``led_damage``): 1e-4 ΔE2000, a ten-thousandth of a just-noticeable
  difference; on a rank-deficient Q (sodium) the 95th percentile of ~140 moves by 3e-6
  between BLAS kernels, and a Q = I stage's ~1e-13 is zero in any rounding;
- ``identity_check.max_abs_error`` is rounding by definition: what it means is that it stays
  within its ``bound``, so that is what is compared;

and so the SHA-256 of the measurements file that the configs and solutions quote differs.
Regenerate with ``python -m ocio_vp.simulator.samples sample_configs``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from ocio_vp.simulator.samples import SAMPLE_NAME, write_paper_samples

SAMPLES = Path(__file__).resolve().parent.parent / "sample_configs"
#: Any decimal number, integers included (OCIO writes 1 or 1.00000000000000 by the last bit).
NUMBER = re.compile(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
#: The measurements file's digest (full in solution.json, 16 hex digits in config descriptions):
#: it changes with the last bit of any float in the file, so it is compared as a placeholder.
DIGEST = re.compile(r"\b[0-9a-f]{64}\b|(?<=sha256 )[0-9a-f]{16}\b")
REGENERATE = "stale sample data: run `python -m ocio_vp.simulator.samples sample_configs`"


def _files(root: Path) -> dict[str, bytes]:
    paths = [root / f"{SAMPLE_NAME}.yaml", *sorted((root / SAMPLE_NAME).rglob("*"))]
    return {str(p.relative_to(root)): p.read_bytes() for p in paths if p.is_file()}


#: Relative and absolute tolerance of a camera-linear value, matrix entry or drive (white = 1).
LINEAR = (1e-9, 1e-12)
#: Absolute tolerance of a ΔE2000 figure (solution.json keys; docstring above).
DELTA_E_KEYS = frozenset({"led_damage", "led_damage_least_squares"})
DELTA_E = 1e-4


def _same_numbers(a: list[float], b: list[float], rtol: float, atol: float) -> bool:
    return len(a) == len(b) and bool(np.allclose(a, b, rtol=rtol, atol=atol))


def _same_text_up_to_rounding(a: bytes, b: bytes) -> bool:
    """Configs and the measurements file: the same text, numbers equal as camera-linear values."""
    text_a, text_b = (DIGEST.sub("<sha256>", x.decode()) for x in (a, b))
    if NUMBER.sub("#", text_a) != NUMBER.sub("#", text_b):
        return False
    numbers_a, numbers_b = ([float(x) for x in NUMBER.findall(t)] for t in (text_a, text_b))
    return _same_numbers(numbers_a, numbers_b, *LINEAR)


def _json_differences(a, b, path: str = "") -> list[str]:
    """Where two solution.json trees differ by more than each quantity's tolerance."""
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            return [f"{path}: keys {list(a)} != {list(b)}"]
        if {"max_abs_error", "bound"} <= set(a):  # identity_check: rounding within its bound
            ok = (a["max_abs_error"] <= a["bound"]) == (b["max_abs_error"] <= b["bound"])
            same_bound = _same_numbers([a["bound"]], [b["bound"]], *LINEAR)
            return [] if ok and same_bound else [f"{path}: {a} != {b}"]
        return [d for k in a for d in _json_differences(a[k], b[k], f"{path}/{k}")]
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} != {len(b)} items"]
        return [
            d
            for i, (x, y) in enumerate(zip(a, b, strict=True))
            for d in _json_differences(x, y, f"{path}[{i}]")
        ]
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool):
        key = path.rsplit("/", 1)[-1]
        rtol, atol = (0.0, DELTA_E) if key in DELTA_E_KEYS else LINEAR
        return [] if _same_numbers([a], [b], rtol, atol) else [f"{path}: {a!r} != {b!r}"]
    if isinstance(a, str) and isinstance(b, str) and DIGEST.fullmatch(a) and DIGEST.fullmatch(b):
        return []
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def _same_up_to_rounding(name: str, a: bytes, b: bytes) -> bool:
    if a == b:
        return True
    if name.endswith(".json"):
        return not _json_differences(json.loads(a), json.loads(b))
    return _same_text_up_to_rounding(a, b)


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    out = tmp_path_factory.mktemp("samples")
    write_paper_samples(out)
    return _files(out)


def test_generation_is_deterministic(regenerated, tmp_path):
    write_paper_samples(tmp_path)
    assert _files(tmp_path) == regenerated


def test_committed_samples_are_current(regenerated):
    committed = _files(SAMPLES)
    assert sorted(committed) == sorted(regenerated), REGENERATE
    # the measurements + config.ocio, solution.json and the ocio-vp output marker x 7
    assert len(committed) == 1 + 3 * 7
    stale = [
        name
        for name, data in regenerated.items()
        if not _same_up_to_rounding(name, committed[name], data)
    ]
    assert not stale, f"{REGENERATE}; differs: {stale}"


def test_sample_file_solves_with_the_cli(tmp_path, capsys):
    from ocio_vp.cli import main

    code = main(
        [
            "solve",
            str(SAMPLES / f"{SAMPLE_NAME}.yaml"),
            "--out",
            str(tmp_path),
            "--method",
            "least-squares",
        ]
    )
    assert code == 0
    # the simulated file states no wall encoding (no take): the assumption is said once
    out = capsys.readouterr().out
    assert out.count("states no wall encoding") == 1 and "linear drive assumed" in out
    for env in ("direct_sun", "sodium_vapour"):
        assert (tmp_path / env / "config.ocio").read_bytes() == (
            SAMPLES / SAMPLE_NAME / env / "config.ocio"
        ).read_bytes() or _same_text_up_to_rounding(
            (tmp_path / env / "config.ocio").read_bytes(),
            (SAMPLES / SAMPLE_NAME / env / "config.ocio").read_bytes(),
        )


def test_rounding_passes_and_a_real_change_fails():
    """The comparison by meaning accepts what another BLAS kernel changes (as measured:
    sodium's led_damage 140.1017668 -> 140.1017634, a Q = I stage's 8.4e-14 -> 7.3e-14, an
    identity check's rounding) and refuses a change that means something."""
    committed = json.loads((SAMPLES / SAMPLE_NAME / "sodium_vapour" / "solution.json").read_text())

    def changed(edit) -> list[str]:
        other = json.loads(json.dumps(committed))
        edit(other)
        return _json_differences(committed, other)

    def noise(s):
        s["diagnostics"]["extrapolation"]["led_damage"] -= 3.4e-6
        s["M"][0][0] *= 1 + 1e-13
        s["black_level_offset"][2] = 1.4e-17

    assert changed(noise) == []
    assert changed(lambda s: s["diagnostics"]["extrapolation"].update(led_damage=140.2))
    assert changed(lambda s: s["M"][0].__setitem__(0, s["M"][0][0] + 1e-6))
    assert changed(lambda s: s.update(method="auto"))
    sun = json.loads((SAMPLES / SAMPLE_NAME / "direct_sun" / "solution.json").read_text())
    check = sun["diagnostics"]["identity_check"]
    broken = json.loads(json.dumps(sun))
    broken["diagnostics"]["identity_check"]["max_abs_error"] = 2 * check["bound"]
    assert _json_differences(sun, broken)
    assert not _same_text_up_to_rounding(b"matrix: [1.0, 0.5]", b"matrix: [1.0, 0.5001]")
    assert _same_text_up_to_rounding(b"matrix: [1.0, 0.5]", b"matrix: [1.0, 0.5000000000000001]")
