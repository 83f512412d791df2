"""``ocio-vp measure``: synthetic plates of a simulated stage -> measurements -> same solve."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from ocio_vp.cli import main
from ocio_vp.formats.measurements import load_measurements, measurements_from_dict
from ocio_vp.pipeline import solve_environment
from ocio_vp.plates.capture import capture_from_dict, load_capture
from ocio_vp.plates.measure import measure_capture
from ocio_vp.simulator.plates import (
    CHART_CORNERS,
    PLATE_SIZE,
    render_chart,
    render_regions,
    write_plate,
)

#: A frame the size of the simulator's other plates (rows, columns, RGB), for plates whose
#: content does not matter (refused for their channels or bit depth whatever they show).
FRAME = (PLATE_SIZE[1], PLATE_SIZE[0], 3)

NOISE, READ_NOISE = 0.01, 1e-4
# 10 % fall-off at the frame's corners, removed with a flat field (4 frames of a white target).
VIGNETTING = 0.1
REGIONS = {"red": (40, 30, 160, 110), "green": (240, 30, 360, 110), "blue": (440, 30, 560, 110)}
ENVIRONMENTS = ["incandescent", "outdoor_shade"]


@pytest.fixture(scope="module")
def truth():
    """The spectral simulator's exact measurements (the paper-like stage, two environments)."""
    from ocio_vp.simulator.stage import paper_stage, simulate_measurements

    return simulate_measurements(ENVIRONMENTS, stage=paper_stage())


def write_capture(folder: Path, truth, *, seed: int = 0) -> Path:
    """Render every plate of a capture (perspective, noise, a glint on one patch) + the file."""
    folder.mkdir(parents=True, exist_ok=True)
    noise = {"noise": NOISE, "read_noise": READ_NOISE, "vignetting": VIGNETTING}
    white = {"all": ((0, 0, 600, 400), np.array([0.5, 0.5, 0.5]))}
    flats = []
    for i in range(4):
        flat = render_regions(white, vignetting=VIGNETTING, noise=0.003, seed=seed + 90 + i)
        flats.append(f"plates/{write_plate(folder / f'flat.{i}.exr', flat).name}")
    primaries = {c: (REGIONS[c], truth.SL[:, k]) for k, c in enumerate(REGIONS)}
    write_plate(folder / "primaries.exr", render_regions(primaries, seed=seed, **noise))
    lit = {}
    for k, c in enumerate(("red", "green", "blue")):
        image = render_chart(truth.SRL[:, :, k], highlight=11, seed=seed + 1 + k, **noise)
        # One lit plate as 16-bit TIFF, the others half-float EXR with extra channels.
        if c == "green":
            name = write_plate(folder / "lit_green.tif", image, dtype="uint16").name
        else:
            name = write_plate(
                folder / f"lit_{c}.exr", image, channels=("A", "B", "G", "R", "Z")
            ).name
        lit[c] = {"plate": f"plates/{name}", "corners": CHART_CORNERS.tolist()}
    environments = []
    for i, env in enumerate(truth.environments):
        image = render_chart(env.target_chart, seed=seed + 10 + i, **noise)
        write_plate(folder / f"{env.name}.exr", image, dtype="float")
        black = render_regions(
            {"b": ((200, 150, 400, 250), env.black_level)}, seed=seed + 20 + i, **noise
        )
        write_plate(folder / f"{env.name}_black.exr", black, dtype="float")
        environments.append(
            {
                "name": env.name,
                "target_chart": {
                    "plate": f"plates/{env.name}.exr",
                    "corners": CHART_CORNERS.tolist(),
                },
                "black_level": {
                    "plate": f"plates/{env.name}_black.exr",
                    "region": [200, 150, 400, 250],
                },
                "w_avg": env.w_avg.tolist(),
            }
        )
    document = {
        "format": "ocio-vp/capture",
        "version": 1,
        "stage": {
            "name": "synthetic-stage",
            "calibration_panel": {"width": 1.0, "height": 1.0, "distance": 1.0},
            "white_patch": 18,
        },
        "chart": {"rows": 4, "columns": 6, "inset": 0.25},
        "flat_field": flats,
        "primaries": {"plate": "plates/primaries.exr", **{c: list(r) for c, r in REGIONS.items()}},
        "lit_chart": lit,
        "environments": environments,
    }
    path = folder.parent / "capture.yaml"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


@pytest.fixture(scope="module")
def capture_file(tmp_path_factory, truth) -> Path:
    return write_capture(tmp_path_factory.mktemp("stage") / "plates", truth)


def _solve_all(measurements):
    return {
        env.name: solve_environment(measurements, env, method="least-squares")
        for env in measurements.environments
    }


def _deviation_in_sigmas(result, truth, n_draws: int = 200) -> dict[str, np.ndarray]:
    """(measured - exact) / sigma for M, Q, N of each environment (27 numbers each).

    sigma: each measured value has a standard error spread / sqrt(pixels) (estimated from the
    plates themselves, flat-field noise included). ``n_draws`` Monte-Carlo draws of the exact
    measurements perturbed by those errors give the spread of M, Q, N (plus 1e-12 for elements
    that do not vary).
    """
    from ocio_vp.formats.measurements import measurements_to_dict

    se = {
        p.plate.key: p.samples.spreads / np.sqrt(p.samples.counts)[:, None] for p in result.plates
    }
    se_SL = np.stack([se["primaries"][k] for k in range(3)], axis=1)
    se_SRL = np.stack([se[f"lit_chart.{c}"] for c in ("red", "green", "blue")], axis=2)

    def flat(solutions):
        return {
            n: np.concatenate([s.M.ravel(), s.Q.ravel(), s.N.ravel()]) for n, s in solutions.items()
        }

    exact = flat(_solve_all(truth))
    measured = flat(_solve_all(result.measurements))
    rng = np.random.default_rng(1)
    draws: dict[str, list[np.ndarray]] = {name: [] for name in exact}
    base = measurements_to_dict(truth)
    for _ in range(n_draws):
        doc = json.loads(json.dumps(base))
        doc["primaries"] = {
            c: (truth.SL[:, k] + se_SL[:, k] * rng.standard_normal(3)).tolist()
            for k, c in enumerate(("red", "green", "blue"))
        }
        SRL = truth.SRL + se_SRL * rng.standard_normal(truth.SRL.shape)
        doc["lit_chart"] = {
            c: SRL[:, :, k].tolist() for k, c in enumerate(("red", "green", "blue"))
        }
        for i, env in enumerate(truth.environments):
            s = se[f"environments[{i}].target_chart"]
            b = se[f"environments[{i}].black_level"][0]
            doc["environments"][i]["target_chart"] = (
                env.target_chart + s * rng.standard_normal(s.shape)
            ).tolist()
            doc["environments"][i]["black_level"] = (
                env.black_level + b * rng.standard_normal(3)
            ).tolist()
        for name, values in flat(_solve_all(measurements_from_dict(doc))).items():
            draws[name].append(values)
    return {
        name: (measured[name] - exact[name]) / (np.std(draws[name], axis=0) + 1e-12)
        for name in exact
    }


class TestMeasureCommand:
    def test_writes_measurements_and_overlays(self, tmp_path, capture_file, truth, capsys):
        out = tmp_path / "stage.yaml"
        assert main(["measure", str(capture_file), "--out", str(out)]) == 0
        measured = load_measurements(out)
        # The glint patch (11) is reported on each lit plate; nothing else.
        printed = capsys.readouterr().out
        assert printed.count("warning:") == 3 and printed.count("patch 11: clipped") == 3
        np.testing.assert_allclose(measured.SL, truth.SL, rtol=0.005)
        white = truth.SRL.max(axis=(0, 1))  # the brightest value on each lit plate
        assert np.max(np.abs(measured.SRL - truth.SRL) / white) < 0.005
        for got, want in zip(measured.environments, truth.environments, strict=True):
            assert got.name == want.name
            scale = want.target_chart.max()
            assert np.max(np.abs(got.target_chart - want.target_chart) / scale) < 0.005
            np.testing.assert_allclose(got.black_level, want.black_level, rtol=0.005)
        folder = tmp_path / "stage.overlays"
        # Plate paths relative to the overlay folder: no absolute path in any output.
        assert str(capture_file.parent) not in (folder / "samples.json").read_text()
        names = sorted(p.name for p in folder.iterdir())
        assert names == sorted(
            [
                "primaries.png",
                "lit_red.png",
                "lit_green.png",
                "lit_blue.png",
                "samples.json",
                ".ocio-vp-output",  # the marker that lets a later run replace the folder
                *(f"{e}_target.png" for e in ENVIRONMENTS),
                *(f"{e}_black.png" for e in ENVIRONMENTS),
            ]
        )
        samples = json.loads((folder / "samples.json").read_text())
        lit_red = next(p for p in samples["plates"] if p["key"] == "lit_chart.red")
        assert lit_red["samples"][11]["flags"] and not lit_red["samples"][10]["flags"]

    def test_overlay_marks_the_sampled_pixels(self, tmp_path, capture_file):
        """The overlay outlines exactly the label map of the sampling (read back with OIIO)."""
        import OpenImageIO as oiio

        from ocio_vp.plates.overlay import OUTLINE_COLOURS
        from ocio_vp.plates.sampling import patch_labels

        out = tmp_path / "m.yaml"
        assert main(["measure", str(capture_file), "--out", str(out)]) == 0
        samples = json.loads((tmp_path / "m.overlays" / "samples.json").read_text())
        entry = next(p for p in samples["plates"] if p["key"] == "lit_chart.blue")
        png = oiio.ImageBuf(str(tmp_path / "m.overlays" / "lit_blue.png")).get_pixels(oiio.UINT8)
        x0, y0 = entry["box"][0] - 16, entry["box"][1] - 16  # the overlay's margin
        box = (x0, y0, x0 + png.shape[1], y0 + png.shape[0])
        labels = patch_labels(np.array(entry["corners"]), 4, 6, inset=0.25, box=box)
        green = np.all(png == OUTLINE_COLOURS["ok"], axis=-1)
        yellow = np.all(png == OUTLINE_COLOURS["clipped"], axis=-1)
        assert np.all(labels[green | yellow] >= 0)  # outlines only on sampled pixels
        assert set(np.unique(labels[yellow])) == {11}  # the glint patch
        assert set(np.unique(labels[green])) == set(range(24)) - {11}

    def test_solve_matches_exact_within_noise(self, capture_file, truth):
        """measure -> solve gives the simulator's M, Q, N within what the sampling noise explains.

        See :func:`_deviation_in_sigmas` for the bound (5 Monte-Carlo sigmas, element-wise).
        """
        result = measure_capture(load_capture(capture_file))
        for name, deviation in _deviation_in_sigmas(result, truth).items():
            assert np.max(np.abs(deviation)) <= 5, (name, deviation)

    def test_bound_catches_uncorrected_vignetting(self, capture_file, truth):
        # The same plates without their flat field: 10 % corner fall-off is far outside the bound.
        document = yaml.safe_load(capture_file.read_text())
        document["flat_field"] = None
        result = measure_capture(capture_from_dict(document, source=str(capture_file)))
        # 40 draws size the bound well enough here (worst observed: 300 sigmas with 200 draws,
        # 331 with 40): a quarter of the Monte-Carlo solves.
        deviations = _deviation_in_sigmas(result, truth, n_draws=40).values()
        worst = max(np.max(np.abs(d)) for d in deviations)
        assert worst > 20, worst


class TestBadInput:
    """Exit 2, one line naming the plate, and nothing written."""

    def _run(self, tmp_path, capture_file, edit, capsys) -> str:
        document = yaml.safe_load(capture_file.read_text())
        edit(document, capture_file.parent / "plates")
        bad = capture_file.parent / f"bad_{tmp_path.name}.yaml"
        bad.write_text(yaml.safe_dump(document, sort_keys=False))
        out = tmp_path / "out" / "stage.yaml"
        capsys.readouterr()
        assert main(["measure", str(bad), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("ocio-vp measure: error: ")
        assert not (tmp_path / "out").exists()  # nothing written, not even the folder
        return err

    def test_missing_file(self, tmp_path, capture_file, capsys):
        def edit(d, plates):
            d["lit_chart"]["red"]["plate"] = "plates/nope.exr"

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "nope.exr" in err and "lit_chart.red" in err and "not found" in err

    def test_corrupt_exr(self, tmp_path, capture_file, capsys):
        def edit(d, plates):
            data = (plates / "lit_blue.exr").read_bytes()
            (plates / "corrupt.exr").write_bytes(data[: len(data) // 2])
            d["lit_chart"]["blue"]["plate"] = "plates/corrupt.exr"

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "corrupt.exr" in err and "lit_chart.blue" in err

    def test_corners_outside(self, tmp_path, capture_file, capsys):
        def edit(d, plates):
            d["environments"][0]["target_chart"]["corners"][1] = [640.0, 104.0]

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "incandescent.exr" in err and "outside the image" in err

    def test_no_rgb_channels(self, tmp_path, capture_file, capsys):
        def edit(d, plates):
            write_plate(plates / "yz.exr", np.ones(FRAME), channels=("Y", "Z"))
            d["lit_chart"]["green"]["plate"] = "plates/yz.exr"

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "yz.exr" in err and "no R, G, B channels (channels: Y, Z)" in err

    def test_fully_clipped_chart(self, tmp_path, capture_file, truth, capsys):
        def edit(d, plates):
            image = np.minimum(render_chart(truth.SRL[:, :, 0] * 100, noise=NOISE), 1.0)
            write_plate(plates / "clipped.tif", image, dtype="uint16")
            d["lit_chart"]["red"]["plate"] = "plates/clipped.tif"

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "clipped.tif" in err and "clipped" in err

    def test_8bit_without_encoding(self, tmp_path, capture_file, capsys):
        def edit(d, plates):
            write_plate(plates / "eight.png", np.full(FRAME, 0.5), dtype="uint8")
            d["environments"][1]["target_chart"]["plate"] = "plates/eight.png"

        err = self._run(tmp_path, capture_file, edit, capsys)
        assert "eight.png" in err and "display-referred" in err


def test_detect_corners_written_back(tmp_path, truth):
    """A chart without corners is found (the default install's detector) within half a pixel,
    and the corners are written back in place of ``detect``."""
    values = truth.environments[0].target_chart
    corners = np.array([[100.0, 80.0], [500.0, 90.0], [495.0, 350.0], [105.0, 345.0]])
    plate = write_plate(tmp_path / "chart.exr", render_chart(values, corners=corners, noise=0.005))
    from ocio_vp.plates.detection import detect_chart_corners
    from ocio_vp.plates.reader import open_plate
    from ocio_vp.plates.sampling import sample_chart

    found = detect_chart_corners(open_plate(plate))
    assert np.max(np.abs(found - corners)) < 0.5
    samples = sample_chart(plate, found, 4, 6)
    # the plate's per-pixel noise is 0.005 relative (render_chart's noise): a patch's mean over
    # its pixels stays well inside that; 0.1 % of the chart's peak for the darkest patches
    np.testing.assert_allclose(samples.means, values, rtol=0.005, atol=0.001 * values.max())

    from ocio_vp.plates.capture import with_corners

    document = {"lit_chart": {"red": {"plate": "x.exr", "corners": "detect"}}}
    written = with_corners(document, {("lit_chart", "red"): found})
    assert written["lit_chart"]["red"]["corners"] == np.round(found, 2).tolist()
    assert document["lit_chart"]["red"]["corners"] == "detect"  # the input is not modified
