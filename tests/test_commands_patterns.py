"""``ocio-vp patterns``: the frames and sequence.yaml, one-line refusals, re-runs."""

from __future__ import annotations

import pytest

from ocio_vp.cli import main
from ocio_vp.patterns.sequence import load_sequence


def test_writes_frames_and_sequence_and_reruns(tmp_path, capsys):
    out = tmp_path / "patterns"
    args = ["patterns", "--out", str(out), "--size", "16x9", "--steps", "5", "--hold", "3"]
    for _ in range(2):  # a re-run replaces its own output
        assert main(args) == 0
    sequence = load_sequence(out / "sequence.yaml")
    frames = sorted(out.glob("patterns.*.exr"))
    assert len(frames) == sequence.last_frame == sum(p.frames for p in sequence.patches)
    printed = capsys.readouterr().out
    assert "with every colour transform bypassed" in printed and "sequence.yaml" in printed


def test_case_insensitive_encoding_and_pq_tiff(tmp_path):
    out = tmp_path / "p"
    args = ["patterns", "--out", str(out), "--size", "8x8", "--format", "TIFF"]
    assert main([*args, "--wall-encoding", "PQ", "--peak-nits", "1000"]) == 0
    sequence = load_sequence(out / "sequence.yaml")
    assert (sequence.encoding, sequence.peak_nits, sequence.file_format) == ("pq", 1000.0, "tiff")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--peak-nits", "1000"], "--peak-nits: give --peak-nits with --wall-encoding pq"),
        (["--wall-encoding", "pq"], "--peak-nits"),
        (["--size", "1920"], "--size: expected WIDTHxHEIGHT"),
        (["--hold", "1"], "--hold: expected 2 <= frames"),
        (["--fps", "0"], "--fps"),
        (
            ["--format", "dpx", "--steps", "1000", "--wall-encoding", "pq", "--peak-nits", "100"],
            "--steps: 1000 ramp steps do not fit",
        ),
        (["--validate", "nowhere"], "no solution.json here"),
    ],
)
def test_bad_arguments_exit_2_and_write_nothing(tmp_path, capsys, extra, message):
    out = tmp_path / "p"
    assert main(["patterns", "--out", str(out), "--size", "8x8", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not out.exists()


def test_refuses_a_folder_it_did_not_write(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert main(["patterns", "--out", str(out), "--size", "8x8"]) == 2
    assert "not written by ocio-vp" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
