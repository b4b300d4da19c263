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
)
_FLOAT_FIELDS = ("inlier_ratio", "residual_rms", "noise_bound")
_TIME_FIELDS = (
    "time_voxelize_ms",
    "time_features_ms",
    "time_matching_ms",
    "time_pruning_ms",
    "time_solver_ms",
    "time_total_ms",
)


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Result:
    """The outcome of a registration: the pose, whether it can be trusted, and every number behind that.

    ``transform`` maps source points into the target frame: ``p_target = rotation @ p_source + translation``
    (or ``(transform @ [x, y, z, 1])[:3]``). When no pose was estimated it is all NaN; when ``valid`` is
    False but a pose was estimated it is kept for inspection, and ``reason`` says why it is not trusted.
    Counts and per-stage wall-clock times (milliseconds) are those of the C ``kissm_result``; the times are
    the only fields that differ between identical calls.
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
    """The sum of the stage times, in milliseconds."""

    @classmethod
    def _from_c(cls, r: Any) -> Result:
        def array(field: Any, n: int, shape: tuple[int, ...]) -> np.ndarray:
            return np.frombuffer(ffi.buffer(field, 8 * n), dtype=np.float64).reshape(shape).copy()

        values: dict[str, Any] = {
            "valid": bool(r.valid),
            "reason": text(lib.kissm_reason_string(r.reason)),
            "reason_code": int(r.reason),
            "transform": array(r.transform, 16, (4, 4)),
            "rotation": array(r.rotation, 9, (3, 3)),
            "translation": array(r.translation, 3, (3,)),
            "inlier_extent": array(r.inlier_extent, 3, (3,)),
        }
        values.update({name: int(getattr(r, name)) for name in _COUNT_FIELDS})
        values.update({name: float(getattr(r, name)) for name in _FLOAT_FIELDS + _TIME_FIELDS})
        return cls(**values)

    @property
    def has_pose(self) -> bool:
        """Whether a pose was estimated (``transform`` is finite), trusted or not."""
        return bool(np.isfinite(self.transform).all())

    @property
    def rotation_angle_deg(self) -> float:
        """The rotation's angle in degrees (NaN without a pose)."""
        cos = (float(np.trace(self.rotation)) - 1.0) / 2.0
        return math.degrees(math.acos(min(1.0, max(-1.0, cos)))) if self.has_pose else math.nan

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
        lines = [
            f"{head}{status},",
            f"{pad}{self.num_final_inliers} final inliers of {self.num_initial_correspondences} matches "
            f"(inlier_ratio {self.inlier_ratio:.3f}), residual_rms {self.residual_rms:.4g}, "
            f"{self.time_total_ms:.1f} ms,",
        ]
        if self.has_pose:
            lines.append(
                f"{pad}rotation {self.rotation_angle_deg:.2f} deg, "
                f"translation {float(np.linalg.norm(self.translation)):.4g},"
            )
            prefix = f"{pad}transform="
            matrix = np.array2string(self.transform, precision=6, suppress_small=True, separator=", ", prefix=prefix)
            lines.append(f"{prefix}{matrix})")
        else:
            lines.append(f"{pad}no pose)")
        return "\n".join(lines)
