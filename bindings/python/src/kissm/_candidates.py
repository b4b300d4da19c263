# SPDX-License-Identifier: MIT
"""Which pairs :mod:`kissm.multiway` registers beyond the obvious ones: loop candidates of a sequence (near each
other by priors or by the chained odometry, or alike by the clouds' signatures), checked options included."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ._errors import InvalidArgumentError, check
from ._ffi import ffi, lib
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
    if (
        isinstance(similar_per_scan, bool)
        or not isinstance(similar_per_scan, int)
        or not 0 <= similar_per_scan <= 1_000_000
    ):
        # The library's range (kissm_sequence_similar's per_scan, kissm_align_options.similar_per_scan).
        raise InvalidArgumentError(f"align: similar_per_scan is {similar_per_scan!r}; an integer of 0 to 1,000,000")
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


def step_flags(steps: Mapping[int, Result | None], n: int) -> tuple[np.ndarray, np.ndarray]:
    """The consecutive registrations (steps[k]: cloud k+1 into k) as the C API takes a chain: (N-1, 4, 4) transforms
    and (N-1,) uint8 flags, 1 for a valid one (a missing or invalid one is 0 and its transform is not read)."""
    transforms = np.zeros((max(n - 1, 0), 4, 4))
    valid = np.zeros(max(n - 1, 0), dtype=np.uint8)
    for k in range(n - 1):
        result = steps.get(k)
        if result is not None and result.valid:
            transforms[k] = np.asarray(result.transform, dtype=np.float64)
            valid[k] = 1
    return transforms, valid


def similar_candidates(
    signatures: np.ndarray, gap: int, per_scan: int, step_valid: np.ndarray
) -> list[tuple[int, int]]:
    """Pairs (i, j), i <= j - gap, of different pieces of the chain (``step_valid``: (N-1,) flags, a 0 starts a new
    piece), whose signatures ((N, KISSM_SIGNATURE_SIZE), :meth:`kissm.Features.signature`; a NaN row for a cloud
    without one) are the nearest, at most per_scan for each j (the nearest first, then the lower i), ordered by j
    then i: where the chained odometry cannot judge. The library's rule (``kissm_sequence_similar``), so that C,
    the CLI and Python choose the same pairs."""
    rows = np.ascontiguousarray(signatures, dtype=np.float64)
    n = len(rows)
    if rows.shape != (n, int(lib.KISSM_SIGNATURE_SIZE)):
        raise InvalidArgumentError(f"similar_candidates: signatures has shape {rows.shape}; (N, KISSM_SIGNATURE_SIZE)")
    flags = np.ascontiguousarray(step_valid, dtype=np.uint8)
    if flags.shape != (max(n - 1, 0),):
        raise InvalidArgumentError(f"similar_candidates: step_valid has shape {flags.shape}; ({n - 1},)")
    found = _pairs(
        lambda out, capacity, count: lib.kissm_sequence_similar(
            n, _uint8s(flags), ffi.from_buffer("double[]", rows), gap, per_scan, out, capacity, count
        )
    )
    return [(int(target), int(source)) for source, target in found]


def corroborated(
    edges: list[tuple[int, int, np.ndarray]], chain: tuple[np.ndarray, np.ndarray], radius: float
) -> list[bool]:
    """For valid registrations (i, j, T) of a sequence (T: cloud j into cloud i), whether the pose graph takes them:
    every one within a piece of the chain (``chain``: :func:`step_flags`), and of those between two pieces, the
    largest set that agrees on where the later piece lies (``kissm_sequence_corroborated``: a revisit gives several
    registrations that agree, while places that merely look alike give one, or a few that the revisit outnumbers).
    A pair found by similarity alone has no position to check it, and a wrong one on a piece's loose end would be
    absorbed by the graph at the cost of one consecutive edge (docs/multiway.md, "Loop candidates by similarity")."""
    transforms, valid = chain
    n = len(valid) + 1
    pairs = np.ascontiguousarray([[j, i] for i, j, _ in edges], dtype=np.uint64).reshape(len(edges), 2)
    moves = np.ascontiguousarray([t for _, _, t in edges], dtype=np.float64).reshape(len(edges), 4, 4)
    steps = np.ascontiguousarray(transforms, dtype=np.float64)
    kept = np.zeros(len(edges), dtype=np.uint8)
    check(
        lib.kissm_sequence_corroborated(
            n,
            ffi.from_buffer("double[]", steps) if n > 1 else ffi.NULL,
            _uint8s(valid),
            radius,
            len(edges),
            ffi.from_buffer("uint64_t[]", pairs) if len(edges) else ffi.NULL,
            ffi.from_buffer("double[]", moves) if len(edges) else ffi.NULL,
            ffi.from_buffer("uint8_t[]", kept, require_writable=True) if len(edges) else ffi.NULL,
        )
    )
    return [bool(k) for k in kept]


def _uint8s(flags: np.ndarray) -> Any:
    contiguous = np.ascontiguousarray(flags, dtype=np.uint8)
    return ffi.from_buffer("uint8_t[]", contiguous) if len(contiguous) else ffi.NULL


def _pairs(call: Any) -> np.ndarray:
    """(count, 2) uint64 (source, target) pairs of a candidate call of the library: counted, then written."""
    count = ffi.new("uint64_t *")
    check(call(ffi.NULL, 0, count))
    found = np.zeros((int(count[0]), 2), dtype=np.uint64)
    if len(found):
        check(call(ffi.from_buffer("uint64_t[]", found, require_writable=True), len(found), count))
    return found
