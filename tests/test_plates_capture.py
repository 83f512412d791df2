"""The capture file (ocio_vp.plates.capture): validation with key paths, paths relative to it."""

from __future__ import annotations

import pytest
import yaml
from test_plates_measure import ENVIRONMENTS, write_capture

from ocio_vp.errors import InputError
from ocio_vp.plates.capture import capture_from_dict, load_capture
from ocio_vp.simulator.stage import paper_stage, simulate_measurements


@pytest.fixture(scope="module")
def capture_file(tmp_path_factory):
    truth = simulate_measurements(ENVIRONMENTS, stage=paper_stage())
    return write_capture(tmp_path_factory.mktemp("stage") / "plates", truth)


class TestCaptureFile:
    @pytest.mark.parametrize(
        ("edit", "message"),
        [
            (lambda d: d.update(formt=1), "formt: unknown key"),
            (lambda d: d["primaries"].update(red=[10, 10, 5, 20]), "primaries.red: empty region"),
            (lambda d: d["lit_chart"]["red"].update(corners=[[1, 2]]), "lit_chart.red.corners"),
            (lambda d: d["chart"].update(inset=0.6), "chart.inset: expected at most 0.45"),
            (lambda d: d["sampling"].update(method="avg"), "sampling.method: unknown method"),
            (lambda d: d["stage"].update(white_reflectance=2), "stage.white_reflectance"),
            (lambda d: d["lit_chart"]["red"].update(encoding="gama"), "unknown encoding"),
        ],
    )
    def test_invalid(self, capture_file, edit, message):
        document = yaml.safe_load(capture_file.read_text())
        document.setdefault("sampling", {})
        edit(document)
        with pytest.raises(InputError, match=message.replace(".", r"\.")) as info:
            capture_from_dict(document, source=str(capture_file))
        assert str(info.value).startswith(str(capture_file))

    def test_paths_relative_to_the_file(self, capture_file):
        capture = load_capture(capture_file)
        assert capture.lit_chart["red"].plate.paths[0] == capture_file.parent / "plates/lit_red.exr"
        assert capture.primaries["red"].plate is capture.primaries["blue"].plate  # shared plate
        assert len(capture.lit_chart["red"].plate.flat_field) == 4
