# SPDX-License-Identifier: MIT
"""Poses as text: the TUM and KITTI trajectory formats (``kissm.io.write_tum`` / ``write_kitti`` and
``kissm.multiway.Alignment``'s writers share these), and the rotation <-> quaternion conversions the g2o and E57
writers use too."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from ._errors import InvalidArgumentError


def quaternion(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """(qx, qy, qz, qw) of a rotation matrix, w >= 0."""
    m = rotation
    trace = float(np.trace(m))
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        q = (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s
    x, y, z, w = (float(v) for v in q)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    sign = -1.0 if w < 0 else 1.0
    return sign * x / norm, sign * y / norm, sign * z / norm, sign * w / norm


def rotation_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The rotation of the quaternion w + xi + yj + zk (normalised first: files store it rounded)."""
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if not (norm > 0 and math.isfinite(norm)):
        raise InvalidArgumentError(f"the quaternion ({w}, {x}, {y}, {z}) has no rotation (its norm is {norm})")
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def check_poses(poses: object, what: str) -> np.ndarray:
    """``poses`` as an (N, 4, 4) float64 array; ``what`` names the argument in the error."""
    array = np.asarray(poses, dtype=np.float64)
    if array.ndim != 3 or array.shape[1:] != (4, 4):
        raise InvalidArgumentError(f"{what}: poses has shape {array.shape}; (N, 4, 4), one 4x4 pose per scan")
    return array


def tum_lines(poses: np.ndarray, stamps: Sequence[float], keep: np.ndarray) -> list[str]:
    """``timestamp tx ty tz qx qy qz qw`` of each pose ``keep`` marks (the shortest repr of each float, so the
    numbers read back bit for bit)."""
    lines = []
    for k, pose in enumerate(poses):
        if not keep[k]:
            continue
        values = (float(stamps[k]), *(float(v) for v in pose[:3, 3]), *quaternion(pose[:3, :3]))
        lines.append(" ".join(repr(v) for v in values))
    return lines


def kitti_lines(poses: np.ndarray) -> list[str]:
    """The first three rows of each 4x4, row-major, one line per pose."""
    return [" ".join(repr(float(v)) for v in pose[:3, :].reshape(-1)) for pose in poses]


def write_lines(path: str | os.PathLike[str], lines: list[str]) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write("".join(line + "\n" for line in lines))


def write_tum(path: str | os.PathLike[str], poses: object, stamps: Sequence[float] | None = None) -> None:
    """Poses in the TUM trajectory format: ``timestamp tx ty tz qx qy qz qw`` per line, the quaternion with
    ``qw >= 0``.

    ``poses``: (N, 4, 4) world <- scan. ``stamps``: one timestamp per pose (seconds), the pose's position when
    not given. A pose with a non-finite entry (NaN: a scan :func:`kissm.multiway.align` did not place) is left out:
    the format has no way to mark a missing pose, the timestamps say which scans the lines are.

    Raises :class:`kissm.InvalidArgumentError` when ``poses`` is not (N, 4, 4) or ``stamps`` does not have N
    entries.
    """
    array = check_poses(poses, "write_tum")
    if stamps is not None and len(stamps) != len(array):
        raise InvalidArgumentError(f"write_tum: {len(stamps)} stamps for {len(array)} poses")
    keep = np.isfinite(array).all(axis=(1, 2))
    write_lines(path, tum_lines(array, stamps if stamps is not None else range(len(array)), keep))


def write_kitti(path: str | os.PathLike[str], poses: object) -> None:
    """Poses in the KITTI odometry format: the first three rows of each 4x4, row-major, one line per pose in
    order (``nan`` entries stay, so that line k is always pose k).

    Raises :class:`kissm.InvalidArgumentError` when ``poses`` is not (N, 4, 4).
    """
    write_lines(path, kitti_lines(check_poses(poses, "write_kitti")))
