"""``sequence.yaml`` (``ocio-vp/patterns`` v1): strict validation, errors naming the key."""

from __future__ import annotations

import copy

import pytest

from ocio_vp.errors import InputError
from ocio_vp.patterns.design import PatternOptions, calibration_sequence
from ocio_vp.patterns.sequence import sequence_from_dict, sequence_to_dict


@pytest.fixture(scope="module")
def document():
    return sequence_to_dict(calibration_sequence(PatternOptions(steps=5, hold=4)))


def _mutated(document, change):
    data = copy.deepcopy(document)
    change(data)
    return data


def _ramp(data, channel="red", step=-1):
    return [p for p in data["patches"] if p.get("channel") == channel and p["kind"] == "ramp"][step]


BAD = {
    "unknown key": (lambda d: d.update(fps_=24), "fps_: unknown key (did you mean 'fps'?)"),
    "wrong format": (lambda d: d.update(format="ocio-vp/capture"), "format: expected"),
    "two frame fields": (
        lambda d: d.update(frames="a.##.b.##.exr"),
        "frames: expected a file pattern",
    ),
    "absolute frames": (lambda d: d.update(frames="/tmp/a.####.exr"), "relative to the sequence"),
    "pq without peak": (
        lambda d: d.update(encoding="pq", peak_nits=None),
        "peak_nits: expected a number",
    ),
    "peak without pq": (lambda d: d.update(peak_nits=1000), "only a pq sequence has a peak"),
    "gap": (lambda d: d["patches"][3].update(first=d["patches"][3]["first"] + 1), "do not follow"),
    "unknown kind": (lambda d: d["patches"][2].update(kind="grey"), "unknown kind 'grey'"),
    "ramp top": (lambda d: _ramp(d).update(drive=[0.99, 0, 0]), "end at exactly 1.0"),
    "negative drive": (
        lambda d: d["patches"][2].update(drive=[-0.1, 0, 0]),
        "drive[0]: expected a number >= 0",
    ),
    "flash outside": (
        lambda d: d["patches"][1]["flashes"][0].__setitem__(0, 1),
        "inside the patch",
    ),
    "duplicate name": (lambda d: d["patches"][3].update(name="black"), "duplicate name 'black'"),
    "bad fps": (lambda d: d.update(fps=0), "fps: expected a number > 0"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_sequence_files_are_one_line_errors(document, case):
    change, message = BAD[case]
    with pytest.raises(InputError) as raised:
        sequence_from_dict(_mutated(document, change), source="seq.yaml")
    text = str(raised.value)
    assert text.startswith("seq.yaml: ") and message in text and "\n" not in text


def test_a_valid_document_loads(document):
    sequence = sequence_from_dict(document, source="seq.yaml")
    assert sequence.patch("white").kind == "white"
    assert sequence.validation is None and sequence.hold == 4


_VALIDATION = {"environment": "e", "stage": "s", "solution_sha256": "ab", "in_frustum": "x"}


@pytest.mark.parametrize("reference", ["two\nlines", "x" * 600, "   "])
def test_validation_texts_that_loaded_before_still_load(document, reference):
    data = _mutated(document, lambda d: d.update(validation=_VALIDATION | {"reference": reference}))
    assert sequence_from_dict(data, source="seq.yaml").validation.reference == reference


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda d: d.update(validation=_VALIDATION | {"reference": ""}),
            "validation.reference: expected a non-empty text",
        ),
        (lambda d: d.update(size=[1, 2, 3]), "size: expected [width, height]"),
    ],
)
def test_sequence_messages_read_as_before(document, change, message):
    with pytest.raises(InputError) as raised:
        sequence_from_dict(_mutated(document, change), source="seq.yaml")
    assert str(raised.value) == f"seq.yaml: {message}"
