"""Movie takes: one simulated take measured from ProRes (log, Y'CbCr) and from linear EXR frames.

The take is the simulator's (the stage and camera of tests/test_plates_take.py: Sigma SDMerill,
Gaussian LEDs 620/535/455 nm; 25 fps against 24, 1 % noise, 2 % flicker, a dropped frame),
rendered twice with the same seed: as half-float EXR frames, and as a QuickTime movie encoded
with ARRI LogC3, converted to 10-bit Y'CbCr by colour-science and compressed by FFmpeg's
ProRes encoder. The EXR measurement is the reference; the Y'CbCr decoding is checked against
colour-science's inverse.
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.formats.documents import read_document
from ocio_vp.patterns.design import PatternOptions, calibration_sequence
from ocio_vp.patterns.frames import write_sequence_folder
from ocio_vp.patterns.sequence import load_sequence
from ocio_vp.plates.movie import open_movie, parse_point, ycbcr_to_rgb
from ocio_vp.simulator.movie import write_movie
from ocio_vp.simulator.take import TakeOptions, write_take
from ocio_vp.wall.linearity import CHANNELS

TAKE = TakeOptions(
    fps=25.0, preroll=1.0, dropped=(300,), flicker=0.02, noise=0.01, size=(96, 54), seed=11
)
STAGE = {"name": "movie-stage", "calibration_panel": {"width": 1.0, "height": 1.0, "distance": 1.0}}
PATTERNS = PatternOptions(size=(64, 36), hold=8, steps=9)  # 595 camera frames


@pytest.fixture(scope="module")
def filmed(tmp_path_factory):
    """The patterns, and the same take as EXR frames and as ProRes 4444 / 422 HQ movies."""
    from ocio_vp.simulator.stage import spectral_stage

    SL = spectral_stage(camera="Sigma SDMerill (NPL)", leds=[(620, 25), (535, 30), (455, 20)]).SL
    folder = tmp_path_factory.mktemp("movie")
    path = write_sequence_folder(calibration_sequence(PATTERNS), folder / "patterns")
    sequence = load_sequence(path)
    name = write_take(sequence, SL, folder / "take", TAKE)
    write_movie(sequence, SL, folder / "A001.mov", TAKE, codec="prores4444")
    write_movie(sequence, SL, folder / "A002.mov", TAKE, codec="prores422")
    write_movie(sequence, SL, folder / "A003.mov", TAKE, tags=False, timecode="10:00:00:00")
    return folder, f"take/{name}"


def _capture(folder: Path, frames: str, **take) -> Path:
    entry = {"frames": frames, "sequence": "patterns/sequence.yaml", **take}
    document = {"format": "ocio-vp/capture", "version": 1, "stage": STAGE, "take": entry}
    path = folder / f"capture_{Path(frames).stem.replace('#', '')}_{len(take)}.yaml"
    path.write_text(yaml.safe_dump(document))
    return path


def _measure(capture: Path) -> dict:
    out = capture.with_suffix(".out.yaml")
    assert main(["measure", str(capture), "--out", str(out)]) == 0
    return read_document(out)[0]


@pytest.fixture(scope="module")
def readings(filmed):
    folder, exr = filmed
    return {
        "exr": _measure(_capture(folder, exr)),
        "prores4444": _measure(_capture(folder, "A001.mov", encoding="ARRI LogC3")),
        "prores422": _measure(_capture(folder, "A002.mov", encoding="ARRI LogC3")),
    }


def _SL(data: dict) -> np.ndarray:
    return np.array([data["primaries"][c] for c in CHANNELS]).T


@pytest.mark.parametrize(("codec", "bound"), [("prores4444", 0.005), ("prores422", 0.01)])
def test_SL_from_prores_matches_the_exr_take(readings, codec, bound):
    reference, movie = _SL(readings["exr"]), _SL(readings[codec])
    error = np.abs(movie - reference).max(axis=0) / np.abs(reference).max(axis=0)
    assert np.all(error < bound), error  # observed: 0.09 % (4444), 0.10 % (422)


@pytest.mark.parametrize(("codec", "bound"), [("prores4444", 0.01), ("prores422", 0.01)])
def test_every_ramp_step_above_2_percent_matches_within_its_own_level(readings, codec, bound):
    for k, channel in enumerate(CHANNELS):
        reference = np.array(readings["exr"]["ramps"][channel]["camera"])
        movie = np.array(readings[codec]["ramps"][channel]["camera"])
        assert (
            readings[codec]["ramps"][channel]["drive"] == readings["exr"]["ramps"][channel]["drive"]
        )
        level = reference[:, k] / reference[-1, k]
        bright = level > 0.02
        relative = np.abs(movie[bright, k] - reference[bright, k]) / reference[bright, k]
        # observed: within 0.48 % (4444), 0.54 % (422)
        assert bright.sum() >= 7 and np.all(relative < bound), (channel, relative)


def test_the_movie_header(filmed):
    folder, _ = filmed
    info = open_movie(folder / "A001.mov", encoding="ARRI LogC3")
    assert (info.codec, info.matrix, info.range, info.tags_from) == (
        "prores",
        "rec709",
        "legal",
        "stream",
    )
    assert info.rate == 25 and info.timecode == "01:00:00:00" and info.bits >= 10
    assert open_movie(folder / "A002.mov", encoding=None).subsampling == (2, 1)


@pytest.mark.parametrize("matrix", ["rec709", "rec2020", "rec601"])
@pytest.mark.parametrize(("bits", "range_"), [(10, "legal"), (12, "full"), (10, "full")])
def test_ycbcr_decoding_against_colour_science(matrix, bits, range_):
    import colour

    weights = {"rec709": "ITU-R BT.709", "rec2020": "ITU-R BT.2020", "rec601": "ITU-R BT.601"}
    rng = np.random.default_rng(3)
    codes = rng.integers(64 << (bits - 10), 940 << (bits - 10), size=(50, 3))
    codes[:, 1:] = rng.integers(64 << (bits - 10), 960 << (bits - 10), size=(50, 2))
    ours = ycbcr_to_rgb(
        codes[:, 0], codes[:, 1], codes[:, 2], bits=bits, matrix=matrix, range_=range_
    )
    theirs = colour.YCbCr_to_RGB(
        codes,
        K=colour.WEIGHTS_YCBCR[weights[matrix]],
        in_bits=bits,
        in_legal=range_ == "legal",
        in_int=True,
    )
    np.testing.assert_allclose(ours, theirs, atol=2e-6)


def test_timecode_points():
    rate = Fraction(25)
    assert parse_point("10:00:02:05", rate, "10:00:00:00", "take.in", "a.mov") == 55
    with pytest.raises(InputError, match="before the movie's start"):
        parse_point("09:59:59:00", rate, "10:00:00:00", "take.in", "a.mov")
    with pytest.raises(InputError, match="not valid at 25 fps"):
        parse_point("10:00:00:25", rate, "10:00:00:00", "take.out", "a.mov")


def test_in_and_out_points_measure_the_same_part(filmed, readings):
    """The untagged movie (start 10:00:00:00) with its tags in the capture file and in/out
    points around the sequence (timecode and frame number) measures what the whole take does."""
    folder, _ = filmed
    first, last = 5, 585  # frames of the 595-frame take (PATTERNS) around its sequence
    capture = _capture(
        folder,
        "A003.mov",
        encoding="ARRI LogC3",
        matrix="Rec.709",
        range="legal",
        **{"in": f"10:00:00:{first:02d}", "out": last},
    )
    data = _measure(capture)
    np.testing.assert_allclose(_SL(data), _SL(readings["prores4444"]), rtol=1e-6, atol=1e-9)
    samples, _ = read_document(capture.with_suffix(".out.overlays") / "samples.json")
    movie = samples["take"]["movie"]
    assert (movie["matrix"], movie["range"], movie["matrix_and_range_from"]) == (
        "rec709",
        "legal",
        "capture file",
    )
    # The take starts at 10:00:00:00, so the in point is frame ``first``; in and out both count.
    assert movie["start_timecode"] == "10:00:00:00"
    assert samples["take"]["frame_count"] == last - first + 1


def _refused(capture: Path, capsys) -> str:
    out = capture.with_suffix(".out.yaml")
    assert main(["measure", str(capture), "--out", str(out)]) == 2
    assert not out.exists() and not out.with_suffix(".overlays").exists()
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def test_a_movie_without_a_colour_matrix_names_the_key(filmed, capsys):
    """ProRes carries no range flag (FFmpeg's decoder states legal, as Apple's spec does), so
    an untagged ProRes lacks only the matrix: the refusal names take.matrix alone."""
    folder, _ = filmed
    line = _refused(_capture(folder, "A003.mov", encoding="ARRI LogC3"), capsys)
    assert "A003.mov" in line and "give take.matrix in the capture file" in line
    assert "take.range" not in line.split("(")[0]


def test_bad_media_are_refused_on_one_line(filmed, tmp_path, capsys):
    import shutil

    folder, _ = filmed
    truncated = folder / "cut.mov"
    data = (folder / "A001.mov").read_bytes()
    truncated.write_bytes(data[: len(data) // 2])
    line = _refused(_capture(folder, "cut.mov", encoding="ARRI LogC3"), capsys)
    assert "cut.mov" in line and "cannot open as a movie" in line
    (folder / "text.mp4").write_text("not a movie\n")
    assert "cannot open as a movie" in _refused(_capture(folder, "text.mp4"), capsys)
    shutil.copy(folder / "A001.mov", folder / "late.mov")
    line = _refused(_capture(folder, "late.mov", encoding="ARRI LogC3", **{"in": 5000}), capsys)
    assert "take.in is frame 5000" in line


def test_a_variable_frame_rate_movie_is_refused(tmp_path):
    import av

    from ocio_vp.plates.movie import scan_movie

    path = tmp_path / "vfr.mov"
    with av.open(str(path), "w", format="mov") as container:
        stream = container.add_stream("prores_ks", rate=25)
        stream.width, stream.height, stream.pix_fmt = 32, 16, "yuv422p10le"
        stream.codec_context.time_base = Fraction(1, 100)
        for k, pts in enumerate([0, 4, 8, 20, 24, 28]):
            frame = av.VideoFrame(32, 16, "yuv422p10le")
            for plane in frame.planes:
                plane.update(np.full(plane.buffer_size // 2, 512 + 10 * k, np.uint16).tobytes())
            frame.pts, frame.time_base = pts, Fraction(1, 100)
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    info = open_movie(path, encoding=None, matrix="rec709", range_="legal")
    with pytest.raises(InputError, match="variable frame rate"):
        scan_movie(info, (0, 0, 32, 16), [(0, 16)], [(0, 16)], clip=None)


def test_movie_keys_are_only_for_movies(tmp_path, capsys):
    capture = _capture(tmp_path, "take/A001.####.exr", matrix="rec709")
    line = _refused(capture, capsys)
    assert "take.matrix" in line and "only for a movie take" in line
    capture = _capture(tmp_path, "A001.mov", range="studio")
    assert "expected one of legal, full" in _refused(capture, capsys)


@pytest.mark.parametrize("encoding", ["ARRI LogC3", "ARRI LogC4", "S-Log3", "sRGB", "Gamma 2.4"])
def test_the_decoding_table_against_colour_science(encoding):
    """Within 2e-5 relative above 1e-4 linear (the worst: a curve's cut between its linear
    toe and its log part, where a table step straddles the kink); observed 1.2e-5 (S-Log3)."""
    from ocio_vp.plates.movie import decode_log
    from ocio_vp.plates.reader import linearise

    low = 0.0 if encoding == "Gamma 2.4" else -0.3  # a pure power has no negative values
    codes = np.concatenate([np.linspace(low, 1.6, 20001), np.random.default_rng(1).random(5000)])
    table, exact = decode_log(codes, encoding), linearise(codes, encoding)
    judged = np.abs(exact) > 1e-4
    assert np.max(np.abs(table - exact)[judged] / np.abs(exact[judged])) < 2e-5
    assert np.max(np.abs(table - exact)[~judged]) < 1e-9


@pytest.mark.parametrize(("pix_fmt", "sub"), [("yuv420p10le", (2, 2)), ("yuv422p10le", (2, 1))])
def test_subsampled_chroma_lands_on_its_pixels(pix_fmt, sub):
    """A decoded 4:2:0 / 4:2:2 frame built from known planes: every pixel of an odd box gets
    the chroma sample covering it (colour-science converts the expected codes)."""
    import av
    import colour

    from ocio_vp.plates.movie import MovieInfo, frame_rgb

    width, height = 36, 20
    rng = np.random.default_rng(7)
    frame = av.VideoFrame(width, height, pix_fmt)
    planes = []
    for plane in frame.planes:
        values = rng.integers(100, 900, size=(plane.height, plane.line_size // 2)).astype(np.uint16)
        plane.update(values.tobytes())
        planes.append(values[:, : plane.width])
    info = MovieInfo(
        path=Path("x.mov"), codec="test", pix_fmt=pix_fmt, width=width, height=height, bits=10,
        rgb=False, subsampling=sub, matrix="rec2020", range="legal", tags_from="stream",
        rate=Fraction(25), frames=1, first=0, last=None, timecode=None, encoding="linear",
    )  # fmt: skip
    x0, y0, x1, y1 = 3, 5, 30, 17
    ys, xs = np.mgrid[y0:y1, x0:x1]
    codes = np.stack(
        [
            planes[0][ys, xs],
            planes[1][ys // sub[1], xs // sub[0]],
            planes[2][ys // sub[1], xs // sub[0]],
        ],
        axis=-1,
    )
    expected = colour.YCbCr_to_RGB(
        codes, K=colour.WEIGHTS_YCBCR["ITU-R BT.2020"], in_bits=10, in_legal=True, in_int=True
    )
    np.testing.assert_allclose(frame_rgb(frame, info, (x0, y0, x1, y1)), expected, atol=2e-6)


def test_a_pixel_format_ocio_vp_does_not_read_is_refused(tmp_path):
    import av

    path = tmp_path / "rgb.mov"
    with av.open(str(path), "w", format="mov") as container:
        stream = container.add_stream("png", rate=25)
        stream.width, stream.height, stream.pix_fmt = 16, 8, "rgb24"
        frame = av.VideoFrame.from_ndarray(np.zeros((8, 16, 3), np.uint8), format="rgb24")
        for packet in [*stream.encode(frame), *stream.encode()]:
            container.mux(packet)
    with pytest.raises(InputError, match="pixel format 'rgb24' is not a planar"):
        open_movie(path, encoding=None)


@pytest.mark.parametrize(
    ("encoder", "pix_fmt", "name", "options"),
    [
        ("dnxhd", "yuv422p10le", "dnxhr.mxf", {"profile": "dnxhr_hqx"}),
        ("libx265", "yuv420p10le", "hevc.mp4", {"x265-params": "lossless=1:log-level=error"}),
    ],
)
def test_dnxhr_in_mxf_and_10_bit_hevc_decode_at_their_codes(
    tmp_path, encoder, pix_fmt, name, options
):
    """Rec.2020-tagged 10-bit DNxHR HQX in MXF and lossless H.265 Main 10 in MP4, flat frames of
    known codes: every frame read back as colour-science converts those codes."""
    import av
    import colour

    from ocio_vp.plates.movie import scan_movie

    path = tmp_path / name
    codes = [(400 + 3 * k, 500 + k, 600 - 2 * k) for k in range(12)]
    with av.open(str(path), "w") as container:
        stream = container.add_stream(encoder, rate=25)
        stream.width, stream.height, stream.pix_fmt = 256, 144, pix_fmt
        stream.options = options
        ctx = stream.codec_context
        ctx.colorspace, ctx.color_range, ctx.color_primaries, ctx.color_trc = 9, 1, 9, 14
        for k, code in enumerate(codes):
            frame = av.VideoFrame(256, 144, pix_fmt)
            for plane, value in zip(frame.planes, code, strict=True):
                plane.update(np.full(plane.buffer_size // 2, value, np.uint16).tobytes())
            frame.pts = k
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    info = open_movie(path, encoding=None)
    assert (info.matrix, info.range, info.tags_from) == ("rec2020", "legal", "stream")
    numbers, signal, _ = scan_movie(info, (8, 8, 248, 136), [(60, 64)], [(10, 12)], clip=None)
    expected = colour.YCbCr_to_RGB(
        np.array(codes),
        K=colour.WEIGHTS_YCBCR["ITU-R BT.2020"],
        in_bits=10,
        in_legal=True,
        in_int=True,
    )
    assert numbers.tolist() == list(range(12))
    np.testing.assert_allclose([s.mean for s in signal], expected, atol=1e-5)
