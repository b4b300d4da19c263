# SPDX-License-Identifier: MIT
"""Fine registration: register(..., refine=...), Matcher.refine, Matcher.refine_features and kissm.refine on
the committed pair against its ground truth; the refined fields of Result; the information matrix's frame
and order; the refined reasons; bad initial transforms."""

from __future__ import annotations

import copy
import json
import math
import pickle

import numpy as np
import pytest

import kissm
from kissm import _ffi

import testdata
from helpers import TIME_FIELDS, assert_same_result, bits
from testdata import pose, rotation_error_deg, rotation_zyx

VOXEL = testdata.VOXEL_SIZE
MODES = ["gicp", "point_to_plane"]


def errors(transform: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(rotation error in degrees, translation error) of a 4x4 pose against the truth."""
    return rotation_error_deg(transform[:3, :3], truth[:3, :3]), float(np.linalg.norm(transform[:3, 3] - truth[:3, 3]))


def hat(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def adjoint(transform: np.ndarray) -> np.ndarray:
    """The 6x6 adjoint of a pose for twists ordered rotation then translation (GTSAM's Pose3.AdjointMap)."""
    rotation, translation = transform[:3, :3], transform[:3, 3]
    out = np.zeros((6, 6))
    out[:3, :3] = out[3:, 3:] = rotation
    out[3:, :3] = hat(translation) @ rotation
    return out


@pytest.fixture(scope="module")
def coarse(pair) -> kissm.Result:
    return kissm.register(pair.source, pair.target, voxel_size=VOXEL, num_threads=2)


@pytest.fixture(scope="module")
def refined(pair) -> dict[str, kissm.Result]:
    return {mode: kissm.register(pair.source, pair.target, voxel_size=VOXEL, refine=mode) for mode in MODES}


@pytest.fixture(scope="module")
def prior(pair) -> np.ndarray:
    """The ground truth turned by 3 degrees about z and moved by 0.36 (as a tracking prior would be off)."""
    return pose(rotation_zyx(3.0), [0.2, -0.15, 0.05]) @ pair.transform


# ---- registration with refinement -------------------------------------------------------------------------


@pytest.mark.parametrize("mode", MODES)
def test_refinement_improves_on_the_coarse_pose(pair, coarse, refined, mode: str) -> None:
    result = refined[mode]
    assert result.valid and result.refined and result.reason_code == 0
    coarse_rre, coarse_rte = errors(result.coarse_transform, pair.transform)
    rre, rte = errors(result.transform, pair.transform)
    assert rre < coarse_rre and rte < coarse_rte, (rre, rte, coarse_rre, coarse_rte)
    assert rre < 0.1 and rte < 0.01  # the coarse pose is off by about 0.24 degrees and 4 cm
    # the coarse stages are those of a registration without refinement
    assert bits(result.coarse_transform) == bits(coarse.transform)
    assert_same_result(
        result,
        coarse,
        ignore=TIME_FIELDS
        | {"transform", "rotation", "translation", "coarse_transform", "information", "overlap", "refine_rmse"}
        | {"refine_condition", "num_refine_correspondences", "refine_iterations", "refine_converged"}
        | {"inlier_coverage", "confidence"},
    )
    assert np.array_equal(result.transform[:3, :3], result.rotation)
    assert np.array_equal(result.transform[:3, 3], result.translation)
    assert np.array_equal(result.transform[3], [0, 0, 0, 1]) and np.array_equal(
        result.coarse_transform[3], [0, 0, 0, 1]
    )


@pytest.mark.parametrize("mode", MODES)
def test_refined_fields(refined, mode: str) -> None:
    result = refined[mode]
    info = result.information
    assert info.shape == (6, 6) and info.dtype == np.float64
    assert np.array_equal(info, info.T)
    assert np.linalg.eigvalsh(info).min() > 0  # positive definite
    np.linalg.cholesky(info)
    assert 0.0 < result.overlap <= 1.0
    assert 0.0 < result.refine_rmse < VOXEL
    assert 0.0 < result.refine_condition <= 1.0
    assert result.inlier_coverage >= kissm.Config().min_inlier_coverage  # valid
    assert 0 < result.num_refine_correspondences <= result.num_source_voxels
    assert 1 <= result.refine_iterations <= kissm.Config().refine_max_iterations
    assert type(result.refine_converged) is bool and result.refine_converged
    assert result.time_refine_ms > 0
    parts = sum(getattr(result, name) for name in TIME_FIELDS - {"time_total_ms"})
    assert result.time_total_ms == pytest.approx(parts)


def test_without_refinement_the_refined_fields_are_empty(coarse) -> None:
    assert coarse.valid and not coarse.refined
    assert bits(coarse.coarse_transform) == bits(coarse.transform)
    assert coarse.information.shape == (6, 6) and np.isnan(coarse.information).all()
    for name in ("overlap", "refine_rmse", "refine_condition", "inlier_coverage"):
        assert math.isnan(getattr(coarse, name)), name
    assert coarse.num_refine_correspondences == coarse.refine_iterations == 0
    assert coarse.refine_converged is False and coarse.time_refine_ms == 0.0
    assert "refined" not in repr(coarse)


def test_refine_keyword_is_refine_mode(pair, refined) -> None:
    gicp = refined["gicp"]
    assert_same_result(kissm.register(pair.source, pair.target, VOXEL, refine_mode="gicp"), gicp)
    assert_same_result(kissm.register(pair.source, pair.target, VOXEL, refine=_ffi.lib.KISSM_REFINE_GICP), gicp)
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as matcher:
        assert_same_result(matcher.register(pair.source, pair.target), gicp)
    with pytest.raises(TypeError, match="refine or refine_mode, not both"):
        kissm.register(pair.source, pair.target, VOXEL, refine="gicp", refine_mode="gicp")
    with pytest.raises(ValueError, match="Config.refine_mode is 'icp'"):
        kissm.register(pair.source, pair.target, VOXEL, refine="icp")  # type: ignore[arg-type]
    assert not kissm.register(pair.source, pair.target, VOXEL, refine="none").refined


def test_refined_registration_uses_the_features_index(pair, refined) -> None:
    """Features computed with refinement on give register's refined result through register_features."""
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as matcher:
        source, target = matcher.compute_features(pair.source), matcher.compute_features(pair.target)
        assert_same_result(matcher.register_features(source, target), refined["gicp"])
    with kissm.Matcher(voxel_size=VOXEL) as plain:  # features without the index: the same numbers
        source, target = plain.compute_features(pair.source), plain.compute_features(pair.target)
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as matcher:
        assert_same_result(matcher.register_features(source, target), refined["gicp"])


# ---- refinement from a prior ------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize(
    ("yaw", "pitch", "roll", "shift"),
    [(3.0, 0.0, 0.0, (0.2, -0.15, 0.05)), (-5.0, 2.0, -2.0, (0.5, 0.3, -0.2)), (8.0, 0.0, 0.0, (1.0, 0.0, 0.0))],
)
def test_matcher_refine_converges_to_the_ground_truth(
    pair, mode: str, yaw: float, pitch: float, roll: float, shift: tuple[float, float, float]
) -> None:
    initial = pose(rotation_zyx(yaw, pitch, roll), shift) @ pair.transform
    with kissm.Matcher(voxel_size=VOXEL, refine_mode=mode, num_threads=2) as matcher:
        result = matcher.refine(pair.source, pair.target, initial)
    assert result.valid and result.refined and result.reason == "none", result
    rre, rte = errors(result.transform, pair.transform)
    assert rre < 0.05 and rte < 0.005, (rre, rte)
    assert result.refine_converged and result.refine_iterations < kissm.Config().refine_max_iterations
    # coarse_transform is the initial transform (made exactly rigid by the library)
    assert np.allclose(result.coarse_transform, initial, rtol=0, atol=1e-12)
    # no descriptors, no global search
    assert result.num_source_keypoints == result.num_initial_correspondences == result.num_final_inliers == 0
    assert result.time_features_ms > 0 and result.time_matching_ms == result.time_solver_ms == 0
    assert result.num_source_voxels > 0 and result.num_target_voxels > 0
    assert "refined from an initial pose" in repr(result)


def test_refine_from_the_solvers_pose_equals_refined_registration(pair, coarse, refined) -> None:
    """kissm_refine from the coarse pose is the same refinement as the one inside register."""
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as matcher:
        result = matcher.refine(pair.source, pair.target, coarse.transform)
    # to rounding (the start is recentred differently): compared entry by entry, as an angle from acos would
    # drown 1e-15 in its own ~1e-6 degrees of noise
    assert np.abs(result.transform - refined["gicp"].transform).max() < 1e-12
    assert result.refine_iterations == refined["gicp"].refine_iterations


def test_refine_mode_none_refines_with_gicp(pair, prior) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as none, kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as gicp:
        assert_same_result(none.refine(pair.source, pair.target, prior), gicp.refine(pair.source, pair.target, prior))
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="point_to_plane") as p2p:
        other = p2p.refine(pair.source, pair.target, prior)
    with kissm.Matcher(voxel_size=VOXEL) as none:
        assert bits(other.transform) != bits(none.refine(pair.source, pair.target, prior).transform)


@pytest.mark.parametrize("refine_mode", ["none", "gicp"])
def test_refine_features_equals_refine_bit_for_bit(pair, prior, refine_mode: str) -> None:
    """Features made with refinement on carry the index; without it it is built per call: same numbers."""
    with kissm.Matcher(voxel_size=VOXEL, refine_mode=refine_mode, num_threads=2) as matcher:
        expected = matcher.refine(pair.source, pair.target, prior)
        source, target = matcher.compute_features(pair.source), matcher.compute_features(pair.target)
        result = matcher.refine_features(source, target, prior)
    # every count too: refinement uses no descriptors, so neither call reports keypoints
    assert_same_result(result, expected, ignore=TIME_FIELDS)
    assert result.num_source_keypoints == result.num_target_keypoints == 0 < source.num_keypoints
    assert result.time_voxelize_ms == result.time_features_ms == 0.0 and result.time_refine_ms > 0
    # features outlive their matcher and work with any matcher of the same descriptor settings
    with kissm.Matcher(voxel_size=VOXEL, min_overlap=0.5) as other:
        assert_same_result(other.refine_features(source, target, prior), result, ignore=TIME_FIELDS)


def test_refine_features_checks_its_arguments(pair, prior) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as matcher:
        features = matcher.compute_features(pair.source)
        with pytest.raises(TypeError, match=r"target must be kissm.Features \(from Matcher.compute_features\)"):
            matcher.refine_features(features, pair.target, prior)
        with pytest.raises(kissm.InvalidArgumentError, match=r"^kissm_refine_features: initial_transform\[5\]"):
            matcher.refine_features(features, features, _with(np.eye(4), (1, 1), math.nan))
    with kissm.Matcher(voxel_size=0.5) as other:
        with pytest.raises(kissm.FeaturesMismatchError, match="^kissm_refine_features: source features"):
            other.refine_features(features, features, prior)


def test_refine_normal_radius_gain_moves_the_refined_pose_only(pair, coarse, refined, prior) -> None:
    """The planes refinement aligns: another neighbourhood, another refined pose (as accurate) from the same coarse
    pose, deterministic across thread counts; features computed with another value are refused."""
    gain = 0.75 * kissm.Config().refine_normal_radius_gain
    results = [
        kissm.register(pair.source, pair.target, VOXEL, refine="gicp", refine_normal_radius_gain=gain, num_threads=n)
        for n in (1, 2)
    ]
    assert_same_result(results[0], results[1], ignore=TIME_FIELDS)
    other = results[0]
    assert other.valid and bits(other.coarse_transform) == bits(coarse.transform)
    assert bits(other.transform) != bits(refined["gicp"].transform)
    rre, rte = errors(other.transform, pair.transform)
    assert rre < 0.1 and rte < 0.01, (rre, rte)
    from_prior = kissm.refine(pair.source, pair.target, prior, VOXEL, refine_normal_radius_gain=gain)
    assert bits(from_prior.transform) != bits(kissm.refine(pair.source, pair.target, prior, VOXEL).transform)
    assert from_prior.valid and errors(from_prior.transform, pair.transform)[0] < 0.1
    with kissm.Matcher(voxel_size=VOXEL) as a, kissm.Matcher(voxel_size=VOXEL, refine_normal_radius_gain=gain) as b:
        source, target = a.compute_features(pair.source), a.compute_features(pair.target)
        with pytest.raises(kissm.FeaturesMismatchError, match="^kissm_register_features: source features"):
            b.register_features(source, target)
        with pytest.raises(kissm.FeaturesMismatchError, match="^kissm_refine_features: source features"):
            b.refine_features(source, target, prior)
        assert b.refine_features(b.compute_features(pair.source), b.compute_features(pair.target), prior).valid


def test_module_refine_equals_matcher_refine(pair, prior) -> None:
    with kissm.Matcher(voxel_size=VOXEL, num_threads=2) as matcher:
        expected = matcher.refine(pair.source, pair.target, prior)
    assert_same_result(kissm.refine(pair.source, pair.target, prior, voxel_size=VOXEL), expected)
    assert_same_result(kissm.refine(pair.source, pair.target, prior, VOXEL, num_threads=1), expected)
    assert_same_result(kissm.refine(pair.source, pair.target, prior.tolist(), VOXEL, refine="gicp"), expected)
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="point_to_plane") as matcher:
        p2p = matcher.refine(pair.source, pair.target, prior)
    assert_same_result(kissm.refine(pair.source, pair.target, prior, VOXEL, refine="point_to_plane"), p2p)
    assert_same_result(kissm.refine(pair.source, pair.target, prior, VOXEL, refine_mode="point_to_plane"), p2p)
    with pytest.raises(TypeError):
        kissm.refine(pair.source, pair.target, prior)  # type: ignore[call-arg]  # voxel_size is required


def test_initial_accepts_any_real_4x4(pair, prior) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as matcher:
        expected = matcher.refine(pair.source, pair.target, prior)
        for initial in (prior.tolist(), np.asfortranarray(prior), prior.astype(np.longdouble), prior[::-1][::-1]):
            assert_same_result(matcher.refine(pair.source, pair.target, initial), expected)
        identity = matcher.refine(pair.source, pair.target, np.eye(4, dtype=np.int64))
        assert bits(identity.coarse_transform) == bits(np.eye(4))


@pytest.mark.parametrize("threads", [1, 2])
def test_results_do_not_depend_on_the_thread_count(pair, prior, refined, threads: int) -> None:
    for mode in MODES:
        result = kissm.register(pair.source, pair.target, VOXEL, refine=mode, num_threads=threads)
        assert_same_result(result, refined[mode])
    with kissm.Matcher(voxel_size=VOXEL, num_threads=threads) as matcher:
        one = matcher.refine(pair.source, pair.target, prior)
    with kissm.Matcher(voxel_size=VOXEL, num_threads=3 - threads) as matcher:
        assert_same_result(matcher.refine(pair.source, pair.target, prior), one)


# ---- bad initial transforms -------------------------------------------------------------------------------


def _with(matrix: np.ndarray, index: tuple[int, int], value: float) -> np.ndarray:
    out = matrix.copy()
    out[index] = value
    return out


def _bad_initials(truth: np.ndarray) -> list[tuple[str, np.ndarray, str]]:
    scaled = truth.copy()
    scaled[:3, :3] *= 1.01
    reflected = truth @ np.diag([1.0, 1.0, -1.0, 1.0])
    return [
        ("nan", _with(truth, (1, 2), math.nan), r"initial_transform\[6\] is not finite"),
        ("inf", _with(truth, (0, 3), math.inf), r"initial_transform\[3\] is not finite"),
        ("scaled rotation", scaled, r"initial_transform's rotation block is not a rotation \(R\^T R - I is 0\.0201"),
        ("reflection", reflected, r"initial_transform's rotation block is not a rotation .*det R = -1"),
        ("last row", _with(truth, (3, 2), 1.0), r"initial_transform's last row is \(0, 0, 1, 1\)"),
        ("scaled last row", _with(truth, (3, 3), 2.0), r"initial_transform's last row is \(0, 0, 0, 2\)"),
        ("far translation", _with(truth, (2, 3), 2e9), r"initial_transform's translation \(2e\+09\) is beyond 1e\+09"),
    ]


@pytest.mark.parametrize("case", range(7), ids=[c[0] for c in _bad_initials(np.eye(4))])
def test_bad_initial_values_raise_the_librarys_invalid_argument(pair, case: int) -> None:
    _, initial, message = _bad_initials(pair.transform)[case]
    with kissm.Matcher(voxel_size=VOXEL) as matcher:
        with pytest.raises(kissm.InvalidArgumentError, match=f"^kissm_refine: {message}") as info:
            matcher.refine(pair.source, pair.target, initial)
        assert type(info.value) is kissm.InvalidArgumentError and isinstance(info.value, ValueError)
        assert info.value.status == _ffi.lib.KISSM_ERR_INVALID_ARGUMENT
        with pytest.raises(kissm.InvalidArgumentError, match=message):
            kissm.refine(pair.source, pair.target, initial, VOXEL)
        assert matcher.refine(pair.source, pair.target, pair.transform).valid  # the matcher is unharmed


@pytest.mark.parametrize(
    ("initial", "message"),
    [
        (np.eye(3), r"initial must have shape \(4, 4\).* not \(3, 3\)"),
        (np.eye(4)[:3], r"initial must have shape \(4, 4\).* not \(3, 4\)"),
        (np.eye(4).ravel(), r"initial must have shape \(4, 4\).* not \(16,\)"),
        (np.eye(4)[None], r"initial must have shape \(4, 4\).* not \(1, 4, 4\)"),
        (np.float64(1.0), r"initial must have shape \(4, 4\).* not \(\)"),
        ([[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "initial cannot be read as a"),
    ],
    ids=["3x3", "3x4", "flat", "batched", "scalar", "ragged"],
)
def test_wrong_initial_shapes_are_valueerrors(pair, initial: object, message: str) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as matcher, pytest.raises(ValueError, match=message) as info:
        matcher.refine(pair.source, pair.target, initial)
    assert not isinstance(info.value, kissm.Error)  # refused in Python, before the library


@pytest.mark.parametrize(
    "initial",
    [np.eye(4, dtype=bool), np.eye(4, dtype=complex), np.full((4, 4), "1"), np.full((4, 4), None), None],
    ids=["bool", "complex", "str", "object", "None"],
)
def test_wrong_initial_types_are_typeerrors(pair, initial: object) -> None:
    with kissm.Matcher(voxel_size=VOXEL) as matcher:
        with pytest.raises(TypeError, match=r"initial has dtype .*a \(4, 4\) array of real numbers"):
            matcher.refine(pair.source, pair.target, initial)
        features = matcher.compute_features(pair.source)
        with pytest.raises(TypeError, match="initial has dtype"):
            matcher.refine_features(features, features, initial)
    with pytest.raises(TypeError, match="initial has dtype"):
        kissm.refine(pair.source, pair.target, initial, VOXEL)


def test_refine_checks_clouds_like_register(pair) -> None:
    with pytest.raises(kissm.TooFewPointsError, match="^kissm_refine: target has 3 points"):
        kissm.refine(pair.source, pair.target[:3], np.eye(4), VOXEL)
    with pytest.raises(ValueError, match=r"source must have shape \(N, 3\)"):
        kissm.refine(pair.source[:, :2], pair.target, np.eye(4), VOXEL)


# ---- the information matrix: rotation then translation, in the source's frame --------------------------


def test_information_follows_the_source_frame(pair, prior) -> None:
    """Moving the source cloud by S changes the pose to T S and the information to Ad(S)^T I Ad(S) (twists in
    the source's frame, rotation first); moving the target leaves the information as it is. Pure translations
    keep the voxel grids (each is anchored to its cloud's bounding box), so both hold to rounding."""
    with kissm.Matcher(voxel_size=VOXEL) as matcher:
        base = matcher.refine(pair.source, pair.target, prior)
        shift = pose(np.eye(3), [8.0, -4.0, 2.0])
        moved_source = matcher.refine(pair.source - shift[:3, 3], pair.target, prior @ shift)
        moved_target = matcher.refine(pair.source, pair.target + [3.0, 5.0, -1.0], pose(np.eye(3), [3, 5, -1]) @ prior)
    assert np.allclose(moved_source.transform, base.transform @ shift, rtol=0, atol=1e-12)
    expected = adjoint(shift).T @ base.information @ adjoint(shift)
    scale = np.abs(base.information).max()
    assert np.abs(moved_source.information - expected).max() < 1e-9 * scale
    assert np.abs(moved_source.information - base.information).max() > 0.1 * scale  # the test can tell
    assert np.abs(moved_target.information - base.information).max() < 1e-9 * scale


def test_information_is_about_gauss_newton_curvature(pair, refined) -> None:
    """The information scales as 1 / residual variance: its size predicts the pose's error on this pair."""
    result = refined["gicp"]
    covariance = np.linalg.inv(result.information)
    sigmas = np.sqrt(np.diag(covariance))
    rre, rte = errors(result.transform, pair.transform)
    # calibrated: the true error is within 6 standard deviations (a 6-DOF NEES of 36, where the chi-square's
    # 99.99th percentile is 27)
    assert math.radians(rre) < 6 * np.linalg.norm(sigmas[:3]) and rte < 6 * np.linalg.norm(sigmas[3:])
    assert np.linalg.norm(sigmas[3:]) < VOXEL


# ---- reasons ----------------------------------------------------------------------------------------------


def test_reason_strings_are_the_librarys() -> None:
    codes = {name: getattr(_ffi.lib, name) for name in dir(_ffi.lib) if name.startswith("KISSM_REASON_")}
    assert codes["KISSM_REASON_LOW_OVERLAP"] == 7 and codes["KISSM_REASON_UNCONSTRAINED"] == 8
    assert sorted(codes.values()) == list(range(len(codes)))  # 9 and 10: see test_validity.py
    texts = {code: _ffi.text(_ffi.lib.kissm_reason_string(code)) for code in codes.values()}
    assert len(set(texts.values())) == len(codes) and "unknown reason" not in texts.values()


def test_low_overlap(pair, refined) -> None:
    overlap = refined["gicp"].overlap
    result = kissm.register(pair.source, pair.target, VOXEL, refine="gicp", min_overlap=min(1.0, overlap + 0.05))
    assert not result.valid and result.reason_code == _ffi.lib.KISSM_REASON_LOW_OVERLAP
    assert result.reason == "the refined pose overlaps too little"
    assert result.has_pose and bits(result.transform) == bits(refined["gicp"].transform)  # kept for inspection
    assert result.overlap == overlap
    at_threshold = kissm.register(pair.source, pair.target, VOXEL, refine="gicp", min_overlap=overlap)
    assert at_threshold.valid
    assert "reason='the refined pose overlaps too little'" in repr(result)


def test_unconstrained_plane() -> None:
    """A plane against itself: the refined pose may slide in the plane and turn about its normal."""
    rng = np.random.default_rng(0)
    plane = np.c_[rng.random((4000, 2)) * 10.0, np.zeros(4000)]
    result = kissm.refine(plane, plane, np.eye(4), voxel_size=0.3)
    assert not result.valid and result.reason_code == _ffi.lib.KISSM_REASON_UNCONSTRAINED
    assert result.reason == "the refined pose is not constrained in every direction"
    assert result.refined and result.refine_condition < 0.01 and result.overlap == 1.0
    noisy = plane + np.c_[np.zeros((4000, 2)), rng.normal(scale=0.01, size=4000)]  # 1 cm of range noise
    result = kissm.refine(noisy, plane, np.eye(4), voxel_size=0.3, refine="point_to_plane")
    assert not result.valid and result.reason_code == _ffi.lib.KISSM_REASON_UNCONSTRAINED


@pytest.mark.parametrize("mode", MODES)
def test_noisy_plane_against_itself_is_unconstrained_along_the_plane(mode: str) -> None:
    """A noisy plane (z = 0 plus 1 cm of noise) refined against itself: the noise tilts the normals a little,
    but neither cost may count that as information (GICP's plane regularisation once did): the information
    leaves translations in the plane and the turn about its normal (near) free, and pins the rest."""
    rng = np.random.default_rng(0)
    noisy = np.c_[rng.random((4000, 2)) * 10.0, rng.normal(scale=0.01, size=4000)]
    result = kissm.refine(noisy, noisy, np.eye(4), voxel_size=0.3, refine=mode)
    assert not result.valid and result.reason_code == _ffi.lib.KISSM_REASON_UNCONSTRAINED, result
    assert result.refined and result.overlap == 1.0 and result.refine_condition < 1e-4
    info = result.information
    assert np.array_equal(info, info.T) and np.isfinite(info).all()
    strongest = np.linalg.eigvalsh(info).max()

    def along(*twist: float) -> float:  # the information along a unit twist (rx, ry, rz, tx, ty, tz)
        unit = np.array(twist) / np.linalg.norm(twist)
        return float(unit @ info @ unit) / strongest

    for angle in np.radians([0.0, 30.0, 90.0, 135.0]):  # any direction in the plane
        assert along(0, 0, 0, math.cos(angle), math.sin(angle), 0) < 1e-5
    assert along(0, 0, 1, 0, 0, 0) < 1e-4  # turning about the normal (in radians; about 4 m of lever arm)
    assert along(0, 0, 0, 0, 0, 1) > 1e-3  # the normal's direction is pinned
    assert along(1, 0, 0, 0, 0, 0) > 0.1 and along(0, 1, 0, 0, 0, 0) > 0.1  # and so is the tilt
    weakest = np.linalg.eigh(info)[1][:, 0]  # its near-null direction lies along the plane
    assert np.linalg.norm(weakest[[0, 1, 5]]) < 1e-2, weakest
    # the library names the same three free directions: their span holds x, y and the turn about z
    assert result.degenerate and result.weak_directions.shape == (3, 6), result.weak_directions
    basis = np.linalg.qr(result.weak_directions.T)[0]
    for free in np.eye(6)[[3, 4, 2]]:
        assert np.linalg.norm(basis.T @ free) > math.cos(math.radians(1.0)), (free, result.weak_directions)


# ---- Result plumbing --------------------------------------------------------------------------------------


def test_refined_results_pickle_copy_and_convert(refined, pair, prior) -> None:
    results = [*refined.values(), kissm.refine(pair.source, pair.target, prior, VOXEL)]
    for result in results:
        for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
            assert_same_result(pickle.loads(pickle.dumps(result, protocol)), result, ignore=set())
        assert_same_result(copy.deepcopy(result), result, ignore=set())
        d = result.to_dict()
        assert (
            d["information"] == result.information.tolist()
            and d["coarse_transform"] == result.coarse_transform.tolist()
        )
        assert d["refine_converged"] is True and d["refine_iterations"] == result.refine_iterations
        json.dumps(d)


def test_refined_repr(refined, pair, prior) -> None:
    result = refined["gicp"]
    text = repr(result)
    assert f"{result.num_final_inliers} final inliers of {result.num_initial_correspondences} matches" in text
    assert f"refined: {result.refine_iterations} iterations (converged), {result.num_refine_correspondences} " in text
    assert f"overlap {result.overlap:.3f}, refine_rmse {result.refine_rmse:.4g}," in text
    variances = np.diag(np.linalg.inv(result.information))
    sigmas = f"1-sigma {math.degrees(math.sqrt(variances[:3].sum())):.3g} deg and {math.sqrt(variances[3:].sum()):.3g}"
    assert f"refine_condition {result.refine_condition:.3g}, {sigmas} (from information)," in text
    turned = rotation_error_deg(result.coarse_transform[:3, :3], result.rotation)
    assert f"(refinement moved it {turned:.3f} deg and " in text
    assert f"inlier_coverage {result.inlier_coverage:.3f} (the inliers' spread)," in text
    assert len(text.splitlines()) == 10 and max(map(len, text.splitlines())) < 110
    assert str(result) == text
    from_prior = repr(kissm.refine(pair.source, pair.target, prior, VOXEL))
    assert "refined from an initial pose" in from_prior and "1-sigma" in from_prior
    assert "final inliers" not in from_prior and len(from_prior.splitlines()) == 9
