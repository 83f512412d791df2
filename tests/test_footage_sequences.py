"""Frame sequences (ocio_vp.footage.sequences): patterns, numeric order, ranges, collisions."""

from __future__ import annotations

from pathlib import Path

import pytest

from ocio_vp.errors import InputError
from ocio_vp.footage.sequences import expand_frames, frame_pattern, output_paths, parse_frame_range


class TestSequences:
    def test_patterns(self):
        assert frame_pattern("a.####.exr") == ("a.", ".exr", 4)
        assert frame_pattern("a.%04d.exr") == ("a.", ".exr", 4)
        assert frame_pattern("a.%d.exr") == ("a.", ".exr", 0)
        assert frame_pattern("a.#.exr") == ("a.", ".exr", 0)
        assert frame_pattern("a.exr") is None
        with pytest.raises(InputError, match="more than one"):
            frame_pattern("a.##.%04d.exr")

    def test_expand_sorts_numerically_and_ranges(self, tmp_path):
        for f in (9, 10, 100):
            (tmp_path / f"p.{f}.exr").write_bytes(b"")
        (tmp_path / "p.x.exr").write_bytes(b"")
        got = expand_frames([str(tmp_path / "p.#.exr")])
        assert [p.name for p in got] == ["p.9.exr", "p.10.exr", "p.100.exr"]
        assert parse_frame_range("1001-1003") == range(1001, 1004)
        with pytest.raises(InputError, match="before"):
            parse_frame_range("5-1")
        with pytest.raises(InputError, match="no frames match"):
            expand_frames([str(tmp_path / "q.####.exr")])

    def test_output_collisions_are_errors(self, tmp_path):
        with pytest.raises(InputError, match="both be written"):
            output_paths([Path("a/x.exr"), Path("b/x.exr")], tmp_path)
