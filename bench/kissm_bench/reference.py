# SPDX-License-Identifier: MIT
"""The reference KISS-Matcher (PyPI ``kiss-matcher``) as every benchmark calls it: a fresh
``KISSMatcher(KISSMatcherConfig(voxel))`` per call, ``estimate(source, target)``, and its own C++ stage times."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np

REFERENCE_MIN_INLIERS = 5  # "valid" for the reference: solution.valid and at least 5 final inliers
REFERENCE_MIN_VOXEL = 0.005  # the reference refuses smaller voxels


def reference_transform(solution: Any) -> np.ndarray:
    """The reference's RegistrationSolution as a 4x4 transform (float64)."""
    import numpy as np

    t = np.eye(4)
    t[:3, :3] = np.array(solution.rotation, dtype=np.float64).reshape(3, 3)
    t[:3, 3] = np.array(solution.translation, dtype=np.float64).reshape(3)
    return t


@dataclass(frozen=True)
class Estimate:
    """One call of the reference: its pose, its Python wall time and its own stage times (ms)."""

    transform: np.ndarray
    wall_ms: float
    solution_valid: bool
    inliers: int  #: final inliers
    processing_ms: float  #: voxelisation
    extraction_ms: float  #: features
    matching_ms: float  #: includes the pruning (ROBIN) time
    rejection_ms: float  #: the pruning
    solver_ms: float

    @property
    def valid(self) -> bool:
        """The benchmarks' rule: ``solution.valid`` and at least REFERENCE_MIN_INLIERS final inliers."""
        return self.solution_valid and self.inliers >= REFERENCE_MIN_INLIERS

    @property
    def cxx_ms(self) -> float:
        """The sum of its own stage times (processing + extraction + matching + solver): "ref C++"."""
        return self.processing_ms + self.extraction_ms + self.matching_ms + self.solver_ms


def estimate(km: Any, voxel: float, source: np.ndarray, target: np.ndarray, use_quatro: bool = False) -> Estimate:
    """One reference call on ``km`` (the imported kiss_matcher module); ``use_quatro``: its 4-DoF (yaw-only) mode."""
    t0 = time.perf_counter()
    config = km.KISSMatcherConfig(voxel, use_quatro=True) if use_quatro else km.KISSMatcherConfig(voxel)
    matcher = km.KISSMatcher(config)
    solution = matcher.estimate(source, target)
    transform = reference_transform(solution)
    wall = (time.perf_counter() - t0) * 1e3
    return Estimate(
        transform=transform,
        wall_ms=wall,
        solution_valid=bool(solution.valid),
        inliers=int(matcher.get_num_final_inliers()),
        processing_ms=matcher.get_processing_time() * 1e3,
        extraction_ms=matcher.get_extraction_time() * 1e3,
        matching_ms=matcher.get_matching_time() * 1e3,
        rejection_ms=matcher.get_rejection_time() * 1e3,
        solver_ms=matcher.get_solver_time() * 1e3,
    )
