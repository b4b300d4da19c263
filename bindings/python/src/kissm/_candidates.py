# SPDX-License-Identifier: MIT
"""Which pairs :mod:`kissm.multiway` registers beyond the obvious ones: loop candidates of a sequence (near each
other by priors or by the chained odometry, or alike by the clouds' signatures), checked options included."""

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
    sequence: bool,
    priors: Any,
    n: int,
    loop_radius: float | None,
    loop_gap: int,
    loops_per_scan: int,
    similar_per_scan: int = 0,
) -> np.ndarray | None:
    """The priors' positions ((N, 3), NaN rows for clouds without one), after checking the sequence options."""
    if not sequence:
        if priors is not None:
            raise InvalidArgumentError("align: priors are read by pairs='sequence' only")
        return None
    if isinstance(similar_per_scan, bool) or not isinstance(similar_per_scan, int) or similar_per_scan < 0:
        raise InvalidArgumentError(f"align: similar_per_scan is {similar_per_scan!r}; an integer of at least 0")
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
    poses, path, piece = reckoned_poses(steps, n)
    return poses[:, :3, 3].copy(), path, piece


def reckoned_poses(steps: Mapping[int, Result | None], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`dead_reckoned` with the whole poses: (N, 4, 4) piece frame <- cloud, the path (N,), the piece (N,)."""
    poses, path, piece = np.tile(np.eye(4), (n, 1, 1)), np.zeros(n), np.zeros(n, dtype=np.int64)
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
        poses[k + 1] = pose
    return poses, path, piece


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


def similar_candidates(
    signatures: np.ndarray, gap: int, per_scan: int, piece: np.ndarray | None = None
) -> list[tuple[int, int]]:
    """Pairs (i, j), i <= j - gap, whose signatures ((N, KISSM_SIGNATURE_SIZE), :meth:`kissm.Features.signature`;
    a NaN row for a cloud without one) are the nearest, at most per_scan for each j (the nearest first, then the
    lower i), ordered by j then i. With ``piece`` ((N,) int), only pairs of different pieces: where the chained
    odometry cannot judge.

    N^2 / 2 distances in all (a few seconds for ten thousand clouds). Each squared distance is summed column by
    column, in order: the same bits on every machine and easy to reproduce in another language (numpy's
    reductions and matrix products sum in orders of their own)."""
    columns = np.ascontiguousarray(np.asarray(signatures, dtype=np.float64).T)
    n = columns.shape[1]
    out: list[tuple[int, int]] = []
    if per_scan == 0:
        return out
    for j in range(gap, n):
        end = j - gap + 1
        distance = np.zeros(end)
        for column in columns:
            distance += np.square(column[:end] - column[j])
        distance[~(distance < np.inf)] = np.inf  # NaN: a cloud without a signature is nobody's candidate
        if piece is not None:
            distance[piece[:end] == piece[j]] = np.inf
        near = np.flatnonzero(distance < np.inf)
        if per_scan < len(near):
            # The per_scan smallest distances and any ties of the last, then the order by (distance, i).
            kth = np.partition(distance[near], per_scan - 1)[per_scan - 1]
            near = near[distance[near] <= kth]
        chosen = near[np.lexsort((near, distance[near]))][:per_scan]
        out.extend((int(i), j) for i in np.sort(chosen))
    return out


def corroborated(
    edges: list[tuple[int, int, np.ndarray]],
    reckoned: tuple[np.ndarray, np.ndarray, np.ndarray],
    radius: float,
    drift: float,
) -> list[bool]:
    """For valid registrations (i, j, T) between clouds of different pieces (T: cloud j into cloud i), whether they
    belong to the largest set that agrees between their two pieces. Registration a agrees with b (of another later
    cloud) when a and the later piece's odometry put b's later cloud within radius + drift x (the paths between
    their earlier clouds and between their later clouds) of where b puts it. The registration that most others agree
    with (the first of equals) is kept with those it agrees with, if any: a revisit gives several registrations that
    agree, while places that merely look alike give one, or a few that the revisit outnumbers. A pair found by
    similarity alone has no position to check it, and a wrong one on a piece's loose end would be absorbed by the
    graph at the cost of one consecutive edge (docs/multiway.md, "Loop candidates by similarity")."""
    poses, path, piece = reckoned
    out = [False] * len(edges)
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (first, later, _) in enumerate(edges):
        groups.setdefault((int(piece[first]), int(piece[later])), []).append(k)
    for members in groups.values():
        i = np.array([edges[k][0] for k in members])
        j = np.array([edges[k][1] for k in members])
        # Each registration's own placing of its later cloud j in the earlier piece's frame.
        placed = np.array([poses[edges[k][0]] @ edges[k][2] for k in members])
        agree = np.zeros((len(members), len(members)), dtype=bool)
        for a in range(len(members)):
            # Registration a's placing of every later cloud of the group: through the later piece's odometry.
            relay = placed[a] @ np.linalg.inv(poses[j[a]])
            predicted = poses[j][:, :3, 3] @ relay[:3, :3].T + relay[:3, 3]
            error = np.linalg.norm(predicted - placed[:, :3, 3], axis=1)
            allowed = radius + drift * (np.abs(path[i] - path[i[a]]) + np.abs(path[j] - path[j[a]]))
            agree[a] = (j != j[a]) & (error <= allowed)
        best = int(np.argmax(agree.sum(axis=1)))
        if agree[best].any():
            for a in np.flatnonzero(agree[best]).tolist() + [best]:
                out[members[a]] = True
    return out
