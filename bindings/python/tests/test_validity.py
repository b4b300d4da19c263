# SPDX-License-Identifier: MIT
"""The validity rules and their measures: Result.rotation_uncertainty (without refinement, against
Config.max_rotation_uncertainty), Result.inlier_coverage (with refinement, against Config.min_inlier_coverage),
Config.refine_min_inliers against min_inliers, Result.refine_condition against Config.min_refine_condition,
convergence, and what a refinement from a prior reports. Each setting is
moved to the value the committed pair measures and one step past it: the decision flips there, in its own rule
only, and the pose is kept for inspection."""

from __future__ import annotations

import math

import numpy as np
import pytest

import kissm
from kissm import _ffi

import testdata
from helpers import TIME_FIELDS, assert_same_result, bits

VOXEL = testdata.VOXEL_SIZE
UNCERTAIN_ROTATION = "the inliers leave the rotation uncertain"
CLUSTERED_INLIERS = "the inliers cover too little of the overlap"
UNCONSTRAINED = "the refined pose is not constrained in every direction"
NOT_CONVERGED = "refinement did not converge"


@pytest.fixture(scope="module")
def coarse(pair) -> kissm.Result:
    return kissm.register(pair.source, pair.target, VOXEL, num_threads=2)


@pytest.fixture(scope="module")
def refined(pair) -> kissm.Result:
    return kissm.register(pair.source, pair.target, VOXEL, refine="gicp", num_threads=2)


def test_reason_codes_and_strings() -> None:
    assert _ffi.lib.KISSM_REASON_UNCERTAIN_ROTATION == 9 and _ffi.lib.KISSM_REASON_CLUSTERED_INLIERS == 10
    assert _ffi.lib.KISSM_REASON_NOT_CONVERGED == 11
    assert _ffi.text(_ffi.lib.kissm_reason_string(8)) == UNCONSTRAINED
    assert _ffi.text(_ffi.lib.kissm_reason_string(9)) == UNCERTAIN_ROTATION
    assert _ffi.text(_ffi.lib.kissm_reason_string(10)) == CLUSTERED_INLIERS
    assert _ffi.text(_ffi.lib.kissm_reason_string(11)) == NOT_CONVERGED


def test_rotation_uncertainty_is_the_documented_measure(coarse, refined) -> None:
    """noise_bound / sqrt(N (e1^2 + e2^2)) over the final inliers, in radians; the same with refinement (it is
    the solver's); within the default threshold here, since the pose is valid."""
    assert coarse.valid and refined.valid
    extent = coarse.inlier_extent
    expected = coarse.noise_bound / math.sqrt(coarse.num_final_inliers * (extent[1] ** 2 + extent[2] ** 2))
    assert coarse.rotation_uncertainty == pytest.approx(expected, rel=1e-12)
    # 73 inliers spread over metres with a 0.19 m bound: about half a degree on this pair
    assert 0.05 < math.degrees(coarse.rotation_uncertainty) < 2.0
    assert coarse.rotation_uncertainty <= kissm.Config().max_rotation_uncertainty
    assert bits(refined.rotation_uncertainty) == bits(coarse.rotation_uncertainty)
    assert math.isnan(coarse.inlier_coverage)  # not refined


def test_inlier_coverage_is_the_inliers_spread_over_the_overlaps(pair, refined) -> None:
    """inlier_extent[0] over the principal standard deviation of the source voxels the refined pose overlaps."""
    coverage = refined.inlier_coverage
    assert 0.0 < coverage <= 1.5 and coverage >= kissm.Config().min_inlier_coverage
    # the overlapped voxels' spread, as Python measures it: within a voxel's rounding of the library's
    spread = refined.inlier_extent[0] / coverage
    points = pair.source @ refined.rotation.T + refined.translation
    all_extent = math.sqrt(float(np.linalg.eigvalsh(np.cov(points.T, bias=True)).max()))
    assert 0.5 * all_extent < spread <= 1.05 * all_extent  # the overlap (87 % of the voxels) spans most of it
    # the same solver inliers over the same overlapped voxels seen from the other cost's pose (about 0.02 degrees
    # and 4 mm away since refinement fits its own planes, refine_normal_radius_gain): the spread agrees to 1e-3
    p2p = kissm.register(pair.source, pair.target, VOXEL, refine="point_to_plane").inlier_coverage
    assert math.isclose(p2p, coverage, rel_tol=1e-3), (p2p, coverage)


def test_max_rotation_uncertainty_decides_without_refinement(pair, coarse) -> None:
    measured = coarse.rotation_uncertainty
    at = kissm.register(pair.source, pair.target, VOXEL, max_rotation_uncertainty=measured)
    assert at.valid  # the rule is <=
    below = kissm.register(pair.source, pair.target, VOXEL, max_rotation_uncertainty=np.nextafter(measured, 0.0))
    assert not below.valid and below.reason_code == _ffi.lib.KISSM_REASON_UNCERTAIN_ROTATION
    assert below.reason == UNCERTAIN_ROTATION and f"reason={UNCERTAIN_ROTATION!r}" in repr(below)
    assert_same_result(below, coarse, ignore=TIME_FIELDS | {"valid", "reason", "reason_code"})  # pose kept
    # with refinement it is not a rule
    tight = kissm.register(pair.source, pair.target, VOXEL, refine="gicp", max_rotation_uncertainty=measured / 100)
    assert tight.valid and tight.rotation_uncertainty == measured


def test_min_inlier_coverage_decides_with_refinement(pair, coarse, refined) -> None:
    measured = refined.inlier_coverage
    at = kissm.register(pair.source, pair.target, VOXEL, refine="gicp", min_inlier_coverage=measured)
    assert at.valid  # the rule is >=
    above = kissm.register(
        pair.source, pair.target, VOXEL, refine="gicp", min_inlier_coverage=np.nextafter(measured, 1.0)
    )
    assert not above.valid and above.reason_code == _ffi.lib.KISSM_REASON_CLUSTERED_INLIERS
    assert above.reason == CLUSTERED_INLIERS and f"reason={CLUSTERED_INLIERS!r}" in repr(above)
    assert_same_result(above, refined, ignore=TIME_FIELDS | {"valid", "reason", "reason_code"})  # pose kept
    # without refinement there is no coverage and it is not a rule
    plain = kissm.register(pair.source, pair.target, VOXEL, min_inlier_coverage=1.0)
    assert plain.valid and math.isnan(plain.inlier_coverage)
    assert_same_result(plain, coarse)


def test_refine_min_inliers_replaces_min_inliers_with_refinement(pair, coarse, refined) -> None:
    n = refined.num_final_inliers
    assert n == coarse.num_final_inliers and n >= kissm.Config().refine_min_inliers
    assert kissm.register(pair.source, pair.target, VOXEL, refine="gicp", refine_min_inliers=n).valid
    few = kissm.register(pair.source, pair.target, VOXEL, refine="gicp", refine_min_inliers=n + 1)
    assert not few.valid and few.reason_code == _ffi.lib.KISSM_REASON_TOO_FEW_INLIERS
    assert_same_result(few, refined, ignore=TIME_FIELDS | {"valid", "reason", "reason_code"})
    # min_inliers is the rule without refinement only, and refine_min_inliers only with it
    assert kissm.register(pair.source, pair.target, VOXEL, refine="gicp", min_inliers=n + 1).valid
    assert kissm.register(pair.source, pair.target, VOXEL, refine_min_inliers=100000).valid
    unrefined = kissm.register(pair.source, pair.target, VOXEL, min_inliers=n + 1)
    assert not unrefined.valid and unrefined.reason_code == _ffi.lib.KISSM_REASON_TOO_FEW_INLIERS


def test_min_refine_condition_decides_with_refinement_and_from_a_prior(pair, coarse, refined) -> None:
    measured = refined.refine_condition
    assert measured >= kissm.Config().min_refine_condition
    assert kissm.register(pair.source, pair.target, VOXEL, refine="gicp", min_refine_condition=measured).valid
    above = kissm.register(
        pair.source, pair.target, VOXEL, refine="gicp", min_refine_condition=np.nextafter(measured, 1.0)
    )
    assert not above.valid and above.reason_code == _ffi.lib.KISSM_REASON_UNCONSTRAINED
    assert above.reason == UNCONSTRAINED
    assert_same_result(above, refined, ignore=TIME_FIELDS | {"valid", "reason", "reason_code"})
    assert_same_result(kissm.register(pair.source, pair.target, VOXEL, min_refine_condition=1.0), coarse)
    # the rule of a refinement from a prior too
    prior = kissm.refine(pair.source, pair.target, pair.transform, VOXEL)
    assert prior.valid
    strict = kissm.refine(
        pair.source, pair.target, pair.transform, VOXEL, min_refine_condition=np.nextafter(prior.refine_condition, 1)
    )
    assert not strict.valid and strict.reason_code == _ffi.lib.KISSM_REASON_UNCONSTRAINED


def test_a_refinement_stopped_by_its_cap_is_not_valid(pair) -> None:
    """From 8 degrees and 1 m off, one iteration cannot converge: the pose is refused (and kept); with the
    default cap the same start converges to the truth."""
    start = testdata.pose(testdata.rotation_zyx(8.0), [1.0, 0.0, 0.0]) @ pair.transform
    capped = kissm.refine(pair.source, pair.target, start, VOXEL, refine_max_iterations=1)
    assert capped.refine_iterations == 1 and not capped.refine_converged
    assert not capped.valid and capped.reason_code == _ffi.lib.KISSM_REASON_NOT_CONVERGED
    assert capped.reason == NOT_CONVERGED and capped.has_pose
    done = kissm.refine(pair.source, pair.target, start, VOXEL)
    assert done.valid and done.refine_converged
    assert testdata.rotation_error_deg(done.rotation, pair.rotation) < 0.1


def test_refinement_from_a_prior_has_no_solver_measures(pair) -> None:
    """kissm.refine runs no solver: neither measure exists and neither setting (nor refine_min_inliers) counts."""
    result = kissm.refine(pair.source, pair.target, pair.transform, VOXEL)
    assert result.valid and result.refined
    assert math.isnan(result.rotation_uncertainty) and math.isnan(result.inlier_coverage)
    strict = kissm.refine(
        pair.source,
        pair.target,
        pair.transform,
        VOXEL,
        max_rotation_uncertainty=1e-9,
        min_inlier_coverage=1.0,
        refine_min_inliers=100000,
    )
    assert_same_result(strict, result)
    assert "rotation_uncertainty" not in repr(result)


def test_without_a_pose_neither_measure_exists() -> None:
    """A cloud within one voxel: no descriptors, no solver pose, so no rotation uncertainty (NaN, not inf)."""
    blob = np.random.default_rng(1).random((500, 3)) * 0.25
    result = kissm.register(blob, blob, 0.3, refine="gicp")
    assert not result.valid and result.reason_code == _ffi.lib.KISSM_REASON_TOO_FEW_VOXELS and not result.has_pose
    assert math.isnan(result.rotation_uncertainty) and math.isnan(result.inlier_coverage)
    assert "rotation_uncertainty" not in repr(result)


def test_repr_shows_the_measures(coarse, refined) -> None:
    lines = repr(coarse).splitlines()
    assert lines[2].strip() == (
        f"rotation_uncertainty {math.degrees(coarse.rotation_uncertainty):.3g} deg (the inliers' spread),"
    )
    text = repr(refined)
    assert (
        f"rotation_uncertainty {math.degrees(refined.rotation_uncertainty):.3g} deg, "
        f"inlier_coverage {refined.inlier_coverage:.3f} (the inliers' spread)," in text
    )


@pytest.mark.parametrize("mode", ["none", "gicp", "point_to_plane"])
def test_valid_poses_are_right_on_the_variations(pairs, mode: str) -> None:
    """Over the committed pair and its moved, shuffled and noisy copies, a valid pose is the true one. (One
    copy's solver pose is 90 degrees off, with inliers that pin the rotation down no better than 2.5 degrees
    and cover an eighth of the overlap: the rule of each mode must refuse it.)"""
    solved = 0
    for pair in pairs:
        result = kissm.register(pair.source, pair.target, VOXEL, refine=mode, num_threads=2)
        if result.valid:
            rre = testdata.rotation_error_deg(result.rotation, pair.rotation)
            rte = float(np.linalg.norm(result.translation - pair.translation))
            assert rre < 1.0 and rte < 0.2, (mode, rre, rte, result)
            solved += 1
    assert solved >= len(pairs) // 2
