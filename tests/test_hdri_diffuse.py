"""w_avg from an equirectangular HDRI, checked against closed forms.

Closed forms used (radiometry of a Lambertian receiver, e.g. Howell's catalog / any radiative
transfer text):
- uniform sky of radiance L: (1/pi) * integral L cos+ dw = L;
- a spherical cap of half-angle a whose axis makes angle t <= pi/2 - a with the normal:
  integral cos dw = pi sin^2(a) cos(t), so w_avg = L sin^2(a) cos(t);
- the upper hemisphere lit, normal horizontal: w_avg = L / 2.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from exr_helpers import write_exr

from ocio_vp.errors import InputError
from ocio_vp.hdri.diffuse import (
    FRONT,
    diffuse_integral,
    equirect_directions,
    equirect_solid_angles,
    read_equirect,
    w_avg_from_hdri,
)

oiio = pytest.importorskip("OpenImageIO")


def cap_image(height, width, axis, half_angle, radiance, sky=0.0):
    """A lat-long image with a disc source; pixel fractions inside the cap by supersampling."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    s = 4  # supersample each pixel 4x4 so the edge is anti-aliased
    dirs = equirect_directions(height * s, width * s)
    inside = (dirs @ axis) >= np.cos(half_angle)
    frac = inside.reshape(height, s, width, s).mean(axis=(1, 3))
    img = np.empty((height, width, 3))
    img[:] = sky
    img += frac[..., None] * (np.asarray(radiance, float) - sky)
    return img


class TestSolidAngles:
    def test_sum_is_full_sphere(self):
        assert equirect_solid_angles(64, 128).sum() == pytest.approx(4 * np.pi, rel=1e-12)

    def test_row_matches_closed_form(self):
        # Row i spans theta in [i pi/H, (i+1) pi/H]: (2 pi/W)(cos t0 - cos t1).
        h, w = 8, 16
        omega = equirect_solid_angles(h, w)
        i = 3
        expected = 2 * np.pi / w * (np.cos(i * np.pi / h) - np.cos((i + 1) * np.pi / h))
        assert omega[i, 5] == pytest.approx(expected, rel=1e-12)

    def test_directions_are_unit_and_centre_is_front(self):
        d = equirect_directions(32, 64)
        np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
        # The image centre is between pixels 15/16 and 31/32; the average of those four is FRONT.
        centre = d[15:17, 31:33].mean(axis=(0, 1))
        np.testing.assert_allclose(centre / np.linalg.norm(centre), FRONT, atol=1e-12)
        assert d[0, 0, 1] > 0.99  # row 0 is the zenith (+y)


class TestDiffuseIntegral:
    @pytest.mark.parametrize("normal", [FRONT, (0, 1, 0), (1, -1, 0.3)])
    def test_uniform_sky_gives_its_radiance(self, normal):
        sky = np.ones((64, 128, 3)) * [0.5, 1.0, 2.0]
        np.testing.assert_allclose(diffuse_integral(sky, normal=normal), [0.5, 1.0, 2.0], rtol=2e-3)

    def test_upper_hemisphere_with_horizontal_normal_is_half(self):
        img = np.zeros((128, 256, 1))
        img[:64] = 3.0
        assert diffuse_integral(img, normal=(0, 1, 0))[0] == pytest.approx(3.0, rel=1e-3)
        assert diffuse_integral(img, normal=FRONT)[0] == pytest.approx(1.5, rel=1e-3)

    @pytest.mark.parametrize("tilt_deg", [0.0, 40.0, 70.0])
    def test_disc_source_is_cos_weighted_solid_angle(self, tilt_deg):
        a, t = np.radians(8.0), np.radians(tilt_deg)
        axis = (np.sin(t), 0.0, np.cos(t))  # tilted from FRONT towards +x
        img = cap_image(256, 512, axis, a, radiance=[100.0, 50.0, 10.0])
        expected = np.array([100.0, 50.0, 10.0]) * np.sin(a) ** 2 * np.cos(t)
        np.testing.assert_allclose(diffuse_integral(img), expected, rtol=5e-3)

    def test_source_behind_contributes_nothing(self):
        img = cap_image(128, 256, (0, 0, -1), np.radians(10), radiance=[5.0, 5.0, 5.0])
        np.testing.assert_allclose(diffuse_integral(img), 0.0, atol=1e-12)

    def test_bad_shape_and_normal(self):
        with pytest.raises(ValueError, match="shape"):
            diffuse_integral(np.ones((4, 8)))
        with pytest.raises(InputError, match="normal"):
            diffuse_integral(np.ones((4, 8, 3)), normal=(0, 0, 0))


class TestFromFile:
    def test_w_avg_from_file_at_full_and_reduced_width(self, tmp_path):
        a, t = np.radians(6.0), np.radians(30.0)
        img = cap_image(256, 512, (0.0, np.sin(t), np.cos(t)), a, [200.0, 180.0, 150.0], sky=0.25)
        path = tmp_path / "sun.exr"
        write_exr(path, img)
        # Sky (0.25 everywhere except the cap) + cap: closed form.
        cap = np.sin(a) ** 2 * np.cos(t)
        expected = 0.25 * (1 - cap) + np.array([200.0, 180.0, 150.0]) * cap
        np.testing.assert_allclose(w_avg_from_hdri(path, width=None), expected, rtol=5e-3)
        np.testing.assert_allclose(w_avg_from_hdri(path, width=128), expected, rtol=2e-2)
        assert read_equirect(path, width=128).shape == (64, 128, 3)

    def test_mip_level_is_used_and_alpha_ignored(self, tmp_path):
        img = np.concatenate([np.full((64, 128, 3), 0.75), np.zeros((64, 128, 1))], axis=-1)
        flat = tmp_path / "flat.exr"
        write_exr(flat, img)
        tex = tmp_path / "flat.tx.exr"
        buf = oiio.ImageBuf(str(flat))
        assert oiio.ImageBufAlgo.make_texture(oiio.MakeTxEnvLatl, buf, str(tex))
        small = read_equirect(tex, width=32)
        assert small.shape == (16, 32, 3)
        np.testing.assert_allclose(w_avg_from_hdri(tex, width=32), 0.75, rtol=1e-3)

    def test_errors_are_input_errors(self, tmp_path):
        with pytest.raises(InputError, match="no such HDRI"):
            w_avg_from_hdri(tmp_path / "missing.exr")
        square = tmp_path / "square.exr"
        write_exr(square, np.ones((32, 32, 3)))
        with pytest.raises(InputError, match="2:1"):
            w_avg_from_hdri(square)
        grey = tmp_path / "grey.exr"
        write_exr(grey, np.ones((32, 64, 1)))
        with pytest.raises(InputError, match="channel"):
            w_avg_from_hdri(grey)
        nan = np.ones((32, 64, 3))
        nan[3, 4, 1] = np.nan
        bad = tmp_path / "nan.exr"
        write_exr(bad, nan)
        with pytest.raises(InputError, match="NaN"):
            w_avg_from_hdri(bad)
        junk = tmp_path / "junk.exr"
        junk.write_bytes(b"not an exr at all")
        with pytest.raises(InputError, match="cannot read"):
            w_avg_from_hdri(junk)


class TestSolveOption:
    def test_hdri_sets_w_avg_of_its_environment_only(self, tmp_path, capsys):
        import json

        import yaml
        from conftest import make_measurements_dict

        from ocio_vp.cli import main

        doc = make_measurements_dict(environments=2)
        stage = tmp_path / "stage.yaml"
        stage.write_text(yaml.safe_dump(doc))
        hdri = tmp_path / "sky.exr"
        write_exr(hdri, np.ones((64, 128, 3)) * [0.7, 0.8, 0.9])  # uniform: w_avg = radiance
        out = tmp_path / "calib"
        assert main(["solve", str(stage), "--out", str(out), "--hdri", f"env_0={hdri}"]) == 0
        assert "env_0: w_avg from" in capsys.readouterr().out
        w0 = json.loads((out / "env_0" / "solution.json").read_text())["w_avg"]
        w1 = json.loads((out / "env_1" / "solution.json").read_text())["w_avg"]
        np.testing.assert_allclose(w0, [0.7, 0.8, 0.9], rtol=2e-3)
        # env_1 keeps the paper's white patch / 0.9 estimate.
        np.testing.assert_allclose(w1, np.asarray(doc["environments"][1]["target_chart"][18]) / 0.9)

    def test_hdri_option_errors(self, tmp_path, capsys):
        import yaml
        from conftest import make_measurements_dict

        from ocio_vp.cli import main

        stage = tmp_path / "stage.yaml"
        stage.write_text(yaml.safe_dump(make_measurements_dict(environments=2)))
        hdri = tmp_path / "sky.exr"
        write_exr(hdri, np.ones((16, 32, 3)))
        base = ["solve", str(stage), "--out", str(tmp_path / "o")]
        assert main([*base, "--hdri", str(hdri)]) == 2
        assert "ENV=FILE" in capsys.readouterr().err
        assert main([*base, "--hdri", f"nowhere={hdri}"]) == 2
        assert "nowhere" in capsys.readouterr().err
        assert main([*base, "--environment", "env_1", "--hdri", str(hdri)]) == 0
        assert not (tmp_path / "o" / "env_0").exists()


def _band(e0: float, e1: float) -> float:
    """Closed form: (1/pi) integral of max(0, n.w) over the elevation band [e0, e1] (radians)
    of a unit-radiance sky, all azimuths, n horizontal: (2/pi) [e/2 + sin(2e)/4]."""
    f = lambda e: e / 2 + np.sin(2 * e) / 4  # noqa: E731
    return 2.0 / np.pi * (f(e1) - f(e0))


class TestPanelRegions:
    """Each panel type's part of w_avg: the diffuse integral over its directions only."""

    def test_bands_of_a_two_colour_sky_match_the_closed_form(self):
        from ocio_vp.formats.panels import PanelRegion, PanelType
        from ocio_vp.hdri.diffuse import panel_w_avg

        height, width = 360, 720  # half a degree per row: 40 degrees is a row edge
        sky, ground = np.array([0.3, 0.5, 0.9]), np.array([0.6, 0.5, 0.3])
        elevation = 90.0 - (np.arange(height) + 0.5) * 180.0 / height
        image = np.where((elevation >= 40.0)[:, None, None], sky, ground) * np.ones((1, width, 3))
        dummy = np.eye(3)
        panels = [
            PanelType("wall", True, dummy, dummy[None], beta=0.2,
                      regions=(PanelRegion(elevation=(-90.0, 40.0)),)),
            PanelType("ceiling", False, dummy, dummy[None], beta=0.2,
                      regions=(PanelRegion(elevation=(40.0, 90.0)),)),
        ]  # fmt: skip
        parts, uncovered = panel_w_avg(image, panels)
        top = _band(np.radians(40.0), np.pi / 2)
        np.testing.assert_allclose(parts["ceiling"], top * sky, rtol=2e-3)
        np.testing.assert_allclose(parts["wall"], (1 - top) * ground, rtol=2e-3)
        assert uncovered < 1e-12
        # A wall in front only (azimuth -90..90): what lies behind the chart gives it no light.
        front = dataclasses.replace(
            panels[0], regions=(PanelRegion(elevation=(-90.0, 40.0), azimuth=(-90.0, 90.0)),)
        )
        parts, _ = panel_w_avg(image, [front, panels[1]])
        np.testing.assert_allclose(parts["wall"], (1 - top) * ground, rtol=2e-3)
        # A wall above the horizon only: the light from below is named as no type's.
        high = dataclasses.replace(panels[0], regions=(PanelRegion(elevation=(0.0, 40.0)),))
        parts, uncovered = panel_w_avg(image, [high, panels[1]])
        below = 0.5 * ground[1]  # the lower hemisphere's band: (2/pi) (pi/4) = 1/2
        assert uncovered == pytest.approx(below / (top * sky[1] + (1 - top) * ground[1]), rel=3e-3)

    def test_solve_takes_each_types_w_avg_from_the_hdri(self, tmp_path, capsys):
        import json

        import yaml
        from conftest import panel_stage_measurements

        from ocio_vp.cli import main
        from ocio_vp.formats.measurements import measurements_to_dict

        _, m = panel_stage_measurements(("overcast",))
        document = measurements_to_dict(m)
        del document["environments"][0]["w_avg"]
        stage = tmp_path / "stage.yaml"
        stage.write_text(yaml.safe_dump(document))
        height = 90  # two degrees per row: 40 degrees is a row edge
        elevation = 90.0 - (np.arange(height) + 0.5) * 180.0 / height
        sky = np.where((elevation >= 40.0)[:, None, None], 0.8, 0.4) * np.ones((1, 180, 3))
        hdri = tmp_path / "sky.exr"
        write_exr(hdri, sky)
        out = tmp_path / "calib"
        assert main(["solve", str(stage), "--out", str(out), "--hdri", f"overcast={hdri}"]) == 0
        assert "overcast: w_avg per panel type from" in capsys.readouterr().out
        panels = json.loads((out / "overcast" / "solution.json").read_text())["panels"]
        top = _band(np.radians(40.0), np.pi / 2)
        np.testing.assert_allclose(panels["ceiling"]["w_avg"], 0.8 * top, rtol=2e-3)
        np.testing.assert_allclose(panels["wall"]["w_avg"], 0.4 * (1 - top), rtol=2e-3)

    def test_a_panel_type_without_region_is_refused_in_one_line(self, tmp_path, capsys):
        import yaml
        from conftest import panel_stage_measurements

        from ocio_vp.cli import main
        from ocio_vp.formats.measurements import measurements_to_dict

        _, m = panel_stage_measurements(("overcast",))
        document = measurements_to_dict(m)
        del document["panels"][1]["region"]
        stage = tmp_path / "stage.yaml"
        stage.write_text(yaml.safe_dump(document))
        hdri = tmp_path / "sky.exr"
        write_exr(hdri, np.ones((16, 32, 3)))
        assert main(["solve", str(stage), "--out", str(tmp_path / "o"), "--hdri", str(hdri)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "panels[1].region: no region" in err


def test_a_map_black_in_front_is_refused_naming_it(tmp_path):
    # A sun straight behind the chart (-z): cos+ is 0 over the back hemisphere, so w_avg is 0
    # exactly; the solve used to fail later with "lit_chart: ... black", naming the
    # measurements instead of the map.
    behind = cap_image(32, 64, (0.0, 0.0, -1.0), np.radians(10.0), radiance=1e4)
    assert diffuse_integral(behind) == pytest.approx(np.zeros(3), abs=1e-12)
    path = tmp_path / "behind.exr"
    write_exr(path, behind.astype(np.float32))
    with pytest.raises(InputError) as caught:
        w_avg_from_hdri(path, width=None)
    assert caught.value.source == str(path) and "frontal hemisphere" in caught.value.problem
    write_exr(path, cap_image(32, 64, FRONT, np.radians(10.0), radiance=1e4).astype(np.float32))
    assert np.all(w_avg_from_hdri(path, width=None) > 0)
