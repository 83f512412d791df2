"""The ``linearity`` block as typed records: the same after a solve and after a load, and
``solution.json``'s keys, order and values unchanged for the scripts that read them."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.formats.linearity import (
    MEASURED_KEYS,
    ChannelBlack,
    ChannelNoise,
    Linearity,
    LinearityChannel,
    LutFile,
    ShadowDeviation,
    SoftClip,
    WallEncodingBlock,
    assumed_linearity,
    read_linearity,
)
from ocio_vp.formats.records import json_value


def _channel(corrected: bool) -> LinearityChannel:
    drive = np.array([0.0, 0.25, 1.0])
    return LinearityChannel(
        drive=drive,
        response=np.array([0.0, 0.2, 1.0]) if corrected else drive,
        measured_response=np.array([0.0, 0.2, 1.0]),
        max_deviation=0.05 if corrected else 0.0,
        shadow_deviation=ShadowDeviation(relative=-0.2, uncertainty=0.01, drive=0.25)
        if corrected
        else None,
        corrected=corrected,
        black=ChannelBlack(source="zero step", camera=np.array([-0.001, 0.0, 0.002]), level=-0.01),
        noise=ChannelNoise(floor=1e-4, relative=0.002, source="given", detection_limit=5e-4),
        below_floor=[1],
        merged=[[2, 3]],
        at_top=[],
        projection_residual=0.001,
        top_step_vs_primary=0.004,
    )


def measured() -> Linearity:
    return Linearity(
        measured=True,
        model="isotonic-pchip-inverse-1d-lut",
        summary="red deviates",
        notes=["red: ..."],
        warnings=[],
        tolerance=0.002,
        relative_tolerance=0.01,
        max_deviation=0.05,
        projection="least squares",
        channels={"red": _channel(True), "green": _channel(False), "blue": _channel(False)},
        lut=None,
        present=MEASURED_KEYS,
    )


def written(block: Linearity) -> str:
    return json.dumps(json_value(block), indent=2)


class TestRoundTrip:
    def test_a_measured_block_reads_back_and_writes_the_same_bytes(self):
        lut = LutFile("luts/x.clf", 4095, "drive", 0.001, [{"from": 0.002, "to": 1.0, "max_error": 0.001, "at": 0.5}], "max |r(LUT(x)) - x| / x")  # fmt: skip
        block = measured().updated(
            lut=lut,
            wall_encoding=WallEncodingBlock("pq", 1000.0),
            soft_clip=SoftClip(0.8, "curve", 1.2, 0.99),
        )
        text = written(block)
        back = read_linearity(json.loads(text))
        assert written(back) == text
        assert back.lut == lut and back.soft_clip == block.soft_clip
        assert back.channels["red"].shadow_deviation == ShadowDeviation(-0.2, 0.01, 0.25)
        np.testing.assert_array_equal(back.channels["red"].drive, [0.0, 0.25, 1.0])
        assert back.channels["red"].drive.dtype == np.float64  # arrays after a load too

    def test_the_keys_are_the_file_format_in_file_order(self):
        data = json.loads(written(measured()))
        assert list(data) == list(MEASURED_KEYS)
        assert data["lut"] is None  # a measured block says it has no LUT
        assert list(data["channels"]["red"]) == [
            "drive", "response", "measured_response", "max_deviation", "shadow_deviation",
            "corrected", "black", "noise", "below_floor", "merged", "at_top",
            "projection_residual", "top_step_vs_primary",
        ]  # fmt: skip
        assert data["channels"]["green"]["shadow_deviation"] is None

    def test_an_older_or_newer_file_keeps_its_keys_and_order(self):
        text = json.dumps(
            {
                "model": "linear (assumed)",
                "measured": False,
                "future_key": [1, 2],
                "wall_encoding": {"name": "pq", "peak_nits": 1000.0},
            }
        )
        block = read_linearity(json.loads(text))
        assert block.wall_encoding == WallEncodingBlock("pq", 1000.0)
        assert json.dumps(json_value(block)) == text


class TestUpdated:
    def test_new_keys_go_after_the_blocks_own(self):
        block = assumed_linearity().updated(soft_clip=SoftClip(0.8, "c", 1.2, 0.99))
        block = block.updated(wall_encoding=WallEncodingBlock("srgb"))
        assert list(json_value(block)) == ["measured", "model", "soft_clip", "wall_encoding"]
        # a key the block has keeps its place
        again = block.updated(soft_clip=SoftClip(0.5, "c", 1.5, 0.99))
        assert list(json_value(again)) == list(json_value(block))
        assert again.soft_clip.knee == 0.5


def test_a_value_of_the_wrong_type_is_refused_naming_its_key():
    data = json.loads(written(measured()))
    data["channels"]["red"]["corrected"] = "yes"
    with pytest.raises(InputError, match=r"linearity\.channels\.red\.corrected"):
        read_linearity(data)
    with pytest.raises(InputError, match="expected a mapping"):
        read_linearity([1, 2])
