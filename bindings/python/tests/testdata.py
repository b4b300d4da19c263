# SPDX-License-Identifier: MIT
"""The clouds of the tests that need no real data: the committed pair of the repository's tests/data
(written once by tools/make_roundtrip_data.py, registered by the C, Python and Rust suites alike), and
rigid moves, row permutations and noise applied to it with numpy, each with its exact ground truth.

The pair is looked up in ``$KISSM_TEST_DATA``, else in ``data/`` next to these tests (where
package_test.sh copies it when the tests run outside the repository), else in the repository's
tests/data.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

import kissm

DATA_ENV = "KISSM_TEST_DATA"
SOURCE, TARGET, GROUND_TRUTH = "roundtrip_source.ply", "roundtrip_target.ply", "roundtrip_ground_truth.txt"
TESTS_DIR = Path(__file__).resolve().parent

#: The voxel size the tests register the pair with (as golden.json's float64 case).
VOXEL_SIZE = 0.25


def data_dir() -> Path:
    """The directory holding the committed pair; FileNotFoundError (failing the test) when there is none."""
    override = os.environ.get(DATA_ENV)
    candidates = [Path(override)] if override else [TESTS_DIR / "data", TESTS_DIR.parents[2] / "tests" / "data"]
    for candidate in candidates:
        if all((candidate / name).is_file() for name in (SOURCE, TARGET, GROUND_TRUTH)):
            return candidate
    raise FileNotFoundError(
        f"the committed test pair ({SOURCE}, {TARGET}, {GROUND_TRUTH}) is in none of "
        f"{', '.join(map(str, candidates))}; copy the repository's tests/data there or set {DATA_ENV}"
    )


def rotation_zyx(yaw_deg: float, pitch_deg: float = 0.0, roll_deg: float = 0.0) -> np.ndarray:
    """Rz(yaw) @ Ry(pitch) @ Rx(roll), angles in degrees."""
    y, p, r = (math.radians(a) for a in (yaw_deg, pitch_deg, roll_deg))
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return rz @ ry @ rx


def pose(rotation: np.ndarray, translation: object) -> np.ndarray:
    """The 4x4 matrix of (rotation, translation)."""
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = rotation, translation
    return out


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation between ``a`` and ``b``, in degrees."""
    cos = (np.trace(a.T @ b) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cos))))


@dataclass(frozen=True)
class Pair:
    source: np.ndarray  #: (N, 3) float64, C-contiguous
    target: np.ndarray
    rotation: np.ndarray  #: the true pose: p_target = rotation @ p_source + translation
    translation: np.ndarray
    voxel_size: float = VOXEL_SIZE

    @property
    def transform(self) -> np.ndarray:
        """The true pose as a 4x4 matrix."""
        return pose(self.rotation, self.translation)

    def moved(self, rotation: np.ndarray, translation: np.ndarray) -> Pair:
        """The target cloud moved by (rotation, translation); the ground truth follows it."""
        return replace(
            self,
            target=np.ascontiguousarray(self.target @ rotation.T + translation),
            rotation=rotation @ self.rotation,
            translation=rotation @ self.translation + translation,
        )

    def permuted(self, seed: int) -> Pair:
        """Both clouds with their rows shuffled (the same scene, another input order)."""
        rng = np.random.default_rng(seed)
        source = self.source[rng.permutation(len(self.source))]
        return replace(self, source=source, target=self.target[rng.permutation(len(self.target))])

    def noisy(self, sigma: float, seed: int) -> Pair:
        """The source with Gaussian noise of standard deviation ``sigma`` added to every coordinate."""
        rng = np.random.default_rng(seed)
        return replace(self, source=self.source + rng.normal(scale=sigma, size=self.source.shape))


def committed_pair() -> Pair:
    """The pair of tests/data, read by the library's PLY reader, with its ground truth."""
    root = data_dir()
    truth = np.loadtxt(root / GROUND_TRUTH).reshape(4, 4)
    source, target = kissm.read_points(root / SOURCE), kissm.read_points(root / TARGET)
    return Pair(source, target, truth[:3, :3].copy(), truth[:3, 3].copy())


def variations(base: Pair) -> list[Pair]:
    """Four different registration problems made from ``base``: itself, and moved, shuffled and noisy
    copies (all with a known pose)."""
    return [
        base,
        base.moved(rotation_zyx(25.0, 2.0, -1.5), np.array([3.0, -2.0, 0.4])),
        base.permuted(11).moved(rotation_zyx(-95.0), np.array([-1.0, 4.0, 0.0])),
        base.noisy(0.01, 13).moved(rotation_zyx(170.0, -3.0, 1.0), np.array([0.5, 0.5, -0.3])),
    ]
