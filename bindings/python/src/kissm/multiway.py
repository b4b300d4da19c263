# SPDX-License-Identifier: MIT
"""Multiway registration: many clouds into one frame with no initial guess (docs/multiway.md).

    alignment = kissm.multiway.align(scans, voxel_size=0.004)   # every pair registered, then a pose graph
    alignment.poses        # (N, 4, 4) world <- scan, world = the first scan's frame; NaN where not placed
    alignment.placed       # (N,) bool
    alignment.merged(scans, voxel_size=0.002)                  # one cloud in the first scan's frame
    alignment.write_g2o("graph.g2o"); alignment.write_tum("poses.txt"); alignment.write_kitti("poses.kitti")

The pairs are registered by :func:`kissm.batch.register_many` (so every executor works and gives the same bits),
each valid registration becomes a robust edge of a :class:`kissm.PoseGraph` with its transform and calibrated
information, and the graph's optimisation places every scan that accepted edges join to the first one. A scan
that cannot be placed is reported as such (NaN pose), never given a guess.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Hashable, Mapping, Sequence
from typing import Any, Literal

import numpy as np

from . import batch
from ._candidates import (
    DRIFT,
    check_sequence_options,
    corroborated,
    loop_candidates,
    reckoned_poses,
    similar_candidates,
    step_flags,
)
from ._config import Config, RefineMode
from ._errors import InvalidArgumentError
from ._matcher import Features
from ._pose_files import kitti_lines, quaternion, tum_lines, write_lines
from ._pose_graph import PoseGraph
from ._read import read_points
from ._result import Result
from .batch import _args as batch_args


@dataclasses.dataclass(frozen=True, eq=False)
class Edge:
    """One valid registration between two scans, as the pose graph judged it."""

    source: int
    """The source scan's position in :attr:`Alignment.keys`."""
    target: int
    """The target scan's position."""
    transform: np.ndarray
    """(4, 4) ``T_target_source``: the registration's pose."""
    information: np.ndarray
    """(6, 6) its information (rotation first, source frame)."""
    accepted: bool
    """Whether the optimisation kept it (False: it disagrees with the rest, or a scan of it is not placed, or it
    was kept out of the graph: a registration between the pieces of a broken chain outside the largest set of them
    that agrees, docs/multiway.md "Loop candidates by similarity")."""
    residual: float
    """Its squared error ``xi^T I xi`` at the solution; NaN where a scan of it is not placed or it was kept out."""
    result: Result
    """The registration itself."""


@dataclasses.dataclass(frozen=True, eq=False)
class Alignment:
    """What :func:`align` found: a pose per scan in the first scan's frame."""

    keys: list[Hashable]
    """The scans' keys, in order (a sequence's positions, or a mapping's keys); the first is the anchor."""
    poses: np.ndarray
    """(N, 4, 4) world <- scan (world = the first scan's frame); NaN for a scan that is not placed."""
    placed: np.ndarray
    """(N,) bool: accepted edges join the scan to the first one."""
    components: np.ndarray
    """(N,) int64: per scan, the smallest scan position joined to it by accepted edges."""
    edges: list[Edge]
    """The valid registrations, in the order their pairs were given."""
    registrations: int
    """How many pairs were registered (valid or not)."""

    def merged(self, clouds: Sequence[Any] | Mapping[Any, Any], voxel_size: float | None = None) -> np.ndarray:
        """The placed scans' points in the first scan's frame, as one (M, 3) float64 array; with ``voxel_size``,
        the centroid of each occupied voxel of that size instead. ``clouds`` as given to :func:`align` (arrays or
        paths)."""
        by_key = _as_mapping(clouds)
        parts = []
        for position, key in enumerate(self.keys):
            if not self.placed[position]:
                continue
            points = _points(by_key[key], key)
            pose = self.poses[position]
            parts.append(points @ pose[:3, :3].T + pose[:3, 3])
        merged = np.concatenate(parts) if parts else np.zeros((0, 3))
        if voxel_size is None:
            return merged
        if not (voxel_size > 0 and math.isfinite(voxel_size)):
            raise InvalidArgumentError(f"merged: voxel_size is {voxel_size}; a finite number above 0")
        cells = np.floor(merged / voxel_size).astype(np.int64)
        _, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.reshape(-1)
        sums = np.zeros((len(counts), 3))
        np.add.at(sums, inverse, merged)
        centroids: np.ndarray = sums / counts[:, None]
        return centroids

    def write_tum(self, path: str | os.PathLike[str], timestamps: Sequence[float] | None = None) -> None:
        """The placed scans' poses in the TUM format: ``timestamp tx ty tz qx qy qz qw`` per line (the scan's
        position as its timestamp unless ``timestamps`` gives one per scan); scans not placed are left out."""
        if timestamps is not None and len(timestamps) != len(self.keys):
            raise InvalidArgumentError(f"write_tum: {len(timestamps)} timestamps for {len(self.keys)} scans")
        stamps = timestamps if timestamps is not None else range(len(self.keys))
        write_lines(path, tum_lines(self.poses, stamps, self.placed))

    def write_kitti(self, path: str | os.PathLike[str]) -> None:
        """Every scan's pose in the KITTI odometry format: the first three rows of the 4x4, row-major, one line per
        scan in order (``nan`` entries for a scan that is not placed, so that line k stays scan k)."""
        write_lines(path, kitti_lines(self.poses))

    def write_g2o(self, path: str | os.PathLike[str]) -> None:
        """The graph in g2o's format: a ``VERTEX_SE3:QUAT`` per placed scan (its pose) and an ``EDGE_SE3:QUAT`` per
        accepted edge. g2o's edge from vertex t to vertex s measures ``inv(X_t) X_s`` (our transform) with its
        error's translation first and its rotation as a quaternion's vector part (half the angle), so the
        information's blocks are swapped and its rotation rows and columns doubled (docs/pose-graph.md)."""
        lines = []
        for position, pose in enumerate(self.poses):
            if self.placed[position]:
                lines.append(f"VERTEX_SE3:QUAT {position} {_g2o_pose(pose)}")
        order = [3, 4, 5, 0, 1, 2]  # g2o: translation, then rotation
        scale = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])  # d(rotation vector) = 2 d(quaternion vector part)
        for edge in self.edges:
            if not edge.accepted:
                continue
            info = edge.information[np.ix_(order, order)] * np.outer(scale, scale)
            upper = [repr(float(info[i, j])) for i in range(6) for j in range(i, 6)]
            lines.append(f"EDGE_SE3:QUAT {edge.target} {edge.source} {_g2o_pose(edge.transform)} {' '.join(upper)}")
        write_lines(path, lines)


def align(
    clouds: Sequence[Any] | Mapping[Any, Any],
    voxel_size: float | Literal["auto"] | None = None,
    *,
    pairs: str | Sequence[tuple[Hashable, Hashable]] = "all",
    priors: Any = None,
    loop_radius: float | None = None,
    loop_gap: int = 10,
    loops_per_scan: int = 5,
    similar_per_scan: int = 3,
    executor: Any = None,
    progress: batch.ProgressLike = None,
    refine: RefineMode | None = "gicp",
    bound: float = PoseGraph.DEFAULT_BOUND,
    threads_per_job: int = 1,
    **config: Any,
) -> Alignment:
    """Register many clouds into the first one's frame with no initial guess.

    ``clouds``: a sequence (keys are the positions) or a mapping (its keys, in order) of what
    :func:`kissm.batch.register_many` takes: (N, 3) arrays, file paths, :class:`kissm.batch.CloudFile`,
    :class:`kissm.Features`. The first is the anchor: its frame is the world.

    ``pairs``: ``"all"`` (every pair once, the later cloud as the source: sensible up to some tens of clouds),
    ``"sequence"`` (clouds in acquisition order: each with the next, then loop candidates, so the work grows with
    the number of clouds, not its square), or the ``(source key, target key)`` pairs to register.

    Loop candidates of ``"sequence"``: pairs at least ``loop_gap`` clouds apart whose positions lie within
    ``loop_radius`` (default 30 voxels) of each other, at most ``loops_per_scan`` per cloud (the nearest first).
    The positions are ``priors`` ((N, 4, 4) world <- scan poses, e.g. GNSS or a SLAM run; rows of NaN for clouds
    without one) when given; otherwise the consecutive registrations chained into a dead-reckoned path, with the
    radius grown by 2% of the path length between the two clouds for the drift (a break in the chain, an
    invalid consecutive pair, starts a new piece). Between pieces, where the odometry cannot judge, the candidates
    come from the clouds' similarity instead: each cloud with the ``similar_per_scan`` earlier clouds of other
    pieces, at least ``loop_gap`` back, whose :meth:`kissm.Features.signature` are the nearest (0 turns this
    off; an unbroken chain gets none, so the registrations still grow linearly with the clouds). Such a pair has no
    position to check it: of the valid registrations between two pieces, only the largest set that agrees on where
    the pieces lie joins the graph (docs/multiway.md, "Loop candidates by similarity").

    ``voxel_size`` (``"auto"``: :func:`kissm.suggest_voxel_size` of every cloud together, the files read once for
    it; not with :class:`kissm.Features`), ``refine`` (``"gicp"`` by default: its information weighs the edges;
    ``None`` or ``"none"`` gives coarse poses, whose edges get an information from the rotation uncertainty alone
    and are weighed equally otherwise) and any other :class:`kissm.Config` field are the registrations' settings;
    ``executor``, ``progress`` and ``threads_per_job`` are :func:`kissm.batch.register_many`'s. ``bound`` is the
    pose graph's (:meth:`kissm.PoseGraph.optimize`).

    Raises :class:`kissm.InvalidArgumentError` for an unknown ``pairs`` value, a pair naming a cloud that is not
    given, or a sequence option out of range (``loop_radius``, ``loop_gap``, ``loops_per_scan``,
    ``similar_per_scan``, ``priors``; the message names it), and whatever :func:`kissm.batch.register_many`
    raises for bad settings or clouds.
    """
    by_key = _as_mapping(clouds)
    keys = list(by_key)
    if not keys:
        raise InvalidArgumentError("align: clouds is empty")
    position = {key: k for k, key in enumerate(keys)}
    sequence = pairs == "sequence"
    if isinstance(pairs, str):
        if pairs not in ("all", "sequence"):
            raise InvalidArgumentError(
                f"align: pairs is {pairs!r}; 'all', 'sequence' or a sequence of (source, target) keys"
            )
        if pairs == "all":
            chosen = [(keys[j], keys[i]) for i in range(len(keys)) for j in range(i + 1, len(keys))]
        else:
            chosen = [(keys[i + 1], keys[i]) for i in range(len(keys) - 1)]
    else:
        chosen = [tuple(pair) for pair in pairs]  # type: ignore[misc]
        for pair in chosen:
            if len(pair) != 2 or pair[0] not in position or pair[1] not in position:
                raise InvalidArgumentError(f"align: pair {pair!r} does not name two of the clouds")
    prior_positions = check_sequence_options(
        sequence, priors, len(keys), loop_radius, loop_gap, loops_per_scan, similar_per_scan
    )
    voxel_size = _one_voxel(voxel_size, by_key)
    runner = _Runner(executor, progress, threads_per_job, voxel_size, refine, config)
    held_out: set[int] = set()
    if sequence and len(keys) > 1:
        # Two rounds over the same clouds: described once, then the features serve both.
        usable = runner.describe(by_key)
        results = runner.register([p for p in chosen if p[0] in usable and p[1] in usable], usable)
        steps = {position[r.target]: r.result for r in results}
        radius = runner.radius(loop_radius)
        if prior_positions is not None:
            loops = loop_candidates(prior_positions, radius, loop_gap, loops_per_scan, drift=0.0)
        else:
            poses, path, piece = reckoned_poses(steps, len(keys))
            loops = loop_candidates((poses[:, :3, 3], path, piece), radius, loop_gap, loops_per_scan, drift=DRIFT)
            chain = step_flags(steps, len(keys))
            if similar_per_scan > 0 and piece[-1] > 0:
                # Across the breaks of the chain, the clouds' similarity, by the library's rule (docs/multiway.md,
                # "Loop candidates by similarity"); an unbroken chain gets none.
                similar = similar_candidates(_signatures(keys, usable), loop_gap, similar_per_scan, chain[1])
                loops = sorted(set(loops).union(similar), key=lambda pair: (pair[1], pair[0]))
        wanted = [(keys[j], keys[i]) for i, j in loops if keys[i] in usable and keys[j] in usable]
        results += runner.register(wanted, usable)
        if prior_positions is None and similar_per_scan > 0 and piece[-1] > 0:
            held_out = _uncorroborated(results, position, chain, radius)
    else:
        results = runner.register(chosen, by_key)
    edges = [(position[r.source], position[r.target], r.result, True) for r in results]
    return _solve(keys, edges, bound, len(results), held_out)


def session_clouds(sessions: Sequence[Sequence[Any] | Mapping[Any, Any]]) -> dict[tuple[int, Hashable], Any]:
    """The clouds of several sessions as one mapping keyed ``(session, key)``: :func:`align_sessions`'s keys, and
    what :meth:`Alignment.merged` takes for its result."""
    flat: dict[tuple[int, Hashable], Any] = {}
    for s, session in enumerate(sessions):
        for key, cloud in _as_mapping(session).items():
            flat[(s, key)] = cloud
    return flat


def align_sessions(
    sessions: Sequence[Sequence[Any] | Mapping[Any, Any]],
    voxel_size: float | Literal["auto"] | None = None,
    *,
    stride: int = 10,
    loop_radius: float | None = None,
    loop_gap: int = 10,
    loops_per_scan: int = 5,
    executor: Any = None,
    progress: batch.ProgressLike = None,
    refine: RefineMode | None = "gicp",
    bound: float = PoseGraph.DEFAULT_BOUND,
    threads_per_job: int = 1,
    **config: Any,
) -> Alignment:
    """Merge sessions (drives, robots, survey days), each a sequence of clouds in acquisition order, into the frame
    of the first session's first cloud, with no initial guess between them.

    Each session's consecutive registrations are its odometry: **trusted** edges (a valid one is taken as right).
    Within a session, loop candidates as ``align(pairs="sequence")`` finds them from the chained odometry (robust
    edges). Across sessions, two rounds of robust candidates: every ``stride``-th cloud of a later session with every
    ``stride``-th cloud of each earlier one (a coarse grid that finds where the sessions meet), then, once the graph
    has placed a later session, its clouds with the earlier sessions' clouds within ``loop_radius`` (default 30
    voxels) of them by the merged poses, at most ``loops_per_scan`` per cloud. One optimisation over everything.

    The result's keys are ``(session, key)``; a session no accepted edge joins to the first is not placed (NaN
    poses). For :meth:`Alignment.merged`, pass :func:`session_clouds` of the sessions. Other arguments as
    :func:`align`'s.
    """
    if isinstance(sessions, (str, bytes, Mapping)) or not isinstance(sessions, Sequence) or not sessions:
        raise InvalidArgumentError("align_sessions: sessions must be a non-empty sequence of sessions")
    if isinstance(stride, bool) or not isinstance(stride, int) or stride < 1:
        raise InvalidArgumentError(f"align_sessions: stride is {stride!r}; an integer of at least 1")
    members = [list(_as_mapping(session)) for session in sessions]
    if any(not m for m in members):
        raise InvalidArgumentError("align_sessions: a session has no clouds")
    by_key = session_clouds(sessions)
    keys = list(by_key)
    position: dict[Any, int] = {key: k for k, key in enumerate(keys)}
    check_sequence_options(True, None, len(keys), loop_radius, loop_gap, loops_per_scan)
    voxel_size = _one_voxel(voxel_size, by_key)
    runner = _Runner(executor, progress, threads_per_job, voxel_size, refine, config)
    radius = runner.radius(loop_radius)
    usable = runner.describe(by_key)

    def pair(s: int, j: int, t: int, i: int) -> list[tuple[Hashable, Hashable]]:
        """[(cloud j of session s, cloud i of session t)], or [] when either could not be described."""
        source, target = (s, members[s][j]), (t, members[t][i])
        return [(source, target)] if source in usable and target in usable else []

    odometry: dict[Any, tuple[int, int]] = {}  # (source, target) -> (session, position of the target)
    for s, m in enumerate(members):
        for k in range(len(m) - 1):
            odometry.update((p, (s, k)) for p in pair(s, k + 1, s, k))
    results = runner.register(list(odometry), usable)
    steps: dict[tuple[int, int], Result | None] = {odometry[(r.source, r.target)]: r.result for r in results}
    wanted: list[tuple[Hashable, Hashable]] = []
    for s, m in enumerate(members):
        poses, path, piece = reckoned_poses({k: steps.get((s, k)) for k in range(len(m) - 1)}, len(m))
        for i, j in loop_candidates((poses[:, :3, 3], path, piece), radius, loop_gap, loops_per_scan, DRIFT):
            wanted += pair(s, j, s, i)
        for t in range(s):
            for j in range(0, len(m), stride):
                for i in range(0, len(members[t]), stride):
                    wanted += pair(s, j, t, i)
    results += runner.register(wanted, usable)

    def edges() -> list[tuple[int, int, Result | None, bool]]:
        return [
            (position[r.source], position[r.target], r.result, (r.source, r.target) not in odometry) for r in results
        ]

    alignment = _solve(keys, edges(), bound, len(results))
    # The second round across sessions, from the merged poses: each placed cloud of a later session with the nearest
    # placed clouds of earlier sessions.
    done = {(r.source, r.target) for r in results}
    placed = [int(k) for k in np.flatnonzero(alignment.placed)]
    where = alignment.poses[:, :3, 3]
    wanted = []
    for k in placed:
        session = keys[k][0]
        earlier = [e for e in placed if keys[e][0] < session]
        if not earlier:
            continue
        distance = np.linalg.norm(where[earlier] - where[k], axis=1)
        near = sorted((float(d), int(e)) for d, e in zip(distance, earlier, strict=True) if d <= radius)
        for _, e in near[:loops_per_scan]:
            candidate = (keys[k], keys[e])
            if candidate not in done and candidate[0] in usable and candidate[1] in usable:
                wanted.append(candidate)
    if wanted:
        results += runner.register(wanted, usable)
        alignment = _solve(keys, edges(), bound, len(results))
    return alignment


def _one_voxel(voxel_size: float | Literal["auto"] | None, clouds: Mapping[Any, Any]) -> float | None:
    """``voxel_size``, with ``"auto"`` made the one voxel of every cloud together (every round of an alignment, and
    its loop radius, needs the same voxel)."""
    if voxel_size != "auto":
        return voxel_size
    inputs = [batch_args.check_cloud(key, cloud) for key, cloud in clouds.items()]
    return float(batch_args.set_voxel_size(Config(voxel_size="auto"), inputs).voxel_size)


class _Runner:
    """The registrations' settings and engine, shared by the rounds of one alignment."""

    def __init__(
        self,
        executor: Any,
        progress: batch.ProgressLike,
        threads_per_job: int,
        voxel_size: float | None,
        refine: RefineMode | None,
        config: dict[str, Any],
    ) -> None:
        self.executor, self.progress, self.threads_per_job = executor, progress, threads_per_job
        self.voxel_size = voxel_size
        self.refine: RefineMode = "none" if refine is None else refine
        self.config = config

    def settings(self) -> dict[str, Any]:
        return {
            "threads_per_job": self.threads_per_job,
            "progress": self.progress,
            "voxel_size": self.voxel_size,
            "refine": self.refine,
            **self.config,
        }

    def describe(self, clouds: Mapping[Any, Any]) -> dict[Any, Features]:
        """Every cloud's features; a cloud that cannot be described is left out of every pair (it ends not
        placed), as a pair with it would end as an error in "all"."""
        described = batch.describe_many(clouds, self.executor, **self.settings())
        return {key: value for key, value in described.items() if isinstance(value, Features)}

    def register(self, wanted: list[tuple[Hashable, Hashable]], clouds: Mapping[Any, Any]) -> list[batch.PairResult]:
        return batch.register_many(wanted, clouds, self.executor, **self.settings()) if wanted else []

    def radius(self, loop_radius: float | None) -> float:
        if loop_radius is not None:
            return loop_radius
        if self.voxel_size is None:
            raise InvalidArgumentError("align: loop candidates need loop_radius when voxel_size is not given")
        return 30.0 * float(self.voxel_size)


def _uncorroborated(
    results: list[batch.PairResult],
    position: Mapping[Any, int],
    chain: tuple[np.ndarray, np.ndarray],
    radius: float,
) -> set[int]:
    """The valid registrations between pieces of the chained odometry (pairs found by similarity) outside the
    largest set that agrees between their pieces (:func:`kissm._candidates.corroborated`): kept out of the graph."""
    numbers: list[int] = []
    found: list[tuple[int, int, np.ndarray]] = []
    for k, r in enumerate(results):
        if r.result is not None and r.result.valid:
            numbers.append(k)
            found.append((position[r.target], position[r.source], np.asarray(r.result.transform, dtype=np.float64)))
    kept = corroborated(found, chain, radius)
    return {k for k, ok in zip(numbers, kept, strict=True) if not ok}


def _solve(
    keys: list[Any],
    registrations: list[tuple[int, int, Result | None, bool]],
    bound: float,
    count: int,
    held_out: set[int] | None = None,
) -> Alignment:
    """The pose graph of the valid registrations (source, target, result, robust), in order, from the first key;
    those numbered in ``held_out`` are reported as edges not accepted and left out of the graph."""
    valid: list[tuple[int, int, np.ndarray, np.ndarray, Result, int]] = []
    added = 0
    with PoseGraph(len(keys)) as graph:
        for k, (source, target, result, robust) in enumerate(registrations):
            if result is None or not result.valid:
                continue
            transform = np.asarray(result.transform, dtype=np.float64)
            information = _information(result)
            slot = -1  # the edge's number in the graph; -1: kept out
            if not held_out or k not in held_out:
                graph.add_edge(source, target, transform, information, robust=robust)
                slot, added = added, added + 1
            valid.append((source, target, transform, information, result, slot))
        solution = graph.optimize(anchor=0, bound=bound)
    edges = [
        Edge(
            s,
            t,
            transform,
            information,
            slot >= 0 and bool(solution.accepted[slot]),
            float(solution.residuals[slot]) if slot >= 0 else math.nan,
            result,
        )
        for s, t, transform, information, result, slot in valid
    ]
    return Alignment(
        keys=keys,
        poses=solution.poses,
        placed=solution.placed,
        components=solution.components,
        edges=edges,
        registrations=count,
    )


# ---- helpers ---------------------------------------------------------------------------------------------------


def _as_mapping(clouds: Sequence[Any] | Mapping[Any, Any]) -> Mapping[Any, Any]:
    if isinstance(clouds, Mapping):
        return clouds
    if isinstance(clouds, (str, bytes, np.ndarray)) or not isinstance(clouds, Sequence):
        raise InvalidArgumentError("align: clouds must be a sequence or a mapping of clouds")
    return dict(enumerate(clouds))


def _points(cloud: Any, key: Hashable) -> np.ndarray:
    if isinstance(cloud, batch.CloudFile):
        return read_points(cloud.path, cloud.format)
    if isinstance(cloud, (str, os.PathLike)):
        return read_points(os.fspath(cloud))
    points = np.asarray(cloud, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise InvalidArgumentError(f"merged: cloud {key!r} is not an (N, 3) array or a file")
    return points


def _signatures(keys: list[Any], features: Mapping[Any, Features]) -> np.ndarray:
    """(N, KISSM_SIGNATURE_SIZE): each cloud's signature; NaN rows for clouds that could not be described."""
    rows = [features[key].signature() if key in features else None for key in keys]
    size = next((len(row) for row in rows if row is not None), 1)
    return np.array([row if row is not None else np.full(size, np.nan) for row in rows]).reshape(len(keys), size)


def _information(result: Result) -> np.ndarray:
    """The refined information; for a coarse pose, an isotropic one from the solver's rotation uncertainty (and
    a translation sigma of a noise bound): coarse edges then count alike, and the graph still rejects the ones that
    disagree by far."""
    information = np.asarray(result.information, dtype=np.float64)
    if np.all(np.isfinite(information)):
        return information
    sigma_rotation = max(float(result.rotation_uncertainty), 1e-4)
    sigma_translation = max(float(result.noise_bound), 1e-9)
    return np.diag([sigma_rotation**-2] * 3 + [sigma_translation**-2] * 3)


def _g2o_pose(pose: np.ndarray) -> str:
    qx, qy, qz, qw = quaternion(pose[:3, :3])
    t = pose[:3, 3]
    return " ".join(repr(float(v)) for v in (t[0], t[1], t[2], qx, qy, qz, qw))


__all__ = ["Alignment", "Edge", "align", "align_sessions", "session_clouds"]
