# SPDX-License-Identifier: MIT
"""The viewpoint-free modes on real scans (../shared/data, skipped when absent): clouds given in frames far from
their sensors, scan-to-map in a world frame, and exact georeferenced shifts (docs/design/frames.md)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import kissm

from conftest import data_dir
from realdata import RealPair, pair_names, read_cached
from testdata import rotation_error_deg

MODES = ["sign_free", "local"]
NAMES = pair_names(data_dir()) or ["(no real data)"]


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def _frame(rng: np.random.Generator, distance: float) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = _axis_angle(rng.normal(size=3), rng.uniform(0.5, math.pi))
    step = rng.normal(size=3)
    t[:3, 3] = step / np.linalg.norm(step) * distance
    return t


def _apply(t: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ t[:3, :3].T + t[:3, 3]


def _errors(result: kissm.Result, truth: np.ndarray, at: np.ndarray) -> tuple[float, float]:
    """Rotation error (degrees) and the distance between where the result and the truth put the point `at`."""
    t = result.transform
    return rotation_error_deg(t[:3, :3], truth[:3, :3]), float(np.linalg.norm(_apply(t, at) - _apply(truth, at)))


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", NAMES)
def test_moved_frames(real_pairs: dict[str, RealPair], name: str, mode: str) -> None:
    """Each cloud in a frame of its own, 40-80 m (LiDAR; 80-160 voxels otherwise) from its sensor and turned:
    LiDAR registers as in the sensor frames, and no pair is ever valid and wrong."""
    pair = real_pairs[name]
    rng = np.random.default_rng(sum(map(ord, name)))
    scale = 1.0 if pair.is_lidar else 2.0 * pair.kind.voxel
    fs, ft = _frame(rng, rng.uniform(40, 80) * scale), _frame(rng, rng.uniform(40, 80) * scale)
    source = _apply(fs, read_cached(pair.source, pair.source_format))
    target = _apply(ft, read_cached(pair.target, pair.target_format))
    truth = ft @ pair.gt @ np.linalg.inv(fs)
    r = kissm.register(source, target, voxel_size=pair.kind.voxel, num_threads=2, viewpoint_mode=mode)
    rre, rte = _errors(r, truth, source.mean(axis=0))
    right = rre < pair.kind.max_rot_deg and rte < pair.kind.max_trans_m
    report = f"{name} ({mode}): valid {r.valid}, {rre:.3f} deg, {rte:.4f} m, {r.num_final_inliers} inliers"
    assert right or not r.valid, report
    if pair.is_lidar:
        assert r.valid and right, report


def _keyframes(real_data: Path) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The KITTI 07 keyframes (sensor frames) and their world poses, chained from keyframe 0."""
    root = real_data / "kitti07_keyframes_gtsam_points"
    if not root.is_dir():
        pytest.skip(f"no KITTI 07 keyframes under {real_data}")
    chain = [np.eye(4)]
    for k in range(1, 5):
        chain.append(chain[-1] @ np.loadtxt(root / "pairs" / f"{k - 1:06d}__{k:06d}" / "gt_T_target_source.txt"))
    return chain, [read_cached(root / f"{k:06d}" / "points.bin", "bin_xyz") for k in range(5)]


@pytest.mark.parametrize("mode", MODES)
def test_scan_to_map_in_world_frame(real_data: Path, mode: str) -> None:
    """Each KITTI 07 keyframe, in its sensor frame, against the other four merged in the world frame."""
    chain, clouds = _keyframes(real_data)
    for k in range(5):
        world_map = np.concatenate([_apply(chain[j], clouds[j]) for j in range(5) if j != k])
        r = kissm.register(clouds[k], world_map, voxel_size=0.5, num_threads=2, viewpoint_mode=mode)
        rre, rte = _errors(r, chain[k], clouds[k].mean(axis=0))
        assert r.valid and rre < 5.0 and rte < 2.0, f"keyframe {k} ({mode}): {rre:.3f} deg, {rte:.4f} m, {r!r}"


@pytest.mark.parametrize("mode", MODES)
def test_map_described_once_serves_every_scan(real_data: Path, mode: str) -> None:
    """A map (keyframes 0, 2, 4 in the world frame) described once; keyframes 1 and 3 registered against it from
    their features: right, and bitwise what a full registration against the map gives."""
    chain, clouds = _keyframes(real_data)
    world_map = np.concatenate([_apply(chain[j], clouds[j]) for j in (0, 2, 4)])
    with kissm.Matcher(voxel_size=0.5, num_threads=2, viewpoint_mode=mode) as matcher:
        map_features = matcher.compute_features(world_map)
        assert map_features.memory_bytes > 264 * map_features.num_keypoints
        for k in (1, 3):
            reused = matcher.register_features(matcher.compute_features(clouds[k]), map_features)
            full = matcher.register(clouds[k], world_map)
            assert np.array_equal(reused.transform, full.transform), k
            assert reused.num_final_inliers == full.num_final_inliers and reused.valid == full.valid, k
            rre, rte = _errors(reused, chain[k], clouds[k].mean(axis=0))
            assert reused.valid and rre < 2.0 and rte < 0.5, f"keyframe {k} ({mode}): {rre:.3f} deg, {rte:.4f} m"


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("seed", [1, 2])
def test_map_to_map_in_far_apart_world_frames(real_data: Path, mode: str, seed: int) -> None:
    """Two merged maps, keyframes 0-2 and keyframes 3-4 (they overlap where keyframes 2 and 3 do), each in a world
    frame of its own: turned about a random axis and 300-800 m from the other's origin."""
    chain, clouds = _keyframes(real_data)
    rng = np.random.default_rng(seed)
    frame_a, frame_b = _frame(rng, rng.uniform(300, 800)), _frame(rng, rng.uniform(300, 800))
    map_a = np.concatenate([_apply(frame_a @ chain[j], clouds[j]) for j in (0, 1, 2)])
    map_b = np.concatenate([_apply(frame_b @ chain[j], clouds[j]) for j in (3, 4)])
    truth = frame_a @ np.linalg.inv(frame_b)  # map b's frame into map a's
    r = kissm.register(map_b, map_a, voxel_size=0.5, num_threads=2, viewpoint_mode=mode)
    rre, rte = _errors(r, truth, map_b.mean(axis=0))
    assert r.valid and rre < 2.0 and rte < 0.5, f"seed {seed} ({mode}): {rre:.3f} deg, {rte:.4f} m, {r!r}"


@pytest.mark.parametrize("mode", MODES)
def test_exact_georeferenced_shift_is_bitwise(real_pairs: dict[str, RealPair], mode: str) -> None:
    """LiDAR scans (float32 coordinates) moved by whole metres up to 1e7 are exact in float64: the library sees
    the same recentred clouds, so rotation, counts and errors are bitwise those of the unshifted pair."""
    lidar = [p for p in real_pairs.values() if p.is_lidar]
    if not lidar:
        pytest.skip("no LiDAR pairs in the data")
    shift = np.array([1e7, -3e6, 250.0])
    for pair in lidar[:3]:
        source, target = read_cached(pair.source, pair.source_format), read_cached(pair.target, pair.target_format)
        assert np.array_equal(source.astype(np.float32).astype(np.float64), source)  # exact after the shift
        a = kissm.register(source, target, voxel_size=pair.kind.voxel, num_threads=2, viewpoint_mode=mode)
        b = kissm.register(
            source + shift, target + shift, voxel_size=pair.kind.voxel, num_threads=2, viewpoint_mode=mode
        )
        assert np.array_equal(a.rotation, b.rotation), pair.name
        assert (a.valid, a.num_final_inliers, a.num_source_keypoints) == (
            b.valid,
            b.num_final_inliers,
            b.num_source_keypoints,
        ), pair.name
        # t' = t + s - R s
        np.testing.assert_allclose(b.translation, a.translation + shift - a.rotation @ shift, rtol=0, atol=1e-6)
