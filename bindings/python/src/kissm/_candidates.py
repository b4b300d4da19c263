# SPDX-License-Identifier: MIT
"""Which pairs :mod:`kissm.multiway` registers beyond the obvious ones: loop candidates of a sequence (near each
other by priors or by the chained odometry), checked options included."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ._errors import InvalidArgumentError
from ._result import Result

#: The radius of a loop candidate grows by this share of the dead-reckoned path between the two clouds. Odometry
#: from registrations drifts by well under 1% of the distance (0.05% per 100 m on kissm simulate's drives); 5% let in
#: candidates up to 68 m apart there, which cost twice a valid registration each and held every wrong one reported
#: valid (docs/reports/multiway-drive.md); 2% still gave every true loop scan a right candidate.
DRIFT = 0.02


def check_sequence_options(
    sequence: bool, priors: Any, n: int, loop_radius: float | None, loop_gap: int, loops_per_scan: int
) -> np.ndarray | None:
    """The priors' positions ((N, 3), NaN rows for clouds without one), after checking the sequence options."""
    if not sequence:
        if priors is not None:
            raise InvalidArgumentError("align: priors are read by pairs='sequence' only")
        return None
    if loop_radius is not None and not (math.isfinite(loop_radius) and loop_radius > 0):
        raise InvalidArgumentError(f"align: loop_radius is {loop_radius}; a finite number above 0")
    if isinstance(loop_gap, bool) or not isinstance(loop_gap, int) or loop_gap < 1:
        raise InvalidArgumentError(f"align: loop_gap is {loop_gap!r}; an integer of at least 1")
    if isinstance(loops_per_scan, bool) or not isinstance(loops_per_scan, int) or loops_per_scan < 0:
        raise InvalidArgumentError(f"align: loops_per_scan is {loops_per_scan!r}; an integer of at least 0")
    if priors is None:
        return None
    poses = np.asarray(priors, dtype=np.float64)
    if poses.shape != (n, 4, 4):
        raise InvalidArgumentError(f"align: priors has shape {poses.shape}; ({n}, 4, 4), one pose per cloud")
    positions: np.ndarray = poses[:, :3, 3].copy()
    positions[~np.isfinite(positions).all(axis=1)] = np.nan
    return positions


def dead_reckoned(steps: Mapping[int, Result | None], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The consecutive registrations (steps[k]: cloud k+1 into k) chained: positions (N, 3), the path length (N,)
    and the piece (N,): a missing or invalid registration starts a new piece in a frame of its own."""
    positions, path, piece = np.zeros((n, 3)), np.zeros(n), np.zeros(n, dtype=np.int64)
    pose = np.eye(4)
    for k in range(n - 1):
        result = steps.get(k)
        if result is not None and result.valid:
            step = np.asarray(result.transform, dtype=np.float64)
            pose = pose @ step
            path[k + 1] = path[k] + float(np.linalg.norm(step[:3, 3]))
            piece[k + 1] = piece[k]
        else:
            pose = np.eye(4)
            piece[k + 1] = piece[k] + 1
        positions[k + 1] = pose[:3, 3]
    return positions, path, piece


def loop_candidates(
    where: np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray], radius: float, gap: int, per_scan: int, drift: float
) -> list[tuple[int, int]]:
    """Pairs (i, j), j >= i + gap, whose positions lie within radius (+ drift x the path between them) of each
    other, at most per_scan for each j (the nearest first, then the lower i), ordered by j then i."""
    if isinstance(where, tuple):
        positions, path, piece = where
    else:
        positions = where
        path, piece = np.zeros(len(where)), np.zeros(len(where), dtype=np.int64)
    known = np.isfinite(positions).all(axis=1)
    out: list[tuple[int, int]] = []
    for j in range(gap, len(positions)):
        if not known[j] or per_scan == 0:
            continue
        earlier = j - gap + 1
        distance = np.linalg.norm(positions[:earlier] - positions[j], axis=1)
        allowed = radius + drift * np.abs(path[j] - path[:earlier])
        near = known[:earlier] & (piece[:earlier] == piece[j]) & (distance <= allowed)
        chosen = sorted(zip(distance[near].tolist(), np.flatnonzero(near).tolist(), strict=True))[:per_scan]
        out.extend(sorted((int(i), j) for _, i in chosen))
    return out
