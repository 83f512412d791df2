"""The committed sample data (sample_configs/paper_stage*) is what the code generates now.

Source: the generator itself, run in a temporary folder; the committed files must match it
byte for byte, or (another BLAS build) differ only in floats by less than 1e-9 relative, and
so in the SHA-256 of the measurements file that the configs and solutions quote.
Regenerate with ``python -m ocio_vp.simulator.samples sample_configs``.
"""

from __future__ import annotations

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


def _same_up_to_float_noise(a: bytes, b: bytes) -> bool:
    text_a, text_b = (DIGEST.sub("<sha256>", x.decode()) for x in (a, b))
    if NUMBER.sub("#", text_a) != NUMBER.sub("#", text_b):
        return False
    numbers_a = np.array([float(x) for x in NUMBER.findall(text_a)])
    numbers_b = np.array([float(x) for x in NUMBER.findall(text_b)])
    return numbers_a.shape == numbers_b.shape and np.allclose(
        numbers_a, numbers_b, rtol=1e-9, atol=1e-15
    )


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
        if committed[name] != data and not _same_up_to_float_noise(committed[name], data)
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
    for env in ("direct_sun", "sodium_vapour"):
        assert (tmp_path / env / "config.ocio").read_bytes() == (
            SAMPLES / SAMPLE_NAME / env / "config.ocio"
        ).read_bytes() or _same_up_to_float_noise(
            (tmp_path / env / "config.ocio").read_bytes(),
            (SAMPLES / SAMPLE_NAME / env / "config.ocio").read_bytes(),
        )
