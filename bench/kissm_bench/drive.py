# SPDX-License-Identifier: MIT
"""The drive benchmark (issue 34, "Sequence"; ``python bench/drive_bench.py --help``): ``kissm.multiway.align``
with ``pairs="sequence"`` on a simulated drive (``kissm simulate``) of 1,000+ scans with loops, judged against
the drive's exact poses and true loop pairs.

Per prefix of the drive (the first N scans: a prefix of a drive is a shorter drive) it runs the pieces of
``align(pairs="sequence")`` one by one, timing each (describing every scan once, the consecutive registrations,
the loop candidates from the chained odometry, their registrations, the pose graph), and then, unless
``--no-align``, ``align`` itself end to end, whose poses and verdicts must be the pieces' bit for bit.

It reports the registrations, the valid ones, the edges accepted and rejected and the scans placed; the true
loops of loops.tsv within the prefix grouped into revisits and how many of them an accepted, right loop edge
joins, and the share of true-loop scans with such an edge; the wrong edges (a relative pose more than 2 degrees
or 2 voxels from the exact one) reported valid and accepted; the trajectory error after anchoring on scan 0
(the graph's and dead reckoning's); the times. Missed revisits are listed with the stage that lost them.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import contextlib
import dataclasses
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Hashable, Iterator, Sequence
from pathlib import Path
from typing import Any

import kissm
import kissm.batch
import kissm.multiway
import numpy as np
from kissm._candidates import DRIFT, dead_reckoned, loop_candidates

from .common import finish_meta, run_meta
from .data import read_scan_set

#: A relative pose more than this far from the exact one is wrong (issue 34's tolerance for a placed scan).
MAX_ANGLE_DEG, MAX_VOXELS = 2.0, 2.0
#: Two true loop pairs belong to the same revisit when their later scans and their earlier scans are each at
#: most this many scans apart; an edge finds a revisit when it lies this close to one of its pairs.
REVISIT_WINDOW = 5
#: The sensors of a true loop pair lie within this distance (kissm simulate's loops.tsv).
LOOP_DISTANCE_M = 10.0
#: The relative pose error's stretch of path.
RPE_LENGTH_M = 100.0


# ---- the drive -----------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Drive:
    """A simulated drive: its scans in order, their exact world poses and its true loop pairs."""

    folder: Path
    files: list[Path]
    formats: list[str]
    poses: np.ndarray
    """(N, 4, 4) T_world_scan."""
    loops: np.ndarray
    """(L, 2) int: the true loop pairs (i, j), i < j, as scan positions."""


def read_drive(folder: Path) -> Drive:
    names, files, formats, poses = read_scan_set(folder)
    position = {name: k for k, name in enumerate(names)}
    pairs = []
    with open(folder / "loops.tsv", encoding="utf-8") as f:
        next(f)
        for line in f:
            if line.strip():
                i, j = line.split("\t")[:2]
                pairs.append((position[i], position[j]))
    loops = np.array(sorted(pairs), dtype=np.int64).reshape(-1, 2)
    return Drive(folder, files, formats, np.array([poses[name] for name in names]), loops)


def simulate(cli: str, folder: Path, scans: int, seed: int, spacing: float | None) -> None:
    command = [cli, "simulate", str(folder), "--scans", str(scans), "--seed", str(seed), "-q"]
    if spacing is not None:
        command += ["--spacing", str(spacing)]
    print("drive:", " ".join(command), file=sys.stderr)
    subprocess.run(command, check=True)


# ---- the run ---------------------------------------------------------------------------------------------------


@dataclasses.dataclass
class Settings:
    voxel: float
    loop_radius: float | None
    loop_gap: int
    loops_per_scan: int
    jobs: int
    bound: float
    config: dict[str, Any]


@dataclasses.dataclass
class Run:
    """One prefix's pieces of align(pairs="sequence") and their times."""

    n: int
    consecutive: list[kissm.batch.PairResult]
    candidates: list[tuple[int, int]]
    loops: list[kissm.batch.PairResult]
    edges: list[tuple[int, int, np.ndarray]]
    """The valid registrations in the order they joined the graph: (source, target, transform)."""
    solution: kissm.PoseGraphSolution
    dead_reckoned: tuple[np.ndarray, np.ndarray, np.ndarray]
    radius: float
    wall: dict[str, float] = dataclasses.field(default_factory=dict)
    cpu: dict[str, float] = dataclasses.field(default_factory=dict)
    align_same: bool | None = None


def position(key: Hashable) -> int:
    """A scan's key in the clouds this benchmark gives kissm.batch: its position."""
    assert isinstance(key, int)
    return key


@contextlib.contextmanager
def timed(wall: dict[str, float], cpu: dict[str, float], stage: str) -> Iterator[None]:
    """The stage's wall time and the process's CPU time (every thread) into wall and cpu."""
    w, c = time.perf_counter(), time.process_time()
    yield
    wall[stage] = time.perf_counter() - w
    cpu[stage] = time.process_time() - c


def run_prefix(drive: Drive, n: int, settings: Settings, executor: Any) -> Run:
    """The pieces of kissm.multiway.align(pairs="sequence") on the first n scans, as align runs them."""
    clouds: dict[Hashable, Any] = {k: kissm.batch.CloudFile(str(drive.files[k]), drive.formats[k]) for k in range(n)}
    options: dict[str, Any] = {
        "threads_per_job": 1,
        "progress": False,
        "voxel_size": settings.voxel,
        "refine": "gicp",
        **settings.config,
    }
    wall: dict[str, float] = {}
    cpu: dict[str, float] = {}
    with timed(wall, cpu, "describe"):
        described = kissm.batch.describe_many(clouds, executor, **options)
    usable = {k: v for k, v in described.items() if isinstance(v, kissm.Features)}
    chosen: list[tuple[Any, Any]] = [(k + 1, k) for k in range(n - 1) if k in usable and k + 1 in usable]
    with timed(wall, cpu, "consecutive"):
        consecutive = kissm.batch.register_many(chosen, usable, executor, **options)
    steps = {position(r.target): r.result for r in consecutive}
    radius = settings.loop_radius if settings.loop_radius is not None else 30.0 * settings.voxel
    with timed(wall, cpu, "candidates"):
        reckoned = dead_reckoned(steps, n)
        candidates = loop_candidates(reckoned, radius, settings.loop_gap, settings.loops_per_scan, drift=DRIFT)
    wanted: list[tuple[Any, Any]] = [(j, i) for i, j in candidates if i in usable and j in usable]
    with timed(wall, cpu, "loops"):
        loops = kissm.batch.register_many(wanted, usable, executor, **options) if wanted else []
    del described, usable
    edges: list[tuple[int, int, np.ndarray]] = []
    with timed(wall, cpu, "graph build"), kissm.PoseGraph(n) as graph:
        for outcome in consecutive + loops:
            result = outcome.result
            if result is None or not result.valid:
                continue
            source, target = position(outcome.source), position(outcome.target)
            transform = np.asarray(result.transform, dtype=np.float64)
            graph.add_edge(source, target, transform, kissm.multiway._information(result), robust=True)
            edges.append((source, target, transform))
        with timed(wall, cpu, "optimize"):
            solution = graph.optimize(anchor=0, bound=settings.bound)
    wall["graph build"] -= wall["optimize"]
    cpu["graph build"] -= cpu["optimize"]
    return Run(n, consecutive, candidates, loops, edges, solution, reckoned, radius, wall, cpu)


def check_align(drive: Drive, run: Run, settings: Settings, executor: Any) -> None:
    """align() end to end on the same prefix: its time, and whether it gives the pieces' poses and verdicts."""
    clouds = {k: kissm.batch.CloudFile(str(drive.files[k]), drive.formats[k]) for k in range(run.n)}
    with timed(run.wall, run.cpu, "align"):
        alignment = kissm.multiway.align(
            clouds,
            settings.voxel,
            pairs="sequence",
            loop_radius=settings.loop_radius,
            loop_gap=settings.loop_gap,
            loops_per_scan=settings.loops_per_scan,
            executor=executor,
            bound=settings.bound,
            progress=False,
            refine="gicp",
            threads_per_job=1,
            **settings.config,
        )
    run.align_same = (
        np.array_equal(alignment.poses, run.solution.poses, equal_nan=True)
        and [e.accepted for e in alignment.edges] == [bool(a) for a in run.solution.accepted]
        and alignment.registrations == len(run.consecutive) + len(run.loops)
    )


# ---- judging it ------------------------------------------------------------------------------------------------


def angle_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def pose_error(estimate: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """(degrees, metres) between two poses."""
    difference = np.linalg.inv(truth) @ estimate
    return angle_deg(difference[:3, :3]), float(np.linalg.norm(difference[:3, 3]))


def revisits(pairs: np.ndarray) -> np.ndarray:
    """A revisit label per true loop pair: pairs whose later scans and earlier scans are each within
    REVISIT_WINDOW scans of another pair's are one revisit (connected components), labelled 0, 1, ... by first j."""
    parent = list(range(len(pairs)))

    def root(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    order = np.lexsort((pairs[:, 0], pairs[:, 1])) if len(pairs) else np.zeros(0, dtype=np.int64)
    ordered = pairs[order]
    for a in range(len(ordered)):
        # ordered by j: only the following pairs with j within the window can join this one
        b = a + 1
        while b < len(ordered) and ordered[b, 1] - ordered[a, 1] <= REVISIT_WINDOW:
            if abs(int(ordered[b, 0]) - int(ordered[a, 0])) <= REVISIT_WINDOW:
                parent[root(b)] = root(a)
            b += 1
    roots = [root(a) for a in range(len(ordered))]
    first: dict[int, int] = {}
    labels_ordered = np.array([first.setdefault(r, len(first)) for r in roots], dtype=np.int64)
    labels = np.zeros(len(pairs), dtype=np.int64)
    labels[order] = labels_ordered
    return labels


def near_pairs(pairs: np.ndarray, edges: Sequence[tuple[int, int]]) -> np.ndarray:
    """(E, L) bool: edge (source, target), source later, lies within REVISIT_WINDOW scans of true pair (i, j)."""
    if not edges or not len(pairs):
        return np.zeros((len(edges), len(pairs)), dtype=bool)
    e = np.array(edges, dtype=np.int64)
    later, earlier = e.max(axis=1), e.min(axis=1)
    near: np.ndarray = (np.abs(later[:, None] - pairs[None, :, 1]) <= REVISIT_WINDOW) & (
        np.abs(earlier[:, None] - pairs[None, :, 0]) <= REVISIT_WINDOW
    )
    return near


def fitted(points: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """points moved by the rigid motion that brings them closest to truth in the least-squares sense (Horn)."""
    mean_p, mean_t = points.mean(axis=0), truth.mean(axis=0)
    u, _, vt = np.linalg.svd((points - mean_p).T @ (truth - mean_t))
    flip = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(vt.T @ u.T)))])
    rotation = vt.T @ flip @ u.T
    moved: np.ndarray = (points - mean_p) @ rotation.T + mean_t
    return moved


def trajectory(
    poses: np.ndarray, truth: np.ndarray, reached: np.ndarray, pairs: np.ndarray
) -> dict[str, float | int | None]:
    """ATE (RMSE and max of the positions, max rotation) anchored on scan 0 and after the best rigid fit of the
    positions, and the relative pose error over RPE_LENGTH_M stretches of the true path, over the scans reached
    (both poses anchored on scan 0); and the error of the relative pose between the scans of each true loop pair
    (how well the map agrees with itself where the drive comes back)."""
    out: dict[str, float | int | None] = {"reached": int(reached.sum())}
    keys = ["ate_rmse", "ate_max", "fit_rmse", "fit_max", "rot_max", "rpe_pct", "rpe_deg"]
    keys += ["pair_deg_median", "pair_deg_max", "pair_m_median", "pair_m_max"]
    if not reached.any():
        return out | dict.fromkeys(keys)
    d = np.linalg.norm(poses[reached, :3, 3] - truth[reached, :3, 3], axis=1)
    f = np.linalg.norm(fitted(poses[reached, :3, 3], truth[reached, :3, 3]) - truth[reached, :3, 3], axis=1)
    rot = [pose_error(poses[k], truth[k])[0] for k in np.flatnonzero(reached)]
    path = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(truth[:, :3, 3], axis=0), axis=1))])
    rpe_t, rpe_r = [], []
    for k in range(len(truth)):
        m = int(np.searchsorted(path, path[k] + RPE_LENGTH_M))
        if m >= len(truth) or not (reached[k] and reached[m]):
            continue
        estimate = np.linalg.inv(poses[k]) @ poses[m]
        exact = np.linalg.inv(truth[k]) @ truth[m]
        degrees, metres = pose_error(estimate, exact)
        length = float(path[m] - path[k])
        rpe_t.append(100.0 * metres / length)
        rpe_r.append(degrees * RPE_LENGTH_M / length)
    both = [(int(i), int(j)) for i, j in pairs if reached[i] and reached[j]]
    errors = np.array(
        [pose_error(np.linalg.inv(poses[i]) @ poses[j], np.linalg.inv(truth[i]) @ truth[j]) for i, j in both]
    ).reshape(-1, 2)
    return out | {
        "pair_deg_median": float(np.median(errors[:, 0])) if len(both) else None,
        "pair_deg_max": float(errors[:, 0].max()) if len(both) else None,
        "pair_m_median": float(np.median(errors[:, 1])) if len(both) else None,
        "pair_m_max": float(errors[:, 1].max()) if len(both) else None,
        "ate_rmse": float(np.sqrt(np.mean(d**2))),
        "ate_max": float(d.max()),
        "fit_rmse": float(np.sqrt(np.mean(f**2))),
        "fit_max": float(f.max()),
        "rot_max": max(rot),
        "rpe_pct": float(np.mean(rpe_t)) if rpe_t else None,
        "rpe_deg": float(np.mean(rpe_r)) if rpe_r else None,
    }


def judge(drive: Drive, run: Run, settings: Settings) -> dict[str, Any]:
    """Everything the page reports about one prefix."""
    n, voxel, gap = run.n, settings.voxel, settings.loop_gap
    world = drive.poses[:n]
    truth = np.linalg.inv(world[0]) @ world
    solution = run.solution
    accepted = np.asarray(solution.accepted, dtype=bool)

    def wrong(source: int, target: int, transform: np.ndarray) -> bool:
        degrees, metres = pose_error(transform, np.linalg.inv(world[target]) @ world[source])
        return degrees > MAX_ANGLE_DEG or metres > MAX_VOXELS * voxel

    is_loop = np.array([abs(s - t) >= gap for s, t, _ in run.edges], dtype=bool)
    is_wrong = np.array([wrong(s, t, transform) for s, t, transform in run.edges], dtype=bool)
    good = accepted & is_loop & ~is_wrong  # accepted right loop edges

    out: dict[str, Any] = {
        "scans": n,
        "consecutive": len(run.consecutive),
        "candidates": len(run.loops),
        "valid_consecutive": int((~is_loop).sum()),
        "valid_loops": int(is_loop.sum()),
        "accepted_consecutive": int((accepted & ~is_loop).sum()),
        "accepted_loops": int((accepted & is_loop).sum()),
        "rejected_consecutive": int((~accepted & ~is_loop).sum()),
        "rejected_loops": int((~accepted & is_loop).sum()),
        "placed": int(np.asarray(solution.placed).sum()),
        "wrong_valid_consecutive": int((is_wrong & ~is_loop).sum()),
        "wrong_valid_loops": int((is_wrong & is_loop).sum()),
        "wrong_accepted_consecutive": int((is_wrong & accepted & ~is_loop).sum()),
        "false_loops": int((is_wrong & accepted & is_loop).sum()),
        "right_loops_rejected": int((~is_wrong & ~accepted & is_loop).sum()),
        "radius": run.radius,
    }
    wrong_list = [
        (s, t, *pose_error(transform, np.linalg.inv(world[t]) @ world[s]), bool(a))
        for (s, t, transform), w, a in zip(run.edges, is_wrong, accepted, strict=True)
        if w
    ]
    out["wrong_edges"] = [
        {"source": s, "target": t, "deg": d, "m": m, "accepted": a, "loop": abs(s - t) >= gap}
        for s, t, d, m, a in wrong_list
    ]

    # the true loops within the prefix, and what each stage made of them
    pairs = drive.loops[(drive.loops < n).all(axis=1)]
    labels = revisits(pairs)
    count = int(labels.max()) + 1 if len(labels) else 0
    candidate_pairs = [(position(r.source), position(r.target)) for r in run.loops]
    valid_loop_pairs = [e for e, loop in zip(run.edges, is_loop, strict=True) if loop]
    good_pairs = [(s, t) for (s, t, _), g in zip(run.edges, good, strict=True) if g]
    stages = {
        "candidate": near_pairs(pairs, candidate_pairs).any(axis=0),
        "valid": near_pairs(pairs, [(s, t) for s, t, _ in valid_loop_pairs]).any(axis=0),
        "found": near_pairs(pairs, good_pairs).any(axis=0),
    }
    per_revisit = {stage: np.zeros(count, dtype=bool) for stage in stages}
    for stage, hit in stages.items():
        np.logical_or.at(per_revisit[stage], labels, hit)
    out["true_pairs"] = len(pairs)
    out["revisits"] = count
    out["revisits_with_candidate"] = int(per_revisit["candidate"].sum())
    out["revisits_with_valid"] = int(per_revisit["valid"].sum())
    out["revisits_found"] = int(per_revisit["found"].sum())

    # (b) true-loop scans j with an accepted, right loop edge to an earlier scan within LOOP_DISTANCE_M
    loop_scans = np.unique(pairs[:, 1]) if len(pairs) else np.zeros(0, dtype=np.int64)
    sensor = world[:, :3, 3]
    closed = set()
    for s, t in good_pairs:
        later, earlier = max(s, t), min(s, t)
        if np.linalg.norm(sensor[later] - sensor[earlier]) <= LOOP_DISTANCE_M:
            closed.add(later)
    out["loop_scans"] = len(loop_scans)
    out["loop_scans_closed"] = sum(1 for j in loop_scans.tolist() if j in closed)
    near = {
        "candidates": near_pairs(pairs, candidate_pairs),
        "valid": near_pairs(pairs, [(s, t) for s, t, _ in valid_loop_pairs]),
        "accepted right": near_pairs(pairs, good_pairs),
    }
    out["revisit_rows"] = [
        {
            "j": [int(pairs[labels == r, 1].min()), int(pairs[labels == r, 1].max())],
            "i": [int(pairs[labels == r, 0].min()), int(pairs[labels == r, 0].max())],
            "pairs": int((labels == r).sum()),
            "later_scans": len(np.unique(pairs[labels == r, 1])),
            "closed": sum(1 for j in np.unique(pairs[labels == r, 1]).tolist() if j in closed),
            **{stage: int(hits[:, labels == r].any(axis=1).sum()) for stage, hits in near.items()},
        }
        for r in range(count)
    ]
    in_table = {(int(i), int(j)) for i, j in pairs}
    out["accepted_loops_true_pair"] = sum(1 for s, t in good_pairs if (min(s, t), max(s, t)) in in_table)

    # missed revisits: where they were lost
    positions, path, piece = run.dead_reckoned
    missed = []
    for r in range(count):
        if per_revisit["found"][r]:
            continue
        members = pairs[labels == r]
        gt = np.linalg.norm(sensor[members[:, 1]] - sensor[members[:, 0]], axis=1)
        reckoned = np.linalg.norm(positions[members[:, 1]] - positions[members[:, 0]], axis=1)
        allowed = run.radius + DRIFT * np.abs(path[members[:, 1]] - path[members[:, 0]])
        same_piece = piece[members[:, 1]] == piece[members[:, 0]]
        best = int(np.argmin(reckoned - allowed))
        stage = (
            "valid, none accepted right"
            if per_revisit["valid"][r]
            else "candidates, none valid"
            if per_revisit["candidate"][r]
            else "no candidate"
        )
        missed.append(
            {
                "j": [int(members[:, 1].min()), int(members[:, 1].max())],
                "i": [int(members[:, 0].min()), int(members[:, 0].max())],
                "pairs": len(members),
                "gt_min_m": float(gt.min()),
                "reckoned_m": float(reckoned[best]),
                "allowed_m": float(allowed[best]),
                "same_piece": bool(same_piece.all()),
                "stage": stage,
            }
        )
    out["missed"] = missed

    # the trajectory: the graph's, and the consecutive registrations chained (dead reckoning)
    placed = np.asarray(solution.placed, dtype=bool)
    out["graph"] = trajectory(solution.poses, truth, placed, pairs)
    chained = np.full((n, 4, 4), np.nan)
    chained[0] = np.eye(4)
    steps = {position(r.target): r.result for r in run.consecutive}
    for k in range(n - 1):
        step = steps.get(k)
        if step is None or not step.valid:
            break
        chained[k + 1] = chained[k] @ np.asarray(step.transform, dtype=np.float64)
    out["dead_reckoning"] = trajectory(chained, truth, np.isfinite(chained).all(axis=(1, 2)), pairs)
    ok = [
        placed[k] and max(pose_error(solution.poses[k], truth[k]) / np.array([MAX_ANGLE_DEG, MAX_VOXELS * voxel])) <= 1
        for k in range(n)
    ]
    out["placed_within_tolerance"] = int(sum(ok))
    path_true = float(np.sum(np.linalg.norm(np.diff(truth[:, :3, 3], axis=0), axis=1)))
    out["path_m"] = path_true
    out["wall"] = dict(run.wall)
    out["cpu"] = dict(run.cpu)
    out["align_same"] = run.align_same
    return out


# ---- the page --------------------------------------------------------------------------------------------------


def fmt(value: float | int | None, digits: int = 2) -> str:
    if value is None:
        return "–"
    if isinstance(value, int):
        return str(value)
    return f"{value:.{digits}f}"


def page(meta: dict[str, Any], results: list[dict[str, Any]]) -> str:
    machine = meta["machine"]
    s = meta["settings"]
    lines = [
        '# Multiway registration on a simulated drive (issue 34, "Sequence")',
        "",
        f"Command: `{meta['command']}`",
        "",
        f"Drive: `{meta['drive']}`; started {meta['started']}, {meta['duration_s'] / 60:.1f} min; load average "
        f"{meta['load_start'][0]:.2f} at the start, {meta['load_end'][0]:.2f} at the end. Machine: "
        f"{machine.get('cpu', '?')}, {machine.get('cpus_online')} CPUs, {machine.get('mem_total_gb')} GB; "
        f"{machine.get('platform')}; Python {machine.get('python')}; kissm {machine.get('packages', {}).get('kissm')}"
        f" (library `{machine.get('kissm_library')}`, checkout {machine.get('git')}).",
        "",
        f'Settings: voxel {s["voxel"]} m, GICP, `pairs="sequence"`, loop_radius '
        f"{s['loop_radius'] if s['loop_radius'] is not None else 'default (30 voxels)'} + {100 * DRIFT:g}% of the "
        f"dead-reckoned path between, loop_gap {s['loop_gap']}, loops_per_scan {s['loops_per_scan']}, "
        f"{s['jobs']} jobs (ThreadPoolExecutor, 1 thread each){', ' + str(s['config']) if s['config'] else ''}.",
        "",
        "## Registrations and graph",
        "",
        "| scans | path m | registrations (consecutive + loop candidates) | valid (consecutive / loop) "
        "| accepted (consecutive / loop) | rejected (consecutive / loop) | placed | placed within 2° and 2 voxels |",
        "|--:|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for r in results:
        lines.append(
            f"| {r['scans']} | {r['path_m']:.0f} | {r['consecutive'] + r['candidates']} ({r['consecutive']} + "
            f"{r['candidates']}) | {r['valid_consecutive']} / {r['valid_loops']} | {r['accepted_consecutive']} / "
            f"{r['accepted_loops']} | {r['rejected_consecutive']} / {r['rejected_loops']} | {r['placed']} | "
            f"{r['placed_within_tolerance']} |"
        )
    lines += [
        "",
        "## Loops",
        "",
        f"True pairs: loops.tsv's pairs with both scans in the prefix. A revisit groups true pairs whose later and "
        f"earlier scans are each within {REVISIT_WINDOW} scans of another's; it is found when an accepted loop edge "
        f"that is right (within 2° and 2 voxels of the exact relative pose) lies within {REVISIT_WINDOW} scans of "
        f"one of its pairs at both ends. Loop scans closed: the later scans of true pairs with an accepted right "
        f"loop edge to an earlier scan within {LOOP_DISTANCE_M:.0f} m. Wrong: more than 2° or 2 voxels off.",
        "",
        "| scans | true pairs | revisits | with a candidate | with a valid loop | found | loop scans closed "
        "| accepted loops on true pairs | wrong valid (consecutive / loop) | false loops accepted "
        "| right loops rejected |",
        "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for r in results:
        share = f" ({100 * r['loop_scans_closed'] / r['loop_scans']:.0f}%)" if r["loop_scans"] else ""
        lines.append(
            f"| {r['scans']} | {r['true_pairs']} | {r['revisits']} | {r['revisits_with_candidate']} | "
            f"{r['revisits_with_valid']} | **{r['revisits_found']} of {r['revisits']}** | {r['loop_scans_closed']} "
            f"of {r['loop_scans']}{share} | {r['accepted_loops_true_pair']} of {r['accepted_loops']} | "
            f"{r['wrong_valid_consecutive']} / {r['wrong_valid_loops']} | **{r['false_loops']}** | "
            f"{r['right_loops_rejected']} |"
        )
    lines += [
        "",
        "## Trajectory error",
        "",
        "Graph: `align`'s poses; dead reckoning: the consecutive registrations chained. ATE: the positions' error "
        "anchored on scan 0 (no other alignment), and after the best rigid fit of all positions (Horn); rotation: "
        f"the largest anchored rotation error. RPE: the mean relative pose error over stretches of "
        f"{RPE_LENGTH_M:.0f} m of the true path (translation in % of the stretch, rotation in degrees per 100 m). "
        "Loop pairs: the error of the relative pose between the two scans of every true loop pair, median and "
        "largest (how well the map agrees with itself where the drive comes back).",
        "",
        "| scans | trajectory | ATE RMSE m | ATE max m | fitted ATE RMSE m | fitted max m | rotation max ° | RPE % "
        "| RPE °/100 m | loop pairs: median ° / m | largest ° / m |",
        "|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for r in results:
        for label, g in (("graph", r["graph"]), ("dead reckoning", r["dead_reckoning"])):
            pair_median = (
                f"{fmt(g['pair_deg_median'], 3)} / {fmt(g['pair_m_median'], 3)}"
                if g["pair_m_median"] is not None
                else "–"
            )
            pair_max = (
                f"{fmt(g['pair_deg_max'], 3)} / {fmt(g['pair_m_max'], 3)}" if g["pair_m_max"] is not None else "–"
            )
            lines.append(
                f"| {r['scans']} | {label} | {fmt(g['ate_rmse'], 3)} | {fmt(g['ate_max'], 3)} | "
                f"{fmt(g['fit_rmse'], 3)} | {fmt(g['fit_max'], 3)} | {fmt(g['rot_max'], 3)} | "
                f"{fmt(g['rpe_pct'], 3)} | {fmt(g['rpe_deg'], 3)} | {pair_median} | {pair_max} |"
            )
    lines += [
        "",
        "## Times",
        "",
        'Wall seconds of each piece of `align(pairs="sequence")` run one by one (describe: every scan\'s features, '
        "read from its PLY; consecutive and loops: the registrations on the features; candidates: the chained "
        "odometry and the loop candidates; graph: adding the edges, then `optimize()`); `align()`: the same "
        "end to end (its poses and verdicts equal the pieces' bit for bit: the last column). CPU: the process's "
        "CPU seconds (all threads) of the pieces; per registration: the CPU of the consecutive and loop "
        "registrations over their number.",
        "",
        "| scans | describe | consecutive | candidates | loops | graph build | optimize | pieces total | "
        "pieces s/scan | registrations/scan | CPU s/scan | CPU ms/registration | align() | align() s/scan "
        "| same bits | load before / after |",
        "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for r in results:
        w, c = r["wall"], r["cpu"]
        pieces = [w[k] for k in ("describe", "consecutive", "candidates", "loops", "graph build", "optimize")]
        total, cpu_total = sum(pieces), sum(c[k] for k in c if k != "align")
        registrations = r["consecutive"] + r["candidates"]
        per_registration = 1000 * (c["consecutive"] + c["loops"]) / registrations if registrations else None
        align = w.get("align")
        same = {None: "–", True: "yes", False: "**no**"}[r["align_same"]]
        lines.append(
            f"| {r['scans']} | {w['describe']:.1f} | {w['consecutive']:.1f} | {w['candidates']:.2f} | "
            f"{w['loops']:.1f} | {w['graph build']:.2f} | {w['optimize']:.2f} | {total:.1f} | "
            f"{total / r['scans']:.3f} | {registrations / r['scans']:.2f} | {cpu_total / r['scans']:.3f} | "
            f"{fmt(per_registration, 1)} | {fmt(align, 1)} | "
            f"{fmt(align / r['scans'] if align is not None else None, 3)} | {same} | "
            f"{r['load_before']:.1f} / {r['load_after']:.1f} |"
        )
    last = results[-1]
    if last["revisit_rows"]:
        lines += [
            "",
            f"## Revisits ({last['scans']} scans)",
            "",
            "Per revisit: its later and earlier scans, its true pairs and later scans, the loop candidates, valid "
            f"loop registrations and accepted right loop edges within {REVISIT_WINDOW} scans of one of its pairs, and "
            "its later scans closed (an accepted right loop edge to an earlier scan within "
            f"{LOOP_DISTANCE_M:.0f} m).",
            "",
            "| later scans | earlier scans | true pairs | distinct later scans | candidates | valid | accepted right "
            "| later scans closed |",
            "|---|---|--:|--:|--:|--:|--:|--:|",
        ]
        for v in last["revisit_rows"]:
            lines.append(
                f"| {v['j'][0]}–{v['j'][1]} | {v['i'][0]}–{v['i'][1]} | {v['pairs']} | {v['later_scans']} | "
                f"{v['candidates']} | {v['valid']} | {v['accepted right']} | {v['closed']} of {v['later_scans']} |"
            )
    for r in results:
        if r["missed"]:
            lines += [
                "",
                f"## Revisits missed ({r['scans']} scans)",
                "",
                "Reckoned / allowed: the dead-reckoned distance of the revisit's pair closest to being a candidate, "
                "and the radius it had to be within.",
                "",
                "| later scans | earlier scans | true pairs | closest m (truth) | reckoned m | allowed m "
                "| same piece | lost at |",
                "|---|---|--:|--:|--:|--:|---|---|",
            ]
            for m in r["missed"]:
                lines.append(
                    f"| {m['j'][0]}–{m['j'][1]} | {m['i'][0]}–{m['i'][1]} | {m['pairs']} | {m['gt_min_m']:.1f} | "
                    f"{m['reckoned_m']:.1f} | {m['allowed_m']:.1f} | {'yes' if m['same_piece'] else 'no'} | "
                    f"{m['stage']} |"
                )
        if r["wrong_edges"]:
            lines += [
                "",
                f"## Wrong valid registrations ({r['scans']} scans)",
                "",
                "| source | target | loop | error ° | error m | accepted |",
                "|--:|--:|---|--:|--:|---|",
            ]
            for e in r["wrong_edges"]:
                lines.append(
                    f"| {e['source']} | {e['target']} | {'yes' if e['loop'] else 'no'} | {e['deg']:.2f} | "
                    f"{e['m']:.2f} | {'**yes**' if e['accepted'] else 'no'} |"
                )
    return "\n".join(lines) + "\n"


# ---- the command -----------------------------------------------------------------------------------------------


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = argparse.ArgumentParser(
        description=(__doc__ or "").split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--drive", type=Path, help="an existing simulated drive (kissm simulate's OUTDIR)")
    source.add_argument("--scans", type=int, help="simulate a drive of this many scans with --kissm into a temp dir")
    parser.add_argument("--seed", type=int, default=1, help="with --scans: the drive's seed (1)")
    parser.add_argument("--spacing", type=float, help="with --scans: metres between scans (the CLI's default, 2)")
    parser.add_argument("--kissm", default="kissm", help="with --scans: the kissm CLI (default: kissm on PATH)")
    parser.add_argument("--workdir", type=Path, help="with --scans: where the temp dir goes (the system's)")
    parser.add_argument("--voxel", type=float, default=0.5, help="voxel size, m (0.5)")
    parser.add_argument("--jobs", type=int, default=2, help="ThreadPoolExecutor workers, 1 thread each (2)")
    parser.add_argument("--prefix", type=int, nargs="+", help="run on the first N scans for each N (all scans)")
    parser.add_argument("--loop-radius", type=float, help="align's loop_radius, m (default: 30 voxels)")
    parser.add_argument("--loop-gap", type=int, default=10, help="align's loop_gap (10)")
    parser.add_argument("--loops-per-scan", type=int, default=5, help="align's loops_per_scan (5)")
    parser.add_argument(
        "--bound",
        type=float,
        default=kissm.PoseGraph.DEFAULT_BOUND,
        help=f"align's bound, the pose graph's rejection threshold ({kissm.PoseGraph.DEFAULT_BOUND})",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="another kissm.Config field for the registrations (a number or a word), repeatable",
    )
    parser.add_argument("--no-align", action="store_true", help="skip align() end to end (the pieces only)")
    parser.add_argument("--out", type=Path, help="write the Markdown page here (else print it)")
    parser.add_argument("--json", type=Path, help="also write the results as JSON here")
    args = parser.parse_args(argv)
    config: dict[str, Any] = {}
    for item in args.set:
        name, _, value = item.partition("=")
        try:
            config[name] = json.loads(value)
        except json.JSONDecodeError:
            config[name] = value
    settings = Settings(args.voxel, args.loop_radius, args.loop_gap, args.loops_per_scan, args.jobs, args.bound, config)
    t0 = time.monotonic()
    with contextlib.ExitStack() as stack:
        if args.drive is not None:
            folder: Path = args.drive
        else:
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="kissm-drive-", dir=args.workdir)))
            simulate(args.kissm, folder, args.scans, args.seed, args.spacing)
        drive = read_drive(folder)
        total = len(drive.files)
        prefixes = args.prefix or [total]
        if any(p < 2 or p > total for p in prefixes):
            parser.error(f"--prefix: each N must be in [2, {total}] (the drive has {total} scans)")
        meta = run_meta("drive_bench.py", argv, args, drive=str(folder), settings=dataclasses.asdict(settings))
        executor = stack.enter_context(cf.ThreadPoolExecutor(args.jobs)) if args.jobs > 0 else None
        results = []
        for n in prefixes:
            load = os.getloadavg()[0]
            run = run_prefix(drive, n, settings, executor)
            if not args.no_align:
                check_align(drive, run, settings, executor)
            result = judge(drive, run, settings)
            result["load_before"] = load
            result["load_after"] = os.getloadavg()[0]
            results.append(result)
            pieces = sum(v for k, v in run.wall.items() if k != "align")
            print(
                f"drive: {n} scans: {result['revisits_found']} of {result['revisits']} revisits found, "
                f"{result['false_loops']} false loops, {result['placed']} placed, ATE RMSE "
                f"{fmt(result['graph']['ate_rmse'], 3)} m, pieces {pieces:.1f} s, align "
                f"{fmt(run.wall.get('align'), 1)} s, same bits {run.align_same}",
                file=sys.stderr,
            )
            del run
    finish_meta(meta, t0)
    text = page(meta, results)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
    else:
        print(text, end="")
    if args.json is not None:
        args.json.write_text(json.dumps({"meta": meta, "results": results}, indent=1, default=str), encoding="utf-8")
    failed = any(r["false_loops"] or r["align_same"] is False for r in results)
    return 1 if failed else 0
