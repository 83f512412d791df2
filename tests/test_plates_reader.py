"""Reading plates by region with OpenImageIO: channels by name, tiles, formats, encodings."""

from __future__ import annotations

import numpy as np
import pytest

from ocio_vp.errors import InputError
from ocio_vp.plates.reader import open_plate, read_region
from ocio_vp.simulator.plates import write_plate


@pytest.fixture
def image() -> np.ndarray:
    rng = np.random.default_rng(5)
    return rng.uniform(0.0, 0.9, size=(120, 200, 3)).astype(np.float32)


def _oiio_full(path) -> np.ndarray:
    """Independent reference: OIIO's ImageBuf reads the whole image."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    names = list(buf.spec().channelnames)
    pixels = buf.get_pixels(oiio.FLOAT)
    return pixels[..., [names.index(c) for c in ("R", "G", "B")]]


class TestReadRegion:
    @pytest.mark.parametrize("tile", [0, 32])
    @pytest.mark.parametrize("channels", [("R", "G", "B"), ("A", "B", "G", "R", "Z")])
    def test_region_equals_full_read(self, tmp_path, image, tile, channels):
        path = write_plate(tmp_path / "p.exr", image, channels=channels, tile=tile)
        full = _oiio_full(path)
        box = (17, 9, 151, 103)
        np.testing.assert_array_equal(read_region(path, box), full[9:103, 17:151])

    @pytest.mark.parametrize(
        ("suffix", "dtype", "step"), [("tif", "uint16", 1 / 65535), ("dpx", "uint10", 1 / 1023)]
    )
    def test_integer_formats(self, tmp_path, image, suffix, dtype, step):
        path = write_plate(tmp_path / f"p.{suffix}", image, dtype=dtype)
        info = open_plate(path)
        assert not info.is_float and info.encoding == "linear"
        np.testing.assert_allclose(read_region(path, (0, 0, 200, 120)), image, atol=step)

    def test_layers(self, tmp_path, image):
        path = write_plate(tmp_path / "l.exr", image, channels=("beauty.R", "beauty.G", "beauty.B"))
        np.testing.assert_array_equal(read_region(path, (0, 0, 10, 10)), _half(image[:10, :10]))
        two = write_plate(
            tmp_path / "two.exr", image, channels=("a.R", "a.G", "a.B", "b.R", "b.G", "b.B")
        )
        with pytest.raises(InputError, match="several RGB layers"):
            open_plate(two)
        assert open_plate(two, layer="b").rgb == (3, 4, 5)

    def test_srgb_png_needs_encoding(self, tmp_path):
        import colour

        codes = np.linspace(0, 1, 200 * 120 * 3).reshape(120, 200, 3)
        path = write_plate(tmp_path / "s.png", codes, dtype="uint8")
        with pytest.raises(InputError, match="display-referred"):
            open_plate(path)
        got = read_region(open_plate(path, encoding="srgb"), (0, 0, 200, 120))
        # Reference: colour-science's IEC 61966-2-1 EOTF on the 8-bit codes.
        want = colour.models.eotf_sRGB(np.round(codes * 255) / 255)
        np.testing.assert_allclose(got, want, atol=1e-6)

    def test_log_dpx_needs_encoding(self, tmp_path, image):
        import colour
        import OpenImageIO as oiio

        spec = oiio.ImageSpec(200, 120, 3, "uint16")
        spec.attribute("oiio:BitsPerSample", 10)
        spec.attribute("dpx:Transfer", "Printing density")
        out = oiio.ImageOutput.create(str(tmp_path / "log.dpx"))
        out.open(str(tmp_path / "log.dpx"), spec)
        out.write_image(image)
        out.close()
        with pytest.raises(InputError, match="log-encoded"):
            open_plate(tmp_path / "log.dpx")
        got = read_region(open_plate(tmp_path / "log.dpx", encoding="cineon"), (0, 0, 200, 120))
        codes = oiio.ImageBuf(str(tmp_path / "log.dpx")).get_pixels(oiio.FLOAT)  # code values
        # Reference: colour-science's Cineon decoding of the code values OIIO's ImageBuf reads.
        np.testing.assert_allclose(got, colour.models.log_decoding_Cineon(codes), rtol=1e-5)

    def test_errors(self, tmp_path, image):
        with pytest.raises(InputError, match="plate not found"):
            open_plate(tmp_path / "missing.exr")
        (tmp_path / "junk.exr").write_bytes(b"not an image at all")
        with pytest.raises(InputError, match="cannot read"):
            open_plate(tmp_path / "junk.exr")
        path = write_plate(tmp_path / "p.exr", image)
        with pytest.raises(InputError, match="outside the image"):
            read_region(path, (150, 0, 201, 10))
        with pytest.raises(InputError, match="unknown encoding"):
            open_plate(path, encoding="gama 2.4")


def _half(a: np.ndarray) -> np.ndarray:
    return a.astype(np.float16).astype(np.float32)


def test_a_take_frame_missing_or_unreadable_is_named_a_frame(tmp_path, image):
    from ocio_vp.plates.take_reader import read_frame_stats

    info = open_plate(write_plate(tmp_path / "A001.0001.exr", image))
    (tmp_path / "A001.0003.exr").write_bytes(b"not an image at all")
    box = (0, 0, info.width, info.height)
    with pytest.raises(InputError, match=r"A001\.0002\.exr: frame not found"):
        read_frame_stats([tmp_path / "A001.0002.exr"], info, box, [(0, 4)])
    with pytest.raises(InputError, match=r"A001\.0003\.exr: cannot read as an image"):
        read_frame_stats([tmp_path / "A001.0003.exr"], info, box, [(0, 4)])
