# SPDX-License-Identifier: MIT
"""``kissm.Result``: a plain, picklable copy of ``kissm_result``."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ._ffi import ffi, lib, text

_COUNT_FIELDS = (
    "num_source_points",
    "num_target_points",
    "num_source_nonfinite",
    "num_target_nonfinite",
    "num_source_voxels",
    "num_target_voxels",
    "num_source_keypoints",
    "num_target_keypoints",
    "num_initial_correspondences",
    "num_pruned_correspondences",
    "num_rotation_inliers",
    "num_final_inliers",
    "max_core_number",
    "num_refine_correspondences",
    "refine_iterations",
    "num_source_suppressed",
    "num_target_suppressed",
)
_FLOAT_FIELDS = (
    "inlier_ratio",
    "residual_rms",
    "noise_bound",
    "overlap",
    "refine_rmse",
    "refine_condition",
    "rotation_uncertainty",
    "inlier_coverage",
    "tilt",
    "ambiguity",
    "confidence",
    "voxel_size_used",
)
_TIME_FIELDS = (
    "time_voxelize_ms",
    "time_features_ms",
    "time_matching_ms",
    "time_pruning_ms",
    "time_solver_ms",
    "time_total_ms",
    "time_refine_ms",
    "time_suppression_ms",
)


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation between the rotation blocks of two 4x4 transforms, in degrees."""
    cos = (float(np.trace(a[:3, :3].T @ b[:3, :3])) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cos))))


def _sigmas(information: np.ndarray) -> tuple[float, float]:
    """Standard deviations by an information matrix: (rotation in degrees, translation), each the root of the
    summed variances of its three components; NaN when it is NaN or not positive definite."""
    try:
        variances = np.diag(np.linalg.inv(information))
    except np.linalg.LinAlgError:
        return math.nan, math.nan
    if not (variances >= 0).all():
        return math.nan, math.nan
    return math.degrees(math.sqrt(float(variances[:3].sum()))), math.sqrt(float(variances[3:].sum()))


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Result:
    """The outcome of a registration: the pose, whether it can be trusted, and every number behind that.

    ``transform`` maps source points into the target frame: ``p_target = rotation @ p_source + translation``
    (or ``(transform @ [x, y, z, 1])[:3]``). When no pose was estimated it is all NaN; when ``valid`` is
    False but a pose was estimated it is kept for inspection, and ``reason`` says why it is not trusted.
    Counts and per-stage wall-clock times (milliseconds) are those of the C ``kissm_result``; the times are
    the only fields that differ between identical calls.

    With refinement (``Config.refine_mode``, ``register(..., refine="gicp")``, :meth:`Matcher.refine`),
    ``transform`` is the refined pose, ``coarse_transform`` the one refinement started from, and
    ``information``, ``overlap``, ``refine_rmse`` and ``refine_condition`` describe the refined pose; without
    it they are NaN (``refined`` is False) and the refinement counts are 0.

    ``valid`` follows one of two rules. Without refinement: at least ``Config.min_inliers`` final inliers, not
    collinear or planar, and ``rotation_uncertainty`` <= ``Config.max_rotation_uncertainty``. With it: at least
    ``Config.refine_min_inliers``, not collinear or planar, ``overlap`` >= ``Config.min_overlap``,
    ``inlier_coverage`` >= ``Config.min_inlier_coverage``, ``refine_condition`` >= ``Config.min_refine_condition``
    (a pose constrained in every direction), a refinement that converged (``refine_converged``) and clouds it
    left within ``Config.max_refine_rmse_gain`` voxels of each other (``refine_rmse``). :meth:`Matcher.refine`
    checks only the overlap, the condition, the convergence and the residual. With ``Config.allow_degenerate``
    the condition is no rule: a pose that leaves directions free may be valid, flagged ``degenerate``.
    """

    valid: bool
    """Whether the pose can be trusted (C ``valid``); see ``reason`` and the counts."""
    reason: str
    """The library's text for ``reason_code`` (``"none"`` when valid)."""
    reason_code: int
    """Why the pose is not trusted: a ``KISSM_REASON_*`` value (C ``reason``); 0 when valid."""
    transform: np.ndarray
    """(4, 4) float64: maps source points into the target frame; all NaN when no pose was estimated."""
    rotation: np.ndarray
    """(3, 3) float64: the rotation part of ``transform``."""
    translation: np.ndarray
    """(3,) float64: the translation part of ``transform``."""
    num_source_points: int
    """Source points given."""
    num_target_points: int
    """Target points given."""
    num_source_nonfinite: int
    """Source points dropped as non-finite (``nonfinite_policy='drop'``)."""
    num_target_nonfinite: int
    """Target points dropped as non-finite (``nonfinite_policy='drop'``)."""
    num_source_voxels: int
    """Occupied source voxels."""
    num_target_voxels: int
    """Occupied target voxels."""
    num_source_keypoints: int
    """Source voxels with a descriptor."""
    num_target_keypoints: int
    """Target voxels with a descriptor."""
    num_initial_correspondences: int
    """Mutual, ratio-tested, capped descriptor matches."""
    num_pruned_correspondences: int
    """Matches in the maximum k-core of the compatibility graph."""
    num_rotation_inliers: int
    """Pruned matches the rotation solver kept."""
    num_final_inliers: int
    """Pruned matches within the solver bound after rotation and translation."""
    max_core_number: int
    """k of the maximum k-core."""
    inlier_ratio: float
    """``num_final_inliers / num_initial_correspondences`` (0 when there are no matches)."""
    residual_rms: float
    """RMS distance over the final inliers, in the clouds' unit (NaN when there are none)."""
    noise_bound: float
    """The solver's inlier bound, in the clouds' unit."""
    inlier_extent: np.ndarray
    """(3,) float64: square roots of the eigenvalues (descending) of the inliers' source covariance."""
    time_voxelize_ms: float
    """Milliseconds spent on input checks, recentring and voxelisation."""
    time_features_ms: float
    """Milliseconds spent on neighbour search, normals and FPFH descriptors."""
    time_matching_ms: float
    """Milliseconds spent on descriptor matching."""
    time_pruning_ms: float
    """Milliseconds spent on the compatibility graph and its maximum k-core."""
    time_solver_ms: float
    """Milliseconds spent on rotation, translation, inliers and validity."""
    time_total_ms: float
    """The sum of the stage times (``time_refine_ms`` included), in milliseconds."""
    coarse_transform: np.ndarray
    """(4, 4) float64: the pose refinement started from: the global solver's, or for :meth:`Matcher.refine` the
    ``initial`` transform. Equal to ``transform`` when no refinement ran; all NaN when no pose was estimated."""
    information: np.ndarray
    """(6, 6) float64, symmetric: the information matrix (inverse covariance) of the refined pose; all NaN when
    refinement did not run.

    Rows and columns are rotation (radians) then translation (the clouds' unit) of the error ``xi`` in
    ``T_true = transform @ expm(hat(xi))``: a perturbation on the right, in the source's frame. That is GTSAM's
    ``Pose3`` convention, so it is a between factor as it stands (with ``transform`` = pose of the source in
    the target's frame)::

        gtsam.BetweenFactorPose3(target_key, source_key, gtsam.Pose3(result.transform),
                                 gtsam.noiseModel.Gaussian.Information(result.information))

    (g2o orders translation first: swap the 3x3 blocks.) It is the Gauss-Newton information of the refinement's
    point-to-plane cost over a calibrated variance (12 times the square of the residuals' robust spread, as
    neighbouring voxels are not independent measurements), measured against the truth on simulated and real
    scans (``docs/design/accuracy.md``): use it as it is. A small eigenvalue marks a direction the data leaves
    free (see ``refine_condition``)."""
    overlap: float
    """Share of the source's voxels that the refined pose lays within refinement's correspondence distance of a
    target voxel, in [0, 1]; NaN when refinement did not run. ``Config.min_overlap`` is checked against it."""
    refine_rmse: float
    """Weighted RMS of refinement's residuals at its final pose (point-to-plane distance, the clouds' unit); NaN
    when refinement did not run or found no correspondence. ``Config.max_refine_rmse_gain`` is checked against
    it."""
    refine_condition: float
    """Weakest over strongest direction of ``information`` (rotations as displacements at the matched points'
    radius), in [0, 1]: near 0 the pose slides along some direction (``Config.min_refine_condition`` is checked
    against it). NaN when refinement did not run."""
    rotation_uncertainty: float
    """How well the solver's inliers pin the rotation down, in radians: its 1-sigma uncertainty about the worst
    axis if every inlier were off by ``noise_bound``, ``noise_bound / sqrt(N (e1**2 + e2**2))`` with ``N``
    = ``num_final_inliers`` and ``e1``, ``e2`` the two smaller ``inlier_extent`` values. Large when the
    inliers are few or all on one compact object. Without refinement ``valid`` needs it <=
    ``Config.max_rotation_uncertainty`` (else reason "the inliers leave the rotation uncertain"). ``inf`` when
    the solver found a pose but no inlier spread (e.g. no inliers); NaN when the global solver estimated no pose
    (and after :meth:`Matcher.refine`, which runs no solver)."""
    inlier_coverage: float
    """How much of the aligned overlap the solver's inliers span: the inliers' principal standard deviation
    (``inlier_extent[0]``) over that of the source voxels the refined pose overlaps; small when the matches
    cluster on one object, which may match itself in several poses. With refinement ``valid`` needs it >=
    ``Config.min_inlier_coverage`` (else reason "the inliers cover too little of the overlap"). NaN unless a
    registration (not :meth:`Matcher.refine`) was refined and had inliers."""
    time_refine_ms: float
    """Milliseconds spent on refinement (0 when it did not run)."""
    num_refine_correspondences: int
    """Refinement's correspondences at its final pose (0 when it did not run)."""
    refine_iterations: int
    """Refinement iterations run (0 when it did not run)."""
    refine_converged: bool
    """Whether refinement stopped on its convergence test rather than its iteration cap; a refined pose that did
    not is not valid (reason "refinement did not converge": it was still crossing between basins, as from a
    wrong start)."""
    num_source_suppressed: int
    """Source voxels ``Config.suppression`` kept from becoming keypoints (0 when it is 'none')."""
    num_target_suppressed: int
    """Target voxels ``Config.suppression`` kept from becoming keypoints (0 when it is 'none')."""
    time_suppression_ms: float
    """Milliseconds of suppression, both clouds (part of ``time_features_ms``; 0 when it is off)."""
    tilt: float
    """With ``Config.rotation_dof=1``: the angle (radians) by which the best unconstrained rotation on the yaw
    solution's inliers turns ``Config.up``; above what the noise allows, the pair is not valid (reason "the
    clouds' relative roll or pitch is not zero"). NaN otherwise."""
    degenerate: bool
    """Whether refinement ran and the aligned clouds leave directions of the pose free (a corridor leaves one, a
    tunnel two, a plane three): ``weak_directions`` is not empty. A direction is free when its share of the
    information, with rotations measured by the displacements they cause at the matched points, is below
    ``Config.min_refine_condition`` of the strongest direction's (``refine_condition`` is the weakest share).
    Such a pose is not valid (reason "the refined pose is not constrained in every direction") unless
    ``Config.allow_degenerate``. False when refinement did not run: without it there is no dense information to
    tell."""
    num_weak_directions: int
    """The free directions counted, 0 to 6: ``len(weak_directions)`` (0 unless ``degenerate``)."""
    weak_directions: np.ndarray
    """(k, 6) float64, k in 0..6: the free directions (see ``degenerate``), weakest first; shape (0, 6) when there
    are none or refinement did not run. Each row is a unit 6-vector ``xi`` = (rotation in radians, translation in
    the clouds' unit) in the order and frame of ``information`` (``transform @ expm(hat(xi))``: a perturbation
    on the right, in the source's frame), its largest-magnitude component positive; the pose moved along it
    changes the alignment by almost nothing. A slide along the target's unit direction ``d`` is the row
    ``(0, 0, 0, *(rotation.T @ d))``, up to sign."""
    ambiguity: float
    """When the global solver found a pose: the support of the best competing pose, distinct from it (moving the
    matched points by more than 8 ``noise_bound``), over its own, in [0, 1]: the competitor's inliers among every
    match against this pose's, and from one half on the smaller of that and the same ratio of source voxels landing
    beside target voxels. Near 0 in a scene with one answer, near 1 in a repetitive or symmetric one (a street of
    identical facades one period along, a symmetric object turned). ``valid`` needs it <= ``Config.max_ambiguity``
    (else reason "a second, distinct pose has nearly as much support"). NaN when the solver did not run (and after
    :meth:`Matcher.refine`)."""
    confidence: float
    """The probability that the pose is within the success tolerance (5 degrees, and 2 m for LiDAR, 0.3 m indoors, 1
    cm on small objects: about 4 to 7 voxels at the suggested sizes), in [0, 1]: a fixed logistic function of
    ``num_final_inliers`` (with refinement also of ``overlap`` and ``refine_rmse``) times a factor falling with
    ``ambiguity`` (1 up to 0.6, a pick among equals from 0.8), and after :meth:`Matcher.refine` of ``overlap`` and
    ``refine_rmse`` (docs/design/accuracy.md, "Confidence"). 0 without a pose. It reads no ``Config`` threshold. Runs
    its fit did not see held no wrong pose at 0.95 or above: a threshold for loop closures."""
    voxel_size_used: float
    """The voxel size the clouds were described with: ``Config.voxel_size``, or under ``voxel_size="auto"`` the one
    :func:`kissm.suggest_voxel_size` gives for both clouds (from features, theirs)."""

    @classmethod
    def _from_c(cls, r: Any) -> Result:
        def array(field: Any, n: int, shape: tuple[int, ...]) -> np.ndarray:
            return np.frombuffer(ffi.buffer(field, 8 * n), dtype=np.float64).reshape(shape).copy()

        weak = min(max(int(r.num_weak_directions), 0), 6)
        values: dict[str, Any] = {
            "valid": bool(r.valid),
            "reason": text(lib.kissm_reason_string(r.reason)),
            "reason_code": int(r.reason),
            "transform": array(r.transform, 16, (4, 4)),
            "rotation": array(r.rotation, 9, (3, 3)),
            "translation": array(r.translation, 3, (3,)),
            "inlier_extent": array(r.inlier_extent, 3, (3,)),
            "coarse_transform": array(r.coarse_transform, 16, (4, 4)),
            "information": array(r.information, 36, (6, 6)),
            "refine_converged": bool(r.refine_converged),
            "degenerate": bool(r.degenerate),
            "num_weak_directions": weak,
            # rows beyond num_weak_directions are NaN in C and left out here
            "weak_directions": array(r.weak_directions, 36, (6, 6))[:weak].copy(),
        }
        values.update({name: int(getattr(r, name)) for name in _COUNT_FIELDS})
        values.update({name: float(getattr(r, name)) for name in _FLOAT_FIELDS + _TIME_FIELDS})
        return cls(**values)

    @property
    def has_pose(self) -> bool:
        """Whether a pose was estimated (``transform`` is finite), trusted or not."""
        return bool(np.isfinite(self.transform).all())

    @property
    def refined(self) -> bool:
        """Whether refinement ran (then ``overlap``, ``information`` and the refine fields are set)."""
        return not math.isnan(self.overlap)

    @property
    def rotation_angle_deg(self) -> float:
        """The rotation's angle in degrees (NaN without a pose)."""
        return _angle_deg(np.eye(4), self.transform) if self.has_pose else math.nan

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python values (nested lists for the arrays), e.g. for JSON."""
        return {
            f.name: (v.tolist() if isinstance(v := getattr(self, f.name), np.ndarray) else v)
            for f in dataclasses.fields(self)
        }

    def __repr__(self) -> str:
        head = "kissm.Result("
        pad = " " * len(head)
        status = "valid=True" if self.valid else f"valid=False, reason={self.reason!r}"
        status += f", confidence={self.confidence:.3f}"
        lines = [f"{head}{status},"]
        from_prior = self.refined and self.num_initial_correspondences == 0  # Matcher.refine: no global solver
        if from_prior:
            lines.append(f"{pad}refined from an initial pose, {self.time_total_ms:.1f} ms,")
        else:
            lines.append(
                f"{pad}{self.num_final_inliers} final inliers of {self.num_initial_correspondences} matches "
                f"(inlier_ratio {self.inlier_ratio:.3f}), residual_rms {self.residual_rms:.4g}, "
                f"{self.time_total_ms:.1f} ms,"
            )
            if not math.isnan(self.rotation_uncertainty):  # the solver estimated a pose
                evidence = f"{pad}rotation_uncertainty {math.degrees(self.rotation_uncertainty):.3g} deg"
                if not math.isnan(self.inlier_coverage):
                    evidence += f", inlier_coverage {self.inlier_coverage:.3f}"
                lines.append(f"{evidence} (the inliers' spread), ambiguity {self.ambiguity:.3f},")
        moved = ""
        if self.refined:
            stop = "converged" if self.refine_converged else "iteration cap"
            rotation_sigma, translation_sigma = _sigmas(self.information)
            lines += [
                f"{pad}refined: {self.refine_iterations} iterations ({stop}), {self.num_refine_correspondences} "
                f"correspondences, overlap {self.overlap:.3f}, refine_rmse {self.refine_rmse:.4g},",
                f"{pad}refine_condition {self.refine_condition:.3g}, 1-sigma {rotation_sigma:.3g} deg and "
                f"{translation_sigma:.3g} (from information),",
            ]
            if self.degenerate:
                k = len(self.weak_directions)
                lines.append(f"{pad}degenerate: {k} free direction{'' if k == 1 else 's'} (weak_directions),")
            turned = _angle_deg(self.coarse_transform, self.transform)
            shifted = float(np.linalg.norm(self.transform[:3, 3] - self.coarse_transform[:3, 3]))
            moved = f" (refinement moved it {turned:.3f} deg and {shifted:.4g})"
        if self.has_pose:
            lines.append(
                f"{pad}rotation {self.rotation_angle_deg:.2f} deg, "
                f"translation {float(np.linalg.norm(self.translation)):.4g}{moved},"
            )
            prefix = f"{pad}transform="
            matrix = np.array2string(self.transform, precision=6, suppress_small=True, separator=", ", prefix=prefix)
            lines.append(f"{prefix}{matrix})")
        else:
            lines.append(f"{pad}no pose)")
        return "\n".join(lines)
