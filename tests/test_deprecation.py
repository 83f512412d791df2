"""Names that left the public API still work for one release, with a DeprecationWarning that
names the replacement and the release that removes them (ocio_vp.deprecation)."""

from __future__ import annotations

import dataclasses
import importlib
import warnings

import numpy as np
import pytest

from ocio_vp.deprecation import REMOVED_IN
from ocio_vp.formats import Solution
from ocio_vp.model import MatrixCorrection, RootPolynomialCorrection
from ocio_vp.model.expansion import apply_root_polynomial

SAMPLE_MATRIX = "ocio_vp.metrics:sample_camera_to_xyz"
#: (module, old name, words the warning must contain, where the value now lives: a module holding
#: it under the old name, or "module:new name")
ALIASES = [
    ("ocio_vp.ocio.config", "MAX_CONDITION_Q_FOR_N", "ocio_vp.calibration", "ocio_vp.calibration"),
    ("ocio_vp.exports.resolve", "DEFAULT_CUBE_SIZE", "exports.source", "ocio_vp.exports.source"),
    ("ocio_vp.exports.resolve", "DEFAULT_CUBE_RANGE", "exports.source", "ocio_vp.exports.source"),
    ("ocio_vp.ocio.root_polynomial", "RootPolynomialOutputs", "ModelOutputs", None),
    ("ocio_vp.ocio.root_polynomial", "root_polynomial_outputs", "model_outputs", None),
    *(
        (module, "default_camera_to_xyz", "metrics.sample_camera_to_xyz", SAMPLE_MATRIX)
        for module in ("ocio_vp.correction", "ocio_vp.correction.perceptual")
    ),
    ("ocio_vp.correction.skin_priority", "default_fit", "q_auto", "ocio_vp.correction.auto:q_auto"),
    ("ocio_vp.ocio.wall", "sidecar_name", "ocio.clf.sidecar_name", "ocio_vp.ocio.clf"),
    ("ocio_vp.synthesis.camera", "CIE_OBSERVER", "spectra.CIE_OBSERVER", "ocio_vp.spectra"),
    ("ocio_vp.synthesis.camera", "cie_cmfs_sds", "spectra.cie_cmfs_sds", "ocio_vp.spectra"),
]
RNG = np.random.default_rng(39)
C = np.hstack([np.diag([1.1, 0.9, 1.0]), 0.05 * RNG.standard_normal((3, 3))])  # degree 2


def _old(module: str, name: str, words: str) -> object:
    with pytest.warns(DeprecationWarning, match=f"{module}.{name}.*{REMOVED_IN}.*{words}"):
        return getattr(importlib.import_module(module), name)


@pytest.mark.parametrize(("module", "name", "words", "home"), ALIASES)
def test_alias_warns_and_is_the_new_object(module, name, words, home) -> None:
    value = _old(module, name, words)
    if home is not None:
        home, _, new = home.partition(":")
        assert value is getattr(importlib.import_module(home), new or name)
    else:
        assert value is getattr(importlib.import_module("ocio_vp.ocio.bake"), words)


def test_unknown_name_is_still_an_attribute_error() -> None:
    import ocio_vp.ocio.root_polynomial as old

    with pytest.raises(AttributeError, match="LUT_SIZE"):
        old.LUT_SIZE  # noqa: B018 (a bake constant that changed meaning: no alias)


def test_wall_signal_encodings_agree_with_wall_encoding() -> None:
    table = _old("ocio_vp.ocio.config", "WALL_SIGNAL_ENCODINGS", "WallEncoding")
    # the values 1631fec's table held, written out
    assert table == {
        "linear": "scene-linear",
        "gamma2.4": "sdr-video",
        "srgb": "sdr-video",
        "pq": "hdr-video",
    }


@pytest.mark.parametrize("module", ["ocio_vp.correction", "ocio_vp.correction.root_polynomial"])
def test_post_correction_function(module) -> None:
    post_correction = _old(module, "post_correction", "Solution.post_correction")
    Q = np.array([[1.2, -0.1, 0.0], [0.0, 0.9, 0.1], [0.05, 0.0, 1.0]])
    rgb = RNG.random((5, 3))
    np.testing.assert_allclose(post_correction(Q, None)(rgb), rgb @ Q.T, rtol=1e-15)
    notes = {"root_polynomial": {"degree": 2, "coefficients": C.tolist()}}
    np.testing.assert_allclose(
        post_correction(Q, notes)(rgb), apply_root_polynomial(C, rgb), rtol=1e-15
    )


@pytest.mark.parametrize("module", ["ocio_vp.footage", "ocio_vp.footage.apply"])
def test_root_polynomial_transform(module) -> None:
    make = _old(module, "RootPolynomialTransform", "ModelTransform")
    rgb = RNG.random((4, 3))
    pixels = rgb.astype(np.float32)
    make(C)(pixels)  # in place, float32 buffer computed in float64
    np.testing.assert_allclose(pixels, apply_root_polynomial(C, rgb.astype(np.float32)), rtol=1e-6)


@pytest.mark.parametrize("module", ["ocio_vp.plates", "ocio_vp.plates.detection"])
def test_detector_still_returns_detect_chart(module) -> None:
    from ocio_vp.plates.detection import detect_chart

    detector = _old(module, "detector", "detect_chart")
    assert detector(source="plate.exr") is detect_chart


def test_detection_found_warns_and_says_whether_corners_were_found() -> None:
    from ocio_vp.plates.detection import Detection

    def detection(corners):
        return Detection(corners, None, "", np.zeros((1, 1, 3)), 1, np.zeros((1, 1)), np.zeros(0))

    for corners, found in [(np.zeros((4, 2)), True), (None, False)]:
        with pytest.warns(DeprecationWarning, match=f"Detection.found.*{REMOVED_IN}.*corners"):
            assert detection(corners).found is found


def test_correction_public_names_all_resolve() -> None:
    """``from ocio_vp.correction import *`` (every name of ``__all__`` importable)."""
    import ocio_vp.correction as correction

    assert [n for n in correction.__all__ if not hasattr(correction, n)] == []


_FIELDS = dict(
    stage="s",
    environment="e",
    method="least-squares",
    beta=1.0,
    w_avg=np.ones(3),
    SL=np.eye(3),
    M=np.eye(3),
    N=None,
    black_level_offset=None,
    black_level_method=None,
)
Q = np.array([[1.1, 0.02, 0.0], [0.01, 0.95, 0.03], [0.0, 0.04, 1.02]])


def test_solution_Q_keyword_alone_is_a_matrix_correction() -> None:
    with pytest.warns(DeprecationWarning, match=rf"Solution\(Q=\.\.\.\).*{REMOVED_IN}"):
        solution = Solution(Q=Q, **_FIELDS)
    assert isinstance(solution.post_correction, MatrixCorrection)
    np.testing.assert_array_equal(solution.Q, Q)


def test_solution_Q_positional_where_post_correction_is() -> None:
    values = list(_FIELDS.values())
    with pytest.warns(DeprecationWarning, match="Solution"):
        solution = Solution(*values[:7], Q, *values[7:])
    np.testing.assert_array_equal(solution.post_correction.matrix, Q)


def test_solution_Q_matching_the_correction_is_accepted_with_a_warning() -> None:
    correction = RootPolynomialCorrection(C, Q)
    with pytest.warns(DeprecationWarning, match="Solution"):
        solution = Solution(Q=Q * (1 + 1e-12), post_correction=correction, **_FIELDS)
    assert solution.post_correction is correction


def test_solution_Q_disagreeing_with_the_correction_is_refused() -> None:
    edited = Q.copy()
    edited[0, 0] += 1e-6
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="differs from"):
        Solution(Q=edited, post_correction=MatrixCorrection(Q), **_FIELDS)


def test_solution_without_Q_does_not_warn() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Solution(post_correction=MatrixCorrection(Q), **_FIELDS)


def test_dict_style_ocio_names_warn_and_read_the_field() -> None:
    """solution.ocio was a dict of names: scripts that index it keep working for one release."""
    from ocio_vp.formats.panel_solution import OcioNames

    names = OcioNames(config="config.ocio", reference="ACES2065-1")
    with pytest.warns(DeprecationWarning, match=f'ocio\\["config"\\].*{REMOVED_IN}.*ocio.config'):
        assert names["config"] == "config.ocio"
    with pytest.warns(DeprecationWarning, match=f"{REMOVED_IN}.*ocio.display"):
        assert names.get("display", "fallback") == "fallback"
    with pytest.warns(DeprecationWarning), pytest.raises(KeyError, match="in_frustum"):
        names["in_frustum"]  # unnamed in this block, as a missing dict key was
    with pytest.warns(DeprecationWarning), pytest.raises(KeyError, match="not_a_name"):
        names["not_a_name"]
    # the rest of the dict API reads the named roles only: None fields are missing keys
    named = {"config": "config.ocio", "reference": "ACES2065-1"}
    with pytest.warns(DeprecationWarning, match=f'"config" in ocio.*{REMOVED_IN}.*ocio.config'):
        assert "config" in names
    with pytest.warns(DeprecationWarning, match=REMOVED_IN):
        assert "display" not in names
    with pytest.warns(DeprecationWarning, match=f"iterating ocio.*{REMOVED_IN}.*to_dict"):
        assert list(names) == list(named)
    with pytest.warns(DeprecationWarning, match=f"ocio.keys\\(\\).*{REMOVED_IN}"):
        assert list(names.keys()) == list(named)
    with pytest.warns(DeprecationWarning, match=f"ocio.items\\(\\).*{REMOVED_IN}"):
        assert dict(names.items()) == named
    with pytest.warns(DeprecationWarning, match=f"ocio.values\\(\\).*{REMOVED_IN}"):
        assert list(names.values()) == list(named.values())
    with pytest.warns(DeprecationWarning, match=REMOVED_IN) as caught:
        assert dict(names) == named  # dict() reads keys(), then ocio[key] for each
    assert [str(w.message).split(" is ")[0] for w in caught] == [
        "ocio.keys()",
        'ocio["config"]',
        'ocio["reference"]',
    ]
    assert names == OcioNames(config="config.ocio", reference="ACES2065-1")  # no warning
    assert OcioNames() == OcioNames() and bool(OcioNames())  # dataclass eq, always truthy


@pytest.mark.parametrize("module", ["ocio_vp.correction", "ocio_vp.correction.linear"])
def test_loo_cv_error_is_the_relative_error_of_the_held_out_predictions(module) -> None:
    from ocio_vp.correction.linear import loo_predictions

    loo_cv_error = _old(module, "loo_cv_error", "error_relative_to_white")
    X = RNG.random((24, 3)) + 0.05
    P = X @ Q.T + 0.01 * RNG.standard_normal((24, 3))
    w = np.ones(24)
    w[3] = 0.0
    held = loo_predictions("least-squares", X, P, w, 18)
    # d96a980's formula, written out: mean_j w_j |held_j - p_j| / p_white over the kept patches
    expected = (w[:, None] * np.abs(held - P)).sum(axis=0) / w.sum() / P[18]
    np.testing.assert_allclose(loo_cv_error("least-squares", X, P, w, 18), expected, rtol=1e-12)


SAMPLE_SOLUTION = "sample_configs/paper_stage/direct_sun"


def test_model_files_is_read_by_config_data_as_its_sidecars() -> None:
    from pathlib import Path

    import ocio_vp.ocio.config as config
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.ocio.description import file, group

    ModelFiles = _old("ocio_vp.ocio.config", "ModelFiles", "ModelOutputs")
    solution = load_solution(Path(__file__).resolve().parent.parent / SAMPLE_SOLUTION)
    data = config.config_data(solution, model=ModelFiles("q.clf", "qi.clf", "Chain note."))
    footage = data.colour_space(config.POST_CORRECTION_COLORSPACE)
    assert (footage.to_reference, footage.from_reference) == (file("q.clf"), file("qi.clf"))
    (q,) = [t for t in data.named_transforms if t.name == config.POST_CORRECTION]
    assert "(q.clf; the matrix below is only its 3x3 approximation). Chain note." in q.description
    inner = data.colour_space(config.IN_FRUSTUM).from_reference  # [SL]^-1 Q^-1(c)
    assert inner.children[0] == file("qi.clf") and inner == group(
        [file("qi.clf"), inner.children[1]]
    )


def test_wall_tail_is_what_wall_chains_appends() -> None:
    from pathlib import Path

    import ocio_vp.ocio.config as config
    from ocio_vp.formats.solution import load_solution
    from ocio_vp.ocio.description import clamp, group
    from ocio_vp.ocio.matrix import matrix_record

    wall_tail = _old("ocio_vp.ocio.config", "wall_tail", "wall_chains")
    solution = load_solution(Path(__file__).resolve().parent.parent / SAMPLE_SOLUTION)
    extra = [matrix_record(np.eye(3) * 0.5)]
    tail, undo = wall_tail(solution, extra)
    # a linear wall without soft clip: the extra records between clamps to the drive's domain
    assert tail == [clamp(min_in=0.0, min_out=0.0), *extra]
    assert undo == [group(tail, inverse=True)]
    there, back = config.wall_chains(solution, {config.OUT_OF_FRUSTUM: extra}, None)[
        config.OUT_OF_FRUSTUM
    ]
    assert there[-2:] == tail and back[:1] == undo
    assert wall_tail(solution, []) == ([], [])


def test_ocio_names_config_filename_keyword_warns_and_names_the_config() -> None:
    from ocio_vp.ocio.config import ocio_names

    with pytest.warns(DeprecationWarning, match=f"config_filename.*{REMOVED_IN}.*ocio_names"):
        names = ocio_names(config_filename="stage.ocio")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert names == dataclasses.replace(ocio_names(), config="stage.ocio")


def test_skin_delta_e_is_camera_delta_e_2000_with_the_target_first() -> None:
    import colour

    skin_delta_e = _old("ocio_vp.correction.skin", "skin_delta_e", "camera_delta_E_2000")
    white = np.array([0.9, 1.0, 0.8])
    target = np.array([[0.40, 0.30, 0.22], [0.20, 0.14, 0.10]])
    corrected = target * np.array([1.03, 0.98, 1.01])
    # independently: XYZ = RGB / white's Y (camera_to_xyz = I), Lab relative to white, ΔE2000
    lab = [
        colour.XYZ_to_Lab(rgb / white[1], colour.XYZ_to_xy(white / white[1]))
        for rgb in (target, corrected)
    ]
    np.testing.assert_allclose(
        skin_delta_e(corrected, target, white, np.eye(3)),
        colour.delta_E(lab[0], lab[1], method="CIE 2000"),
        rtol=1e-9,
    )


def test_wall_encoding_of_names_the_encoding_and_peak() -> None:
    from pathlib import Path

    from ocio_vp.formats.solution import load_solution

    wall_encoding_of = _old("ocio_vp.patterns.validation", "wall_encoding_of", "WallEncoding.of")
    solution = load_solution(Path(__file__).resolve().parent.parent / SAMPLE_SOLUTION)
    assert solution.linearity is None  # a linear wall, no peak: what d96a980 returned for it
    assert wall_encoding_of(solution) == ("linear", None)


@pytest.mark.parametrize(
    ("module", "name", "fields"),
    [
        ("ocio_vp.ocio.show", "KeptSpace", ["name", "aliases", "is_data", "record", "problem"]),
        ("ocio_vp.exports.unreal_script", "UnrealSlot", ["name", "index", "family"]),
    ],
)
def test_old_records_keep_their_fields(module, name, fields) -> None:
    record = _old(module, name, "")
    assert [f.name for f in dataclasses.fields(record)] == fields


def test_show_data_kept_keyword_warns_and_changes_nothing() -> None:
    from ocio_vp.ocio import description as d
    from ocio_vp.ocio import show

    base = d.ConfigData(
        colour_spaces=[d.ColourSpace("AP0", "", "")],
        roles={"aces_interchange": "AP0"},
        views=[d.View("sRGB", "Film", "AP0")],
    )
    camera = d.matrix([2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 2.0, 0, 0, 0, 0, 1])
    own = d.ConfigData(colour_spaces=[d.ColourSpace(show.REFERENCE, "ocio-vp/Camera", "camera")])
    envs = [show.EnvironmentData("a", own, camera)]
    with pytest.warns(DeprecationWarning, match=f"show_data\\(kept=.*{REMOVED_IN}.*base.kept"):
        data = show.show_data(base, envs, "base", kept=[])
    assert data == show.show_data(base, envs, "base")


def _corrections():
    from ocio_vp.model.correction import FitDomain, ProtectedCorrection

    domain = FitDomain(np.eye(3), [[0.2, 0.2], [0.5, 0.2], [0.2, 0.5]], [0.3, 0.3])
    return [
        MatrixCorrection(Q),
        RootPolynomialCorrection(C, Q),
        ProtectedCorrection(MatrixCorrection(Q), domain, np.eye(3)),
    ]


@pytest.mark.parametrize("index", range(3))
def test_homogeneous_warns_and_says_whether_q_commutes_with_scale(index) -> None:
    correction = _corrections()[index]
    name = type(correction).__name__
    with pytest.warns(DeprecationWarning, match=f"{name}.homogeneous.*{REMOVED_IN}"):
        homogeneous = correction.homogeneous
    assert homogeneous is (index < 2)  # d96a980: True, True, False
    rgb = RNG.random((64, 3)) * 2.0
    commutes = np.allclose(correction.apply(4.0 * rgb), 4.0 * correction.apply(rgb), rtol=1e-9)
    assert commutes is homogeneous


def test_chart_errors_summary_is_the_means_and_maxima() -> None:
    from ocio_vp.metrics import ChartErrors

    errors = ChartErrors(np.array([0.01, 0.02, 0.03]), np.array([1.0, 3.0]), np.array([2.0, 6.0]))
    with pytest.warns(DeprecationWarning, match=f"ChartErrors.summary.*{REMOVED_IN}"):
        summary = errors.summary
    assert summary == pytest.approx(
        {
            "relative_to_white_mean": 0.02,
            "delta_E_2000_mean": 2.0,
            "delta_E_2000_max": 3.0,
            "delta_E_ITP_mean": 4.0,
            "delta_E_ITP_max": 6.0,
        },
        rel=1e-15,
    )


def test_model_outputs_inverse_is_the_blocks_inverse_agreement() -> None:
    from ocio_vp.formats.diagnostics import PostCorrectionOCIO
    from ocio_vp.model.footage_range import Agreement
    from ocio_vp.ocio.bake import ModelOutputs

    forward = Agreement({"all": 0.1}, {"all": 0.2}, (1.0, 1.0, 1.0))
    back = Agreement({"all": 0.3}, {"all": 0.4}, (0.5, 0.5, 0.5))
    block = PostCorrectionOCIO(files=["q.clf", "qi.clf"], agreement=forward, inverse_agreement=back)
    for outputs, expected in [
        (ModelOutputs("q.clf", "qi.clf", forward, block=block), back),
        (ModelOutputs("q.clf", None, forward), None),
    ]:
        with pytest.warns(DeprecationWarning, match=f"ModelOutputs.inverse.*{REMOVED_IN}"):
            assert outputs.inverse is expected


@pytest.mark.parametrize(("zero", "overflow"), [(True, 0.0), (False, np.inf)])
def test_block_means_zero_non_finite_keyword_still_chooses(monkeypatch, zero, overflow) -> None:
    from ocio_vp.plates import reader

    pixels = np.full((8, 8, 3), 0.5, dtype=np.float32)
    pixels[4:8, 0:4] = np.inf  # one block overflowed
    monkeypatch.setattr(reader, "read_region", lambda info, box: pixels[box[1] : box[3]])
    info = reader.PlateInfo("p.exr", "openexr", 8, 8, 16, True, "linear")
    with pytest.warns(DeprecationWarning, match=f"zero_non_finite.*{REMOVED_IN}"):
        means = reader.block_means(info, 4, zero_non_finite=zero)
    assert (means[1, 0] == overflow).all() and (means[0, 0] == 0.5).all()


def test_finite_array_old_call_fails_at_once_and_says_how() -> None:
    from ocio_vp.formats.records import finite_array

    with pytest.raises(TypeError, match=r"now finite_array\(data, name, shape, within\)"):
        finite_array([1.0, 2.0, 3.0], (3,), "white")  # type: ignore[arg-type]
    np.testing.assert_array_equal(finite_array({"white": [1, 2, 3]}, "white", (3,)), [1, 2, 3])
