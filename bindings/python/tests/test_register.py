# SPDX-License-Identifier: MIT
"""Registration through Matcher, kissm.register and features; Result; lifecycle; pickling."""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import numpy as np
import pytest

import kissm

from helpers import TIME_FIELDS, assert_same_result, bits
from testdata import rotation_error_deg


@pytest.fixture(scope="module")
def result(pair) -> kissm.Result:
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2) as matcher:
        return matcher.register(pair.source, pair.target)


def test_recovers_the_true_pose(pair, result) -> None:
    assert result.valid and result.reason == "none" and result.reason_code == 0
    assert rotation_error_deg(result.rotation, pair.rotation) < 1.0
    assert np.linalg.norm(result.translation - pair.translation) < 0.1
    aligned = pair.source[:100] @ result.rotation.T + result.translation
    homogeneous = np.c_[pair.source[:100], np.ones(100)] @ result.transform.T
    assert np.allclose(aligned, homogeneous[:, :3])


def test_result_fields(pair, result) -> None:
    assert result.transform.shape == (4, 4) and result.transform.dtype == np.float64
    assert result.rotation.shape == (3, 3) and result.translation.shape == (3,)
    assert result.inlier_extent.shape == (3,)
    assert np.array_equal(result.transform[:3, :3], result.rotation)
    assert np.array_equal(result.transform[:3, 3], result.translation)
    assert np.array_equal(result.transform[3], [0, 0, 0, 1])
    assert result.num_source_points == len(pair.source) and result.num_target_points == len(pair.target)
    assert result.num_source_nonfinite == result.num_target_nonfinite == 0
    assert result.num_source_voxels >= result.num_source_keypoints > 0
    assert result.num_target_voxels >= result.num_target_keypoints > 0
    assert result.num_initial_correspondences >= result.num_pruned_correspondences >= result.num_final_inliers
    assert result.num_final_inliers >= kissm.Config().min_inliers and result.max_core_number > 0
    assert result.num_rotation_inliers > 0
    assert result.inlier_ratio == result.num_final_inliers / result.num_initial_correspondences
    assert 0 < result.residual_rms < result.noise_bound == pytest.approx(0.75 * pair.voxel_size)
    for name in TIME_FIELDS:
        assert getattr(result, name) >= 0
    parts = (
        result.time_voxelize_ms
        + result.time_features_ms
        + result.time_matching_ms
        + result.time_pruning_ms
        + result.time_solver_ms
    )
    assert result.time_total_ms == pytest.approx(parts)
    for field in dataclasses.fields(kissm.Result):  # plain Python types, not cdata
        value = getattr(result, field.name)
        assert isinstance(value, (bool, int, float, str, np.ndarray)), field.name
    true_angle = rotation_error_deg(np.eye(3), pair.rotation)
    assert result.has_pose and result.rotation_angle_deg == pytest.approx(true_angle, abs=1.0)


def test_result_is_immutable_and_picklable(result) -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.valid = False  # type: ignore[misc]
    for protocol in range(2, pickle.HIGHEST_PROTOCOL + 1):
        assert_same_result(pickle.loads(pickle.dumps(result, protocol)), result, ignore=set())
    assert_same_result(copy.deepcopy(result), result, ignore=set())


def test_result_to_dict_is_plain(result) -> None:
    import json

    d = result.to_dict()
    assert d["transform"] == result.transform.tolist() and d["num_final_inliers"] == result.num_final_inliers
    json.dumps(d)


def test_result_repr_is_readable(result) -> None:
    text = repr(result)
    assert text.startswith(f"kissm.Result(valid=True, confidence={result.confidence:.3f},\n")
    assert f"{result.num_final_inliers} final inliers of {result.num_initial_correspondences} matches" in text
    assert f"rotation {result.rotation_angle_deg:.2f} deg" in text and "transform=[[" in text
    assert text.endswith("]])")
    assert f"rotation_uncertainty {math.degrees(result.rotation_uncertainty):.3g} deg (the inliers' spread)," in text
    assert len(text.splitlines()) == 8 and max(map(len, text.splitlines())) < 110


def test_invalid_result_keeps_nan_pose_and_reason(pair) -> None:
    flat = np.c_[np.random.default_rng(0).random((2000, 2)) * 10, np.zeros(2000)]  # a plane: no features
    result = kissm.register(flat, flat, voxel_size=0.3)
    assert not result.valid and result.reason_code != 0 and result.reason not in ("", "none")
    if not result.has_pose:
        assert np.isnan(result.transform).all() and math.isnan(result.rotation_angle_deg)
        assert "no pose" in repr(result)
    assert f"valid=False, reason={result.reason!r}" in repr(result)
    pickle.loads(pickle.dumps(result))


def test_module_register_equals_matcher(pair, result) -> None:
    assert_same_result(kissm.register(pair.source, pair.target, voxel_size=pair.voxel_size), result)
    assert_same_result(kissm.register(pair.source, pair.target, pair.voxel_size, num_threads=1), result)
    with pytest.raises(TypeError):
        kissm.register(pair.source, pair.target)  # type: ignore[call-arg]  # voxel_size is required


def test_results_do_not_depend_on_thread_count_or_reuse(pair, result) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=1) as matcher:
        assert_same_result(matcher.register(pair.source, pair.target), result)
        assert_same_result(matcher.register(pair.source, pair.target), result)
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=0) as matcher:
        assert_same_result(matcher.register(pair.source, pair.target), result)


def test_features_path_equals_register(pair, result) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2) as matcher:
        source, target = matcher.compute_features(pair.source), matcher.compute_features(pair.target)
        assert source.num_points == len(pair.source) and source.num_voxels == result.num_source_voxels
        assert source.num_keypoints == result.num_source_keypoints
        assert target.num_keypoints == result.num_target_keypoints
        # the descriptors twice (rows and the search index's copy) are the bulk of it
        assert 2 * 33 * 4 * source.num_keypoints < source.memory_bytes < 1024 * source.num_voxels
        via_features = matcher.register_features(source, target)
    assert_same_result(via_features, result)
    assert via_features.time_voxelize_ms == via_features.time_features_ms == 0.0
    # features outlive their matcher and work with any matcher of the same descriptor settings
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=1, min_inliers=10) as other:
        assert_same_result(other.register_features(source, target), result)
    assert "keypoints" in repr(source)


def test_features_is_a_deprecated_alias_of_compute_features(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2) as matcher:
        expected = matcher.compute_features(pair.source)
        with pytest.warns(DeprecationWarning, match=r"Matcher\.compute_features\(\)") as caught:
            old = matcher.features(pair.source)
        assert len(caught) == 1 and caught[0].filename == __file__  # reported at the caller's line
        assert isinstance(old, kissm.Features)
        assert (old.num_points, old.num_voxels, old.num_keypoints) == (
            expected.num_points,
            expected.num_voxels,
            expected.num_keypoints,
        )
        assert_same_result(matcher.register_features(old, old), matcher.register_features(expected, expected))


def test_features_pickle_through_their_bytes_and_are_not_constructible(pair) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size) as matcher:
        features = matcher.compute_features(pair.source)
    assert pickle.loads(pickle.dumps(features)).to_bytes() == features.to_bytes()  # more in test_features_bytes.py
    with pytest.raises(TypeError, match=r"Matcher\.compute_features"):
        kissm.Features()


def test_matcher_lifecycle(pair) -> None:
    matcher = kissm.Matcher(voxel_size=pair.voxel_size)
    with matcher as entered:
        assert entered is matcher and not matcher.closed
    assert matcher.closed and "(closed)" in repr(matcher)
    matcher.close()  # idempotent
    matcher.cancel()  # harmless
    for call in (lambda: matcher.register(pair.source, pair.target), lambda: matcher.compute_features(pair.source)):
        with pytest.raises(ValueError, match="closed kissm.Matcher"):
            call()
    with pytest.raises(ValueError, match="closed"):
        with matcher:
            pass
    with pytest.raises(ValueError, match="closed"):
        pickle.dumps(matcher)


def test_matcher_pickles_as_its_settings(pair, result) -> None:
    with kissm.Matcher(voxel_size=pair.voxel_size, num_threads=2) as matcher:
        clone = pickle.loads(pickle.dumps(matcher))
    with clone:
        assert clone.config == kissm.Config(voxel_size=pair.voxel_size, num_threads=2)
        assert_same_result(clone.register(pair.source, pair.target), result)


def test_read_points_formats(tmp_path, pair) -> None:
    xyz = pair.source[:500]
    np.save(tmp_path / "a.npy", xyz)
    np.save(tmp_path / "b.npy", np.c_[xyz, np.ones(len(xyz))].astype(np.float32))
    (tmp_path / "c.xyz").write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in xyz.tolist()))
    xyz.astype("<f4").tofile(tmp_path / "d.bin")
    np.c_[xyz, np.zeros(len(xyz))].astype("<f4").tofile(tmp_path / "e.bin")
    assert bits(kissm.read_points(tmp_path / "a.npy")) == bits(xyz)
    assert bits(kissm.read_points(str(tmp_path / "b.npy"))) == bits(xyz.astype(np.float32).astype(np.float64))
    assert bits(kissm.read_points(tmp_path / "c.xyz", format="xyz")) == bits(xyz)  # repr is exact
    as_f32 = xyz.astype(np.float32).astype(np.float64)
    assert bits(kissm.read_points(tmp_path / "d.bin", format="bin_xyz")) == bits(as_f32)
    assert bits(kissm.read_points(tmp_path / "d.bin", format="bin_xyz_f32")) == bits(as_f32)
    assert bits(kissm.read_points(tmp_path / "e.bin")) == bits(as_f32)  # .bin: KITTI x y z intensity
    points = kissm.read_points(tmp_path / "a.npy")
    assert points.flags.c_contiguous and points.flags.writeable and points.flags.owndata
    points[0, 0] = 1.0  # the caller's own copy


def test_version() -> None:
    assert isinstance(kissm.__version__, str) and kissm.__version__.count(".") == 2


def test_result_has_every_field_of_the_c_result() -> None:
    c_fields = {name for name, _ in kissm._ffi.ffi.typeof("kissm_result").fields}
    python_fields = {f.name for f in dataclasses.fields(kissm.Result)}
    assert c_fields - {"struct_size", "reserved0", "reason"} <= python_fields
    assert {"reason", "reason_code"} <= python_fields
