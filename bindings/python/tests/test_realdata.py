# SPDX-License-Identifier: MIT
"""Real scans from ../shared/data (or $KISSM_DATA_DIR): every pair of index.tsv against its ground truth,
and bitwise against the kissm CLI. Skipped when the data is absent."""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

import kissm

from cli_json import assert_matches_cli, run_cli
from conftest import data_dir
from helpers import assert_same_result
from realdata import RealPair, pair_names, read_cached
from testdata import rotation_error_deg

NAMES = pair_names(data_dir()) or ["(no real data)"]
LIDAR_NAMES = pair_names(data_dir(), lidar_only=True) or ["(no real LiDAR data)"]


_RESULTS: dict[str, kissm.Result] = {}


def _register(name: str, pair: RealPair) -> kissm.Result:
    """The Python registration of a pair (computed once, shared by the tests below)."""
    if name not in _RESULTS:
        source, target = read_cached(pair.source, pair.source_format), read_cached(pair.target, pair.target_format)
        _RESULTS[name] = kissm.register(source, target, voxel_size=pair.kind.voxel, num_threads=2)
    return _RESULTS[name]


@pytest.mark.parametrize("name", NAMES)
def test_real_pair_against_ground_truth(real_pairs: dict[str, RealPair], name: str) -> None:
    pair = real_pairs[name]
    result = _register(name, pair)
    assert result.num_source_points == len(read_cached(pair.source, pair.source_format))
    rre = rotation_error_deg(result.rotation, pair.gt[:3, :3]) if result.valid else math.nan
    rte = float(np.linalg.norm(result.translation - pair.gt[:3, 3])) if result.valid else math.nan
    success = result.valid and rre < pair.kind.max_rot_deg and rte < pair.kind.max_trans_m
    if result.valid and result.refine_iterations == 0:  # the rule without refinement, on the measure reported
        assert 0.0 < result.rotation_uncertainty <= kissm.Config().max_rotation_uncertainty, name
        assert math.isnan(result.inlier_coverage)
    elif result.valid:  # declined for its rotation's uncertainty (or valid at one sigma but not at two), then
        # verified by refinement (GICP)
        assert 2.0 * result.rotation_uncertainty > kissm.Config().max_rotation_uncertainty, name
        assert result.inlier_coverage >= kissm.Config().min_inlier_coverage, name
    else:
        assert math.isnan(result.inlier_coverage)
    if pair.kind.must_succeed:
        assert success, f"{name}: {result!r}\nRRE {rre:.3f} deg, RTE {rte:.4f} m"
    else:  # object scans: may give up, must not be confidently wrong
        assert success or not result.valid, f"{name}: valid but wrong (RRE {rre:.3f} deg, RTE {rte:.4f} m)"


#: Refinement may leave the coarse pose's error at most this much worse (degrees, metres): the ground truths
#: are themselves SLAM or ICP estimates good to about this.
REFINE_SLACK_DEG, REFINE_SLACK_M = 0.1, 0.02


@pytest.mark.parametrize("name", LIDAR_NAMES)
def test_real_lidar_pair_refined_with_gicp(real_pairs: dict[str, RealPair], name: str) -> None:
    """Every LiDAR pair as recorded: GICP refinement keeps the pose valid and brings it closer to the ground
    truth than the global solver's, or leaves it within REFINE_SLACK of that."""
    pair = real_pairs[name]
    assert pair.is_lidar
    source, target = read_cached(pair.source, pair.source_format), read_cached(pair.target, pair.target_format)
    result = kissm.register(source, target, voxel_size=pair.kind.voxel, refine="gicp", num_threads=2)
    assert result.valid and result.refined, f"{name}: {result!r}"
    assert np.array_equal(result.coarse_transform, _register(name, pair).transform)  # the solver's pose, unchanged
    coarse_rre = rotation_error_deg(result.coarse_transform[:3, :3], pair.gt[:3, :3])
    coarse_rte = float(np.linalg.norm(result.coarse_transform[:3, 3] - pair.gt[:3, 3]))
    rre = rotation_error_deg(result.rotation, pair.gt[:3, :3])
    rte = float(np.linalg.norm(result.translation - pair.gt[:3, 3]))
    report = f"{name}: coarse {coarse_rre:.3f} deg {coarse_rte:.4f} m, refined {rre:.3f} deg {rte:.4f} m"
    assert rre < coarse_rre + REFINE_SLACK_DEG and rte < coarse_rte + REFINE_SLACK_M, report
    assert rre < pair.kind.max_rot_deg and rte < pair.kind.max_trans_m, report
    assert 0.5 < result.overlap <= 1.0 and result.refine_converged, f"{report}\n{result!r}"
    assert np.linalg.eigvalsh(result.information).min() > 0, report
    # the refined rule's measure; the solver's is reported as without refinement
    assert result.inlier_coverage >= kissm.Config().min_inlier_coverage, report
    assert result.rotation_uncertainty == _register(name, pair).rotation_uncertainty, report


@pytest.mark.parametrize("name", NAMES)
def test_real_pair_bitwise_equals_cli(real_pairs: dict[str, RealPair], cli: Path, name: str) -> None:
    pair = real_pairs[name]
    expected = run_cli(
        cli,
        pair.source,
        pair.target,
        pair.kind.voxel,
        ["--format-src", pair.source_format, "--format-tgt", pair.target_format],
    )
    assert_matches_cli(_register(name, pair), expected)


def test_kitti_float32_points_without_reading_through_the_library(real_pairs: dict[str, RealPair]) -> None:
    """Raw float32 x y z read by numpy and passed in place give the library reader's result."""
    pair = next((p for p in real_pairs.values() if p.source_format == "bin_xyz_f32"), None)
    if pair is None:
        pytest.skip("no bin_xyz_f32 pair")
    source = np.fromfile(pair.source, dtype="<f4").reshape(-1, 3)
    target = np.fromfile(pair.target, dtype="<f4").reshape(-1, 3)
    result = kissm.register(source, target, voxel_size=pair.kind.voxel, num_threads=2)
    assert_same_result(result, _register(pair.name, pair))


def test_kitti_xyzi_columns_in_place(real_pairs: dict[str, RealPair]) -> None:
    """KITTI x y z intensity rows: xyzi[:, :3] is read in place (stride 16 bytes)."""
    pair = next((p for p in real_pairs.values() if p.source_format == "kitti_bin_xyzi_f32"), None)
    if pair is None:
        pytest.skip("no kitti_bin_xyzi_f32 pair")
    source = np.fromfile(pair.source, dtype="<f4").reshape(-1, 4)
    target = np.fromfile(pair.target, dtype="<f4").reshape(-1, 4)
    assert np.shares_memory(kissm.as_point_array(source[:, :3]), source)
    result = kissm.register(source[:, :3], target[:, :3], voxel_size=pair.kind.voxel, num_threads=2)
    assert_same_result(result, _register(pair.name, pair))


def test_cli_is_runnable(cli: Path) -> None:
    done = subprocess.run([str(cli), "--version"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and kissm.__version__ in done.stdout
