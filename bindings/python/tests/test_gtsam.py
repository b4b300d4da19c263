# SPDX-License-Identifier: MIT
"""Result.information in GTSAM, as the docs say to use it: a BetweenFactorPose3 from the target's pose to the
source's, measured ``Pose3(result.transform)``, noise ``noiseModel.Gaussian.Information(result.information)``.
Its error vanishes at the refined pose and is ``0.5 xi^T I xi`` at ``transform * Expmap(xi)``; GTSAM's marginal
covariance of the source pose is ``inv(information)``; and the information the library gives for the same
source cloud in another frame is what GTSAM's pose algebra makes of it. Together these pin the order (rotation
first), the side of the perturbation (right) and the frame (the source's) to GTSAM's Pose3 conventions."""

from __future__ import annotations

import numpy as np
import pytest

import kissm

import testdata
from testdata import pose, rotation_zyx

gtsam = pytest.importorskip(
    "gtsam", reason="gtsam is not installed (the test extra installs gtsam 4.3.0 on Linux x86_64, Python >= 3.11)"
)

VOXEL = testdata.VOXEL_SIZE
TARGET, SOURCE = 0, 1
#: The target scan's pose in some world frame: anything, the relative pose and its information do not care.
WORLD_TARGET = pose(rotation_zyx(23.0, -11.0, 4.0), [10.0, -3.0, 2.0])
#: Standard deviation of the prior that pins the target: small enough to leave inv(information) to 1e-5.
PINNED = 1e-7


@pytest.fixture(scope="module")
def refined(pair) -> kissm.Result:
    result = kissm.register(pair.source, pair.target, voxel_size=VOXEL, refine="gicp")
    assert result.valid and result.refined
    return result


def between(result: kissm.Result) -> object:
    """The factor the Result.information docstring shows."""
    noise = gtsam.noiseModel.Gaussian.Information(result.information)
    return gtsam.BetweenFactorPose3(TARGET, SOURCE, gtsam.Pose3(result.transform), noise)


def values(**poses: np.ndarray) -> object:
    out = gtsam.Values()
    for key, matrix in poses.items():
        out.insert({"target": TARGET, "source": SOURCE}[key], gtsam.Pose3(matrix))
    return out


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def test_factor_error_is_zero_at_the_refined_pose_and_the_information_form_around_it(refined) -> None:
    factor = between(refined)
    source = WORLD_TARGET @ refined.transform
    assert factor.error(values(target=WORLD_TARGET, source=source)) < 1e-20
    rng = np.random.default_rng(5)
    for _ in range(5):
        xi = np.r_[rng.normal(scale=2e-3, size=3), rng.normal(scale=2e-2, size=3)]  # radians, then metres
        moved = source @ gtsam.Pose3.Expmap(xi).matrix()  # perturbed on the right, in the source's frame
        here = values(target=WORLD_TARGET, source=moved)
        assert np.allclose(factor.unwhitenedError(here), xi, rtol=1e-9, atol=1e-15)
        assert factor.error(here) == pytest.approx(0.5 * xi @ refined.information @ xi, rel=1e-9)


def test_marginal_covariance_is_the_inverse_information(refined) -> None:
    graph = gtsam.NonlinearFactorGraph()
    graph.add(gtsam.PriorFactorPose3(TARGET, gtsam.Pose3(WORLD_TARGET), gtsam.noiseModel.Isotropic.Sigma(6, PINNED)))
    graph.add(between(refined))
    estimate = values(target=WORLD_TARGET, source=WORLD_TARGET @ refined.transform)
    covariance = gtsam.Marginals(graph, estimate).marginalCovariance(SOURCE)
    assert relative_error(covariance, np.linalg.inv(refined.information)) < 1e-5


def test_information_of_the_source_in_another_frame_agrees_through_gtsam(pair, refined) -> None:
    """The source cloud given in a frame moved by ``shift`` (a translation keeps the voxel grid) is refined
    with its own information. The original source pose is that one composed with ``shift^-1``; GTSAM's adjoint
    carries the first covariance over to it, and the result is ``inv(information)`` of the original."""
    shift = pose(np.eye(3), [8.0, -4.0, 2.0])
    with kissm.Matcher(voxel_size=VOXEL, refine_mode="gicp") as matcher:
        elsewhere = matcher.refine(pair.source - shift[:3, 3], pair.target, refined.transform @ shift)
        again = matcher.refine(pair.source, pair.target, refined.transform)
    assert elsewhere.valid and again.valid
    assert relative_error(elsewhere.information, again.information) > 0.1  # another frame, another matrix
    # X exp(xi) shift^-1 = (X shift^-1) exp(Ad(shift) xi): the covariance moves by Ad(shift)
    adjoint = gtsam.Pose3(shift).AdjointMap()
    carried = adjoint @ np.linalg.inv(elsewhere.information) @ adjoint.T
    assert relative_error(carried, np.linalg.inv(again.information)) < 1e-9
