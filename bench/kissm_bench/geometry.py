# SPDX-License-Identifier: MIT
"""Rotations, rigid transforms and the errors of an estimated pose against the ground truth (numpy is imported
when first needed)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np


def rotation_about(axis: Any, angle: float) -> np.ndarray:
    """The rotation by ``angle`` radians about ``axis`` (any length; Rodrigues' formula)."""
    import numpy as np

    u: np.ndarray = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    rot: np.ndarray = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    return rot


def axis_angle(axis: Any, deg: float) -> np.ndarray:
    """The rotation by ``deg`` degrees about ``axis``."""
    return rotation_about(axis, math.radians(deg))


def rot_about(axis: str, deg: float) -> np.ndarray:
    """The rotation by ``deg`` degrees about the coordinate axis ``axis`` ("x" or "z"), written out: exactly
    about that axis."""
    import numpy as np

    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == "z":
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    if axis == "x":
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    raise ValueError(axis)


def rigid(rot: np.ndarray, trans: np.ndarray) -> np.ndarray:
    """The 4x4 transform of rotation ``rot`` and translation ``trans``."""
    import numpy as np

    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rot, trans
    return t


def apply(t: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` (N, 3) or one point (3,) moved by the 4x4 transform ``t``."""
    import numpy as np

    return np.asarray(points @ t[:3, :3].T + t[:3, 3])


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    """The angle of the rotation between the 3x3 rotations ``a`` and ``b``, in degrees."""
    import numpy as np

    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(a.T @ b)) - 1.0) / 2.0))))


def pose_errors(transform: Any, truth: np.ndarray) -> tuple[float | None, float | None]:
    """Rotation error (degrees) and translation error (metres, at the source's origin) of the 4x4 ``transform``;
    (None, None) when it is not finite."""
    import numpy as np

    t = np.asarray(transform, dtype=np.float64)
    if not np.isfinite(t).all():
        return None, None
    return rotation_error_deg(t[:3, :3], truth[:3, :3]), float(np.linalg.norm(t[:3, 3] - truth[:3, 3]))


def judge_at(
    transform: Any, gt: np.ndarray, max_rot: float, max_trans: float, at: np.ndarray | None = None
) -> tuple[float, float, bool]:
    """Rotation error (degrees), translation error at the point ``at`` (the source's origin when None) and
    whether both are within the thresholds; NaN errors and wrong when the pose is not finite."""
    import numpy as np

    t = np.asarray(transform)
    if not np.isfinite(t).all():
        return math.nan, math.nan, False
    e_rot = rotation_error_deg(t[:3, :3], gt[:3, :3])
    point = np.zeros(3) if at is None else at  # where the translation error is measured
    e_trans = float(np.linalg.norm(apply(t, point) - apply(gt, point)))
    return e_rot, e_trans, e_rot <= max_rot and e_trans <= max_trans
