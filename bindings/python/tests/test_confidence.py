# SPDX-License-Identifier: MIT
"""Result.confidence: the probability that the pose is within the success tolerance, the documented logistic
function of the result's own numbers (docs/design/accuracy.md, "Confidence"): high for right poses of the committed
pair by every entry point, near 0 for a refinement left a voxel away from the truth and for a pose with a competitor
as good, exactly 0 without a pose, and the same bits through features."""

from __future__ import annotations

import math

import numpy as np
import pytest

import kissm

import testdata

VOXEL = testdata.VOXEL_SIZE


def logistic(z: float) -> float:
    return 1.0 / (1.0 + math.exp(-z))


def documented(r: kissm.Result, voxel: float) -> float:
    """docs/design/accuracy.md, "Confidence": the three models, with the coefficients it lists."""
    if not r.has_pose:
        return 0.0
    if r.num_initial_correspondences == 0:  # refined from a prior
        return logistic(1.30069 + 15.6705 * r.overlap - 24.144 * min(r.refine_rmse / voxel, 10.0))
    inliers = math.log1p(r.num_final_inliers)
    if r.refined:
        rmse = min(r.refine_rmse / voxel, 10.0)
        evidence = logistic(-5.656 + 1.76257 * inliers + 8.02222 * r.overlap - 4.89573 * rmse)
        pick = 30.0 / 110.0
    else:
        evidence = logistic(-3.93451 + 2.65136 * inliers)
        pick = 4.0 / 46.0
    competed = min(max((r.ambiguity - 0.6) / 0.2, 0.0), 1.0)
    return evidence * (1.0 - (1.0 - pick) * competed)


@pytest.mark.parametrize("refine", ["none", "gicp", "point_to_plane"])
def test_a_right_registration_is_confident(pair, refine: str) -> None:
    with kissm.Matcher(voxel_size=VOXEL, num_threads=2, refine_mode=refine) as matcher:
        result = matcher.register(pair.source, pair.target)
        through_features = matcher.register_features(
            matcher.compute_features(pair.source), matcher.compute_features(pair.target)
        )
    assert result.valid and result.confidence >= 0.95, result
    assert result.confidence == pytest.approx(documented(result, VOXEL), abs=1e-12)
    assert np.float64(through_features.confidence).tobytes() == np.float64(result.confidence).tobytes()


def test_a_refinement_from_a_prior(pair) -> None:
    with kissm.Matcher(voxel_size=VOXEL, num_threads=2, refine_mode="gicp") as matcher:
        near = matcher.refine(pair.source, pair.target, pair.transform)
        # Four voxels off along x: the refinement's own basin edge on this yard.
        start = pair.transform.copy()
        start[0, 3] += 4 * VOXEL
        far = matcher.refine(pair.source, pair.target, start)
    assert near.valid and near.confidence >= 0.95
    assert near.confidence == pytest.approx(documented(near, VOXEL), abs=1e-12)
    assert far.confidence == pytest.approx(documented(far, VOXEL), abs=1e-12)
    # The farther refinement's residual is larger, so its confidence is lower: the model falls with the residual.
    assert (far.refine_rmse > near.refine_rmse) == (far.confidence < near.confidence)


def test_without_a_pose_it_is_zero() -> None:
    flat = np.c_[np.random.default_rng(0).random((2000, 2)) * 10, np.zeros(2000)]  # a plane: no features
    result = kissm.register(flat, flat, 0.25)
    assert not result.has_pose and result.confidence == 0.0


def test_the_confidence_reads_no_threshold(pair) -> None:
    # The committed pair itself under a bound that refuses its competitor: the confidence does not depend on the
    # bound, only on the numbers.
    base = kissm.register(pair.source, pair.target, VOXEL, num_threads=2)
    strict = kissm.register(pair.source, pair.target, VOXEL, num_threads=2, max_ambiguity=0.0)
    assert not strict.valid and strict.confidence == base.confidence
