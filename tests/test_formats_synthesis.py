"""The ``synthesized`` record of an environment: round trip and strict validation."""

from __future__ import annotations

import copy

import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.measurements import (
    load_measurements,
    measurements_from_dict,
    measurements_to_dict,
    save_measurements,
)
from ocio_vp.formats.synthesis import SynthesisRecord, synthesis_warnings
from ocio_vp.simulator import paper_stage_measurements

RECORD = {
    "source": "hdri",
    "hdri": "sky.exr",
    "colorspace": "camera",
    "illuminant": "CIE daylight",
    "cct": 5503.1,
    "duv": 0.0032,
    "camera": "Nikon 5100 (NPL) spectral sensitivities",
    "chart": "ColorChecker N Ohta",
    "assumptions": ["the light is daylight"],
    "warnings": ["a warning"],
}


@pytest.fixture(scope="module")
def document():
    data = measurements_to_dict(paper_stage_measurements(["direct_sun"]))
    data["environments"][0]["synthesized"] = dict(RECORD)
    return data


def test_round_trip_through_a_file(document, tmp_path):
    measurements = measurements_from_dict(document)
    record = measurements.environments[0].synthesized
    assert record == SynthesisRecord(
        source="hdri",
        hdri="sky.exr",
        colorspace="camera",
        illuminant="CIE daylight",
        cct=5503.1,
        duv=0.0032,
        camera="Nikon 5100 (NPL) spectral sensitivities",
        chart="ColorChecker N Ohta",
        assumptions=("the light is daylight",),
        warnings=("a warning",),
    )
    for name in ("m.yaml", "m.json"):
        save_measurements(measurements, tmp_path / name)
        assert load_measurements(tmp_path / name).environments[0].synthesized == record


def test_environments_without_it_are_unchanged(document):
    plain = copy.deepcopy(document)
    del plain["environments"][0]["synthesized"]
    assert measurements_from_dict(plain).environments[0].synthesized is None
    assert (
        "synthesized" not in measurements_to_dict(measurements_from_dict(plain))["environments"][0]
    )


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("source", "photo", "expected one of hdri, average-rgb"),
        ("cct", -3.0, "expected a number > 0"),
        ("cct", "warm", "expected a number"),
        ("duv", 2.0, r"in \[-1, 1\]"),
        ("assumptions", [], "non-empty list"),
        ("assumptions", "one", "non-empty list"),
        ("warnings", ["two\nlines"], "one line"),
        ("camera", "", "non-empty text"),
        ("colour", "x", "unknown key"),
    ],
)
def test_bad_records_name_the_key(document, key, value, message):
    bad = copy.deepcopy(document)
    bad["environments"][0]["synthesized"][key] = value
    with pytest.raises(InputError, match=message) as error:
        measurements_from_dict(bad, source="m.yaml")
    assert f"environments[0].synthesized.{key}" in str(error.value)
    assert "\n" not in str(error.value)


def test_missing_required_key(document):
    bad = copy.deepcopy(document)
    del bad["environments"][0]["synthesized"]["chart"]
    with pytest.raises(InputError, match="missing required key 'chart'"):
        measurements_from_dict(bad)


def test_warnings_say_synthesized_and_repeat_the_record(document):
    record = measurements_from_dict(document).environments[0].synthesized
    lines = synthesis_warnings(record)
    assert "SYNTHESIZED from the HDRI sky.exr" in lines[0] and "5503 K" in lines[0]
    assert lines[1:] == ["synthesized target: a warning"]
