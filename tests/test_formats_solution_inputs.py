"""The one vocabulary of solution inputs (report, export, apply): solution_folders()."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.solution_inputs import generated_kind, solution_folders


def _solve_output(root: Path, names=("a_env", "b_env", "c_env")) -> Path:
    """A solve output folder: one folder per environment with a solution.json."""
    for name in names:
        (root / name).mkdir(parents=True)
        (root / name / "solution.json").write_text(json.dumps({"environment": name}))
    return root


@pytest.fixture
def calib(tmp_path) -> Path:
    root = _solve_output(tmp_path / "calib")
    (root / "report" / "img").mkdir(parents=True)  # what `report` writes
    (root / "report" / "index.html").write_text("<html></html>")
    (root / "stage.yaml").write_text("format: ocio-vp/measurements\nversion: 1\n")
    (root / "a_env" / "exports" / "nuke").mkdir(parents=True)  # what `export` writes
    return root


class TestSolutionFolders:
    def test_solve_output_means_all_environments(self, calib):
        chosen = solution_folders([calib])
        assert chosen.environments == ["a_env", "b_env", "c_env"]
        assert chosen.complete and chosen.solve_folders == (calib.resolve(),)
        assert chosen.skipped == ()

    def test_a_glob_skips_what_ocio_vp_wrote(self, calib):
        chosen = solution_folders(sorted(calib.iterdir()))
        assert chosen.environments == ["a_env", "b_env", "c_env"] and chosen.complete
        kinds = {p.name: kind for p, kind in chosen.skipped}
        assert kinds == {"report": "a report folder", "stage.yaml": "a measurements file"}
        assert chosen.notes() == [
            f"skipped {calib / 'report'}: a report folder, not a solution",
            f"skipped {calib / 'stage.yaml'}: a measurements file, not a solution",
        ]

    def test_folder_file_and_duplicates(self, calib):
        chosen = solution_folders(
            [calib / "b_env" / "solution.json", calib / "b_env", calib / "a_env"]
        )
        assert chosen.environments == ["b_env", "a_env"]  # the user's order, once each
        assert not chosen.complete

    def test_several_solve_folders(self, calib, tmp_path):
        other = _solve_output(tmp_path / "other", names=("z_env",))
        chosen = solution_folders([calib, other / "z_env"])
        assert chosen.environments == ["a_env", "b_env", "c_env", "z_env"]
        assert chosen.solve_folders == (calib.resolve(), other.resolve())
        assert chosen.complete

    def test_missing_path_is_an_error(self, tmp_path):
        with pytest.raises(InputError, match="no such file or folder") as info:
            solution_folders([tmp_path / "nope"])
        assert info.value.key == "SOLUTION_DIR"

    def test_foreign_folder_is_an_error_not_skipped(self, calib, tmp_path):
        (tmp_path / "holiday").mkdir()
        with pytest.raises(InputError, match=r"no solution\.json here"):
            solution_folders([calib, tmp_path / "holiday"])

    def test_only_generated_things_is_an_error(self, calib):
        with pytest.raises(InputError, match="no solution among"):
            solution_folders([calib / "report"], key="SOLUTION")


def test_generated_kind(calib, tmp_path):
    assert generated_kind(calib / "a_env" / "exports") == "an export folder"
    (tmp_path / "stage.overlays").mkdir()
    assert generated_kind(tmp_path / "stage.overlays") == "an overlay folder"
    (tmp_path / "notes.yaml").write_text("format: something-else\n")
    assert generated_kind(tmp_path / "notes.yaml") is None
    assert generated_kind(calib / "a_env") is None
