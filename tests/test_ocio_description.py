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
from ocio_vp.ocio.matrix import matrix_record

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


def test_the_environment_config_is_its_description_built():
    """What config_data says is exactly what the written config holds: compared as data."""
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.ocio.config import config_data

    solution = load_solution(SAMPLES[0].parent)
    data = config_data(solution)
    assert config_record(build(data)) == data
    assert data.colour_space("Stage Footage").to_reference == matrix_record(solution.Q)
    inner = data.colour_space("LED Wall - Inner Frustum")
    assert inner.from_reference == matrix_record(solution.N, solution.black_level_offset)
    assert "N NOT SOLVED" not in inner.description


def test_a_base_config_with_a_transform_without_record_is_refused(tmp_path):
    from ocio_vp.errors import InputError
    from ocio_vp.ocio.show import ShowEnvironment, build_show_config

    base = OCIO.Config.CreateRaw()
    aces = OCIO.ColorSpace(name="aces", toReference=OCIO.CDLTransform(slope=[1.1] * 3))
    base.addColorSpace(aces)
    base.setRole("aces_interchange", "aces")
    path = tmp_path / "base.ocio"
    path.write_text(base.serialize(), encoding="utf-8")
    env = ShowEnvironment("a", OCIO.Config.CreateFromFile(str(SAMPLES[0])))
    with pytest.raises(InputError, match="CDLTransform"):
        build_show_config([env], str(path))
