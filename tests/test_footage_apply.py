"""``ocio-vp apply``: pixels equal numpy's Q maths, everything else passes through untouched.

The reference for the colour maths is numpy (``Q @ rgb`` in float64 from solution.json's Q,
independent of OCIO); the reference for "untouched" is the input file itself, read back with
OpenImageIO (bitwise equality of the other channels, metadata, windows, compression).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from conftest import make_measurements_dict, oracle_correction

from ocio_vp.cli import main
from ocio_vp.footage import stream
from ocio_vp.footage.apply import (
    TRANSFORMS,
    FrameTask,
    apply_file,
    apply_in_place,
    cpu_processor,
    load_post_correction,
    pixel_transform,
)
from ocio_vp.footage.stream import apply_frames

oiio = pytest.importorskip("OpenImageIO")


@pytest.fixture(scope="module")
def solution_dir(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("solve")
    path = root / "stage.yaml"
    path.write_text(yaml.safe_dump(make_measurements_dict(environments=1)))
    assert main(["solve", str(path), "--out", str(root / "calib")]) == 0
    return root / "calib" / "env_0"


def _Q(solution_dir: Path) -> np.ndarray:
    return np.asarray(json.loads((solution_dir / "solution.json").read_text())["Q"])


def write_image(
    path, pixels, names, *, fmt="float", formats=None, attrs=None, origin=(0, 0), full=None
):
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.channelnames = tuple(names)
    if formats:
        spec.channelformats = tuple(oiio.TypeDesc(f) for f in formats)
    spec.x, spec.y = origin
    if full:
        spec.full_x, spec.full_y, spec.full_width, spec.full_height = full
    for k, v in (attrs or {}).items():
        spec.attribute(k, v)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), oiio.geterror()
    assert out.write_image(np.ascontiguousarray(pixels, dtype=np.float32))
    out.close()


def read_image(path):
    inp = oiio.ImageInput.open(str(path))
    spec = oiio.ImageSpec(inp.spec())
    pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    return spec, np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels)


def test_float_rgb_pixels_equal_numpy(tmp_path, solution_dir):
    rng = np.random.default_rng(1)
    rgb = rng.uniform(-0.1, 4.0, size=(24, 40, 3))
    write_image(tmp_path / "in.exr", rgb, "RGB")
    out = tmp_path / "out"
    rc = main(
        [
            "apply",
            str(solution_dir),
            str(tmp_path / "in.exr"),
            "--out",
            str(out),
            "--no-progress",
            "--workers",
            "1",
        ]
    )
    assert rc == 0
    _, got = read_image(out / "in.exr")
    expected = rgb.astype(np.float32).astype(np.float64) @ _Q(solution_dir).T
    np.testing.assert_allclose(got, expected, atol=1e-5, rtol=1e-5)


def test_half_rgba_depth_aovs_metadata_window_pass_through(tmp_path, solution_dir):
    rng = np.random.default_rng(2)
    h, w = 20, 30
    names = ("R", "G", "B", "A", "Z", "diffuse.R", "diffuse.G", "diffuse.B")
    pixels = rng.uniform(0.0, 2.0, size=(h, w, len(names)))
    pixels[..., 4] = rng.uniform(1.0, 1000.0, size=(h, w))  # depth in float
    pixels[0, 0, :3] = [np.inf, 1.0, 0.5]  # alpha must survive an infinite pixel
    formats = ("half", "half", "half", "half", "float", "half", "half", "half")
    attrs = {"compression": "piz", "Owner": "stage-a unit", "ocio_vp_test:take": "T042"}
    src = tmp_path / "plate.exr"
    write_image(
        src,
        pixels,
        names,
        fmt="half",
        formats=formats,
        attrs=attrs,
        origin=(7, 3),
        full=(0, 0, 64, 48),
    )
    in_spec, original = read_image(src)
    out = tmp_path / "out"
    assert (
        main(
            [
                "apply",
                str(solution_dir),
                str(src),
                "--out",
                str(out),
                "--no-progress",
                "--workers",
                "1",
            ]
        )
        == 0
    )
    spec, got = read_image(out / "plate.exr")
    # Other channels: bitwise identical to the input as stored (half/float).
    np.testing.assert_array_equal(got[..., 3:], original[..., 3:])
    # RGB: numpy maths on the stored half values, rounded to half as the file stores it.
    with np.errstate(invalid="ignore", over="ignore"):  # the infinite pixel gives inf - inf
        expected = (original[..., :3].astype(np.float64) @ _Q(solution_dir).T).astype(np.float16)
    finite = np.isfinite(expected).all(axis=-1)
    np.testing.assert_allclose(got[..., :3][finite], expected[finite], rtol=2**-10, atol=1e-6)
    assert tuple(spec.channelnames) == names
    assert [str(t) for t in spec.channelformats] == list(formats)
    assert (spec.x, spec.y, spec.width, spec.height) == (7, 3, w, h)
    assert (spec.full_x, spec.full_y, spec.full_width, spec.full_height) == (0, 0, 64, 48)
    assert spec.get_string_attribute("compression") == in_spec.get_string_attribute("compression")
    assert spec.get_string_attribute("compression") == "piz"
    assert spec.get_string_attribute("Owner") == "stage-a unit"
    assert spec.get_string_attribute("ocio_vp_test:take") == "T042"


def test_second_subimage_without_rgb_passes_through(tmp_path, solution_dir):
    src = tmp_path / "multi.exr"
    rgb = np.full((8, 8, 3), 0.5, dtype=np.float32)
    depth = np.arange(64, dtype=np.float32).reshape(8, 8, 1)
    specs = [oiio.ImageSpec(8, 8, 3, "float"), oiio.ImageSpec(8, 8, 1, "float")]
    specs[0].attribute("name", "beauty")
    specs[1].channelnames = ("Z",)
    specs[1].attribute("name", "depth")
    out = oiio.ImageOutput.create(str(src))
    assert out.open(str(src), specs)
    assert out.write_image(rgb)
    assert out.open(str(src), specs[1], "AppendSubimage")
    assert out.write_image(depth)
    out.close()
    dst_dir = tmp_path / "out"
    assert (
        main(
            [
                "apply",
                str(solution_dir),
                str(src),
                "--out",
                str(dst_dir),
                "--no-progress",
                "--workers",
                "1",
            ]
        )
        == 0
    )
    inp = oiio.ImageInput.open(str(dst_dir / "multi.exr"))
    beauty = inp.read_image(0, 0, 0, 3, oiio.FLOAT)
    z = inp.read_image(1, 0, 0, 1, oiio.FLOAT)
    inp.close()
    np.testing.assert_allclose(
        beauty.reshape(8, 8, 3)[0, 0], _Q(solution_dir) @ np.full(3, 0.5), atol=1e-5
    )
    np.testing.assert_array_equal(np.asarray(z).reshape(8, 8, 1), depth)


def test_corrupt_frame_in_sequence_is_reported_and_others_done(tmp_path, solution_dir, capsys):
    seq = tmp_path / "seq"
    seq.mkdir()
    for f in range(1001, 1006):
        write_image(seq / f"plate.{f:04d}.exr", np.full((16, 16, 3), f / 1000.0), "RGB")
    good = (seq / "plate.1003.exr").read_bytes()
    (seq / "plate.1003.exr").write_bytes(good[: len(good) // 2])  # truncated mid-pixels
    out = tmp_path / "out"
    args = [
        "apply",
        str(solution_dir),
        str(seq / "plate.####.exr"),
        "--out",
        str(out),
        "--no-progress",
        "--workers",
        "1",
    ]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "plate.1003.exr" in err and "plate.1001.exr" not in err
    written = sorted(p.name for p in out.iterdir())
    assert written == [f"plate.{f}.exr" for f in (1001, 1002, 1004, 1005)]  # no partials left
    _, px = read_image(out / "plate.1005.exr")
    np.testing.assert_allclose(px[3, 3], _Q(solution_dir) @ np.full(3, 1.005), atol=1e-5)
    # Resume: the four good frames are skipped; the fixed frame is now done.
    (seq / "plate.1003.exr").write_bytes(good)
    before = (out / "plate.1001.exr").stat().st_mtime_ns
    assert main(args) == 0
    assert "4 already done" in capsys.readouterr().out
    assert (out / "plate.1001.exr").stat().st_mtime_ns == before
    assert (out / "plate.1003.exr").is_file()


def test_frame_range_reports_missing_frames(tmp_path, solution_dir, capsys):
    for f in (1, 2, 4):
        write_image(tmp_path / f"shot_{f:03d}.exr", np.ones((4, 4, 3)), "RGB")
    rc = main(
        [
            "apply",
            str(solution_dir),
            str(tmp_path / "shot_%03d.exr"),
            "--frames",
            "1-4",
            "--out",
            str(tmp_path / "o"),
            "--no-progress",
            "--workers",
            "1",
        ]
    )
    assert rc == 2
    assert "shot_003.exr: no such frame" in capsys.readouterr().err
    assert len(list((tmp_path / "o").iterdir())) == 3


def test_bad_solution_dir_is_an_input_error(tmp_path, capsys):
    assert main(["apply", str(tmp_path), "x.exr", "--out", str(tmp_path / "o")]) == 2
    assert "solution.json" in capsys.readouterr().err


class TestApplyInPlace:
    def test_threads_and_channel_order_match_numpy(self, solution_dir):
        cpu = cpu_processor(load_post_correction(solution_dir))
        Q = _Q(solution_dir)
        rng = np.random.default_rng(3)
        img = rng.uniform(0, 1, size=(37, 11, 5)).astype(np.float32)
        ref = img.copy()
        apply_in_place(cpu, img, rgb=(4, 2, 0), threads=3)
        expected = ref[..., [4, 2, 0]].astype(np.float64) @ Q.T
        np.testing.assert_allclose(img[..., [4, 2, 0]], expected, atol=1e-5)
        np.testing.assert_array_equal(img[..., [1, 3]], ref[..., [1, 3]])

    def test_rejects_non_float32(self, solution_dir):
        cpu = cpu_processor(load_post_correction(solution_dir))
        with pytest.raises(ValueError, match="float32"):
            apply_in_place(cpu, np.zeros((2, 2, 3)))

    def test_half_in_place_equals_float32_then_rounded_to_half(self, solution_dir):
        # OCIO's own half path against the float32 path rounded to half by numpy's cast
        # (round to nearest even): bitwise the same, including an RGBA layout and 2 threads.
        pc = load_post_correction(solution_dir)
        rng = np.random.default_rng(4)
        half = rng.uniform(-0.05, 60000.0 / 3, size=(29, 13, 4)).astype(np.float16)
        half[0, 0, :3] = [6.1e-5, 3e-8, 65504.0]  # smallest normal, a subnormal, the largest
        expected = half[..., :3].astype(np.float32)
        apply_in_place(cpu_processor(pc), expected, threads=1)
        with np.errstate(over="ignore"):
            expected = expected.astype(np.float16)
        got = half.copy()
        apply_in_place(pixel_transform(pc), got, rgb=(0, 1, 2), threads=2)
        np.testing.assert_array_equal(got[..., :3].view(np.uint16), expected.view(np.uint16))
        np.testing.assert_array_equal(got[..., 3], half[..., 3])


def test_half_frame_stays_half_and_matches_numpy(tmp_path, solution_dir):
    rng = np.random.default_rng(5)
    rgb = rng.uniform(0.0, 8.0, size=(40, 24, 3)).astype(np.float16)
    src = tmp_path / "in.exr"
    write_image(src, rgb.astype(np.float32), "RGB", fmt="half", attrs={"compression": "zip"})
    apply_file(src, tmp_path / "out.exr", load_post_correction(solution_dir), threads=2)
    spec, got = read_image(tmp_path / "out.exr")
    assert str(spec.format) == "half" and not spec.channelformats
    assert spec.get_string_attribute("compression") == "zip"
    # numpy's float64 maths on the stored half values, rounded to half: at most one half ulp
    # apart (float32 arithmetic may round the other way at a tie).
    expected = (rgb.astype(np.float64) @ _Q(solution_dir).T).astype(np.float16)
    ulp = np.spacing(np.abs(expected)).astype(np.float64)
    assert np.max(np.abs(got - expected.astype(np.float64)) / ulp) <= 1.0


def test_pipeline_keeps_order_skips_failures_and_frames(tmp_path, solution_dir):
    pc = load_post_correction(solution_dir)
    frames = []
    for i in range(5):
        frames.append(tmp_path / f"p.{i}.exr")
        write_image(frames[-1], np.full((9, 7, 3), 0.1 * (i + 1)), "RGB")
    frames[2].write_bytes(b"not an image")
    out = tmp_path / "out"
    out.mkdir()
    (out / "p.3.exr").write_bytes(b"already there")
    tasks = [FrameTask(str(f), str(out / f.name), pc) for f in frames]
    results = dict(apply_frames(tasks, threads=2))
    assert sorted(results) == [0, 1, 2, 3, 4]
    # p.3's output exists but ocio-vp did not write it: neither replaced nor counted as done
    assert [results[i].status for i in range(5)] == [
        "done",
        "done",
        "input-error",
        "input-error",
        "done",
    ]
    assert "p.2.exr" in results[2].message
    assert "p.3.exr" in results[3].message and "not written by ocio-vp" in results[3].message
    assert (out / "p.3.exr").read_bytes() == b"already there"
    assert sorted(p.name for p in out.iterdir()) == ["p.0.exr", "p.1.exr", "p.3.exr", "p.4.exr"]
    # A rerun skips the frames ocio-vp wrote; --overwrite redoes them but still not the foreign one
    again = dict(apply_frames(tasks, threads=2))
    assert [again[i].status for i in range(5)] == [
        "skipped",
        "skipped",
        "input-error",
        "input-error",
        "skipped",
    ]
    forced = [dataclasses.replace(t, overwrite=True) for t in tasks]
    forced_results = dict(apply_frames(forced, threads=2))
    assert [forced_results[i].status for i in (0, 1, 3, 4)] == [
        "done",
        "done",
        "input-error",
        "done",
    ]
    assert (out / "p.3.exr").read_bytes() == b"already there"
    _, px = read_image(out / "p.4.exr")
    np.testing.assert_allclose(px[4, 3], _Q(solution_dir) @ np.full(3, 0.5), atol=1e-5)


def test_pipeline_holds_a_bounded_number_of_frames(tmp_path, solution_dir, monkeypatch):
    # Slow writes pile up behind a fast reader: the stream still holds at most HELD frames (one
    # read, one transformed, WRITERS being written) and writes at most WRITERS at once.
    import threading
    import time

    lock = threading.Lock()
    live = {"frames": 0, "writes": 0, "max_frames": 0, "max_writes": 0}

    def count(key, step):
        with lock:
            live[key] += step
            live[f"max_{key}"] = max(live[f"max_{key}"], live[key])

    from ocio_vp.footage import apply as frame_io  # where the stream's tasks read and write

    real_load, real_store = frame_io.load_frame, frame_io.store_frame

    def load(src):
        parts = real_load(src)
        count("frames", 1)
        return parts

    def store(dst, parts):
        count("writes", 1)
        # long beside reading and transforming a 4x5 frame (~1 ms), even on a loaded machine
        time.sleep(0.2)
        try:
            real_store(dst, parts)
        finally:
            count("writes", -1)
            count("frames", -1)

    monkeypatch.setattr(frame_io, "load_frame", load)
    monkeypatch.setattr(frame_io, "store_frame", store)
    pc = load_post_correction(solution_dir)
    tasks = []
    for i in range(8):
        write_image(tmp_path / f"p.{i}.exr", np.full((4, 5, 3), 0.1), "RGB")
        tasks.append(
            FrameTask(str(tmp_path / f"p.{i}.exr"), str(tmp_path / "out" / f"p.{i}.exr"), pc)
        )
    results = list(apply_frames(tasks, threads=1))
    assert [i for i, _ in results] == list(range(8))
    assert all(r.status == "done" for _, r in results)
    assert live["frames"] == 0 and live["writes"] == 0
    assert live["max_frames"] == stream.HELD == 2 + stream.WRITERS
    assert live["max_writes"] == stream.WRITERS


def test_pixel_transform_is_pluggable(tmp_path, solution_dir, monkeypatch):
    # A post-correction of another kind runs its own transform (here: doubling, in numpy).
    def doubling(pc):
        def transform(rgb):
            rgb *= 2

        return transform

    monkeypatch.setitem(TRANSFORMS, "double", doubling)
    pc = load_post_correction(solution_dir)
    pc = type(pc)(pc.config, pc.source, pc.target, pc.environment, kind="double")
    write_image(tmp_path / "in.exr", np.full((6, 5, 3), 0.25), "RGB")
    apply_file(tmp_path / "in.exr", tmp_path / "out.exr", pc)
    _, got = read_image(tmp_path / "out.exr")
    np.testing.assert_array_equal(got, np.full((6, 5, 3), 0.5))


@pytest.fixture(scope="module")
def rp_solution_dir(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("solve_rp")
    path = root / "stage.yaml"
    path.write_text(yaml.safe_dump(make_measurements_dict(environments=1)))
    args = ["solve", str(path), "--out", str(root / "calib"), "--method", "root-polynomial"]
    assert main(args) == 0
    return root / "calib" / "env_0"


def _finlayson(solution_dir: Path, rgb: np.ndarray) -> np.ndarray:
    """The solution's post_correction block (a bounded root-polynomial) applied by the tests'
    independent implementation (colour-science's expansion, the gauge by bisection), float64."""
    block = json.loads((solution_dir / "solution.json").read_text())["post_correction"]
    return oracle_correction(block, np.asarray(rgb, dtype=np.float64))


def _extremes(rng) -> np.ndarray:
    rgb = rng.uniform(-0.5, 8.0, size=(20, 33, 3))
    rgb[0, :4] = 0.0
    rgb[1, :4] = 1e-8
    rgb[2, :4] = 1e4
    rgb[3, :4] = [[-1e-8, 1e-8, 0.0], [1e-8, -1e-8, 1e-8], [-1.0, -1.0, -1.0], [0.0, 1e4, -1e-8]]
    return rgb


def test_root_polynomial_apply_is_the_exact_model(tmp_path, rp_solution_dir):
    """``apply`` with a root-polynomial solution runs the model itself (not the config's LUT):
    the independent implementation of its post_correction block on the float32 pixels, to the
    float32 output's rounding, including zeros, negatives around black, 1e-8 and 1e4."""
    pc = load_post_correction(rp_solution_dir)
    assert pc.kind == "model" and json.loads(pc.model)["kind"] == "root-polynomial"
    rgb = _extremes(np.random.default_rng(12))
    write_image(tmp_path / "in.exr", rgb, "RGB")
    apply_file(tmp_path / "in.exr", tmp_path / "out.exr", pc, threads=2)
    spec, got = read_image(tmp_path / "out.exr")
    ref = _finlayson(rp_solution_dir, rgb.astype(np.float32))
    assert np.all(np.isfinite(got))
    scale = np.abs(ref).max(axis=-1, keepdims=True)
    assert np.all(np.abs(got - ref) <= 2.0**-23 * scale)
    assert np.array_equal(got[0, :4], np.zeros((4, 3)))  # black stays black
    assert "model applied exactly" in spec.get_string_attribute("ocio_vp:postCorrection")


def test_root_polynomial_apply_half_and_continuity_around_black(rp_solution_dir):
    """Half buffers (computed in float32): the float64 result rounded to half, except at most
    one half step where it lies within float32's error of a rounding midpoint (rare). Around
    black the result is continuous through zero (sign-preserving roots), never NaN."""
    transform = pixel_transform(load_post_correction(rp_solution_dir))
    rgb = _extremes(np.random.default_rng(13))
    rgb[rgb > 1e3] = 1e3  # keep the corrected values inside half's range (65504)
    rgb = rgb.astype(np.float16)
    exact = _finlayson(rp_solution_dir, rgb)
    ref = exact.astype(np.float16)

    def check(got):
        step = np.spacing(np.abs(ref)).astype(np.float64)  # one half step at each value
        off = got != ref
        assert np.all(np.abs(got.astype(np.float64) - ref) <= step)
        # where it differs, the exact value was a hair from the midpoint between the two
        midpoint = (got[off].astype(np.float64) + ref[off]) / 2
        assert np.all(np.abs(exact[off] - midpoint) <= 1e-6 * np.abs(exact[off]) + 1e-12)
        assert off.mean() < 0.01

    work = rgb.copy()
    apply_in_place(transform, work)
    check(work)
    rgba = np.concatenate([rgb, np.ones_like(rgb[..., :1])], axis=-1)
    transform(rgba[..., :3])  # a non-contiguous view (not what apply passes): still in place
    check(rgba[..., :3])
    assert np.all(rgba[..., 3] == 1)
    t = np.linspace(-1e-3, 1e-3, 2001, dtype=np.float32)
    ramp = np.ascontiguousarray(np.stack([t, 2e-3 + 0 * t, 1e-3 + 0 * t], -1)[None])
    out = ramp.copy()
    apply_in_place(transform, out)
    assert np.all(np.isfinite(out))
    # No jump at r = 0: the result is the (continuous) model to float32 rounding, and no step
    # between neighbouring ramp samples (1e-6 apart) exceeds 2 % of the ramp's output (a
    # discontinuity, e.g. a sign flip of a root, would jump by the size of the output itself).
    np.testing.assert_allclose(out[0], _finlayson(rp_solution_dir, ramp[0]), rtol=1e-6, atol=1e-12)
    assert np.abs(np.diff(out[0], axis=0)).max() <= 0.02 * np.abs(out).max()
