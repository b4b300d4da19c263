# SPDX-License-Identifier: MIT
"""The pose-graph benchmark (``python bench/pose_graph_bench.py --help``): kissm's optimiser against GTSAM 4.3's
Levenberg-Marquardt on the same synthetic drives (a spiral of loops: odometry from each pose to the next, trusted,
and a loop closure every 7 poses to the pose 100 ahead, robust), with noise on every edge and, optionally, a share of
the loop closures replaced by far-off poses with the same confident information.

With --shared-sets it instead aligns the shared multi-scan sets (kissm.multiway.align, every pair, GICP) and adds
wrong edges to each set's accepted ones: as many as 30% of its valid registrations, between random scans, random
poses (0.2 rad to a half turn, 50 voxels) with the information of a real edge; over --seeds runs it counts the
wrong edges accepted, the right ones rejected, and the scans not placed or moved by more than 0.1 degree or 0.1
voxel from where the right edges alone put them; and it times the right edges' graph alone, kissm against GTSAM's
Levenberg-Marquardt (started from a breadth-first tree; medians of 5), with the largest difference of their poses.

Per graph it prints the nodes and edges, kissm's time, GTSAM's time (started from the chained odometry, anchored
by a prior of sigma 1e-10, tolerances 1e-12), the largest difference between their poses (entries of the 3x4
matrices; GTSAM is given the edges kissm accepted, whose optimum kissm's must be), and with outliers how many wrong
edges kissm accepted and how many right ones it rejected. Times are
medians of --repeats runs, the two optimisers alternating in one process.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from typing import Any

import kissm
import numpy as np

SIGMA_ROTATION, SIGMA_TRANSLATION = 0.01, 0.1  # per edge: rad, m
INFORMATION = np.diag([1 / SIGMA_ROTATION**2] * 3 + [1 / SIGMA_TRANSLATION**2] * 3)


def exp_rotation(w: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(w))
    if angle < 1e-15:
        return np.eye(3)
    k = w / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    rotation: np.ndarray = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    return rotation


def rigid(w: np.ndarray, t: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = exp_rotation(w)
    m[:3, 3] = t
    return m


def drive(n: int, outliers: float, seed: int) -> tuple[list[tuple[int, int, np.ndarray, bool]], np.ndarray]:
    """Edges (source, target, transform, robust) of a spiral drive of n poses, and which edges are wrong."""
    rng = np.random.default_rng(seed)
    poses = []
    for i in range(n):
        a = 2 * math.pi * i / 100
        poses.append(rigid(np.array([0.0, 0.0, a]), np.array([30 * math.cos(a) + 0.01 * i, 30 * math.sin(a), 0.0])))

    def noisy(s: int, t: int) -> np.ndarray:
        noise = rigid(rng.normal(0, SIGMA_ROTATION, 3), rng.normal(0, SIGMA_TRANSLATION, 3))
        measured: np.ndarray = np.linalg.inv(poses[t]) @ poses[s] @ noise
        return measured

    edges: list[tuple[int, int, np.ndarray, bool]] = [(i + 1, i, noisy(i + 1, i), False) for i in range(n - 1)]
    wrong = [False] * len(edges)
    for i in range(0, n - 100, 7):
        transform = noisy(i, i + 100)
        bad = rng.random() < outliers
        if bad:
            transform = transform @ rigid(rng.normal(0, 1.0, 3), rng.normal(0, 10.0, 3))
        edges.append((i, i + 100, transform, True))
        wrong.append(bad)
    return edges, np.array(wrong)


def run_kissm(n: int, edges: list[tuple[int, int, np.ndarray, bool]]) -> tuple[float, kissm.PoseGraphSolution]:
    with kissm.PoseGraph(n) as graph:
        for s, t, transform, robust in edges:
            graph.add_edge(s, t, transform, INFORMATION, robust=robust)
        start = time.perf_counter()
        solution = graph.optimize(anchor=0)
        return time.perf_counter() - start, solution


def gtsam_lm(graph: Any, initial: Any, n: int) -> tuple[float, np.ndarray]:
    """GTSAM's Levenberg-Marquardt (tolerances 1e-12, at most 100 iterations): its time and the n poses."""
    import gtsam  # benchmarks and tests only

    params = gtsam.LevenbergMarquardtParams()
    params.setRelativeErrorTol(1e-12)
    params.setAbsoluteErrorTol(1e-12)
    params.setMaxIterations(100)
    start = time.perf_counter()
    result = gtsam.LevenbergMarquardtOptimizer(graph, initial, params).optimize()
    elapsed = time.perf_counter() - start
    return elapsed, np.array([result.atPose3(i).matrix() for i in range(n)])


def run_gtsam(n: int, edges: list[tuple[int, int, np.ndarray, bool]], keep: np.ndarray) -> tuple[float, np.ndarray]:
    import gtsam  # benchmarks and tests only

    noise = gtsam.noiseModel.Gaussian.Information(INFORMATION)
    graph = gtsam.NonlinearFactorGraph()
    odometry = {}
    for (s, t, transform, robust), k in zip(edges, keep, strict=True):
        if k:
            graph.add(gtsam.BetweenFactorPose3(t, s, gtsam.Pose3(transform), noise))
        if not robust:
            odometry[s] = transform
    graph.add(gtsam.PriorFactorPose3(0, gtsam.Pose3(), gtsam.noiseModel.Isotropic.Sigma(6, 1e-10)))
    initial = gtsam.Values()
    x = np.eye(4)
    initial.insert(0, gtsam.Pose3(x))
    for i in range(1, n):  # the edge i -> i - 1 states inv(X_{i-1}) X_i
        x = x @ odometry[i]
        initial.insert(i, gtsam.Pose3(x))
    return gtsam_lm(graph, initial, n)


def run_gtsam_real(n: int, edges: list[tuple[int, int, np.ndarray, np.ndarray]]) -> tuple[float, np.ndarray]:
    """GTSAM's Levenberg-Marquardt on real edges (source, target, transform, information), started from the poses
    composed along a breadth-first tree from node 0 (as a user without a spanning-tree start would)."""
    import gtsam  # benchmarks and tests only

    graph = gtsam.NonlinearFactorGraph()
    for s, t, transform, information in edges:
        noise = gtsam.noiseModel.Gaussian.Information(information)
        graph.add(gtsam.BetweenFactorPose3(t, s, gtsam.Pose3(transform), noise))
    graph.add(gtsam.PriorFactorPose3(0, gtsam.Pose3(), gtsam.noiseModel.Isotropic.Sigma(6, 1e-10)))
    poses: dict[int, np.ndarray] = {0: np.eye(4)}
    frontier = [0]
    while frontier:
        node = frontier.pop(0)
        for s, t, transform, _ in edges:  # transform = inv(X_t) X_s
            if t == node and s not in poses:
                poses[s] = poses[t] @ transform
                frontier.append(s)
            elif s == node and t not in poses:
                poses[t] = poses[s] @ np.linalg.inv(transform)
                frontier.append(t)
    initial = gtsam.Values()
    for i in range(n):
        initial.insert(i, gtsam.Pose3(poses[i]))
    return gtsam_lm(graph, initial, n)


def angle_deg(rotation: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def shared_sets(seeds: int) -> None:
    """Wrong edges added to the shared multi-scan sets' real ones (the module docstring)."""
    import kissm.batch
    import kissm.multiway

    from .common import default_data
    from .data import SCAN_SETS, read_scan_set

    print(
        "| set | real edges | wrong per run | runs bent | wrong accepted | right rejected | scans moved or unplaced "
        "| right edges alone: kissm ms | GTSAM LM ms | max pose difference |"
    )
    print("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|")
    for scan_set in SCAN_SETS:
        names, files, formats, _ = read_scan_set(default_data() / scan_set.folder)
        clouds = {n: kissm.batch.CloudFile(str(f), fmt) for n, f, fmt in zip(names, files, formats, strict=True)}
        alignment = kissm.multiway.align(clouds, scan_set.voxel, threads_per_job=2)
        n, voxel = len(names), scan_set.voxel
        real = [e for e in alignment.edges if e.accepted]
        count = max(2, round(0.3 * len(alignment.edges)))
        bent = accepted = rejected = moved = 0
        ours_ms, theirs_ms, gap = [], [], 0.0
        for _ in range(5):  # the graphs are small: medians of 5
            with kissm.PoseGraph(n) as graph:
                for e in real:
                    graph.add_edge(e.source, e.target, e.transform, e.information)
                start = time.perf_counter()
                solution = graph.optimize()
                ours_ms.append(1e3 * (time.perf_counter() - start))
            elapsed, theirs = run_gtsam_real(n, [(e.source, e.target, e.transform, e.information) for e in real])
            theirs_ms.append(1e3 * elapsed)
            gap = float(np.abs(solution.poses[:, :3, :] - theirs[:, :3, :]).max())
        for seed in range(seeds):
            rng = np.random.default_rng(seed)
            wrong = []
            for k in range(count):
                source, target = (int(v) for v in rng.choice(n, size=2, replace=False))
                axis = rng.normal(size=3)
                transform = rigid(axis / np.linalg.norm(axis) * rng.uniform(0.2, math.pi), rng.normal(0, 50 * voxel, 3))
                wrong.append((source, target, transform, real[k % len(real)].information))
            with kissm.PoseGraph(n) as clean, kissm.PoseGraph(n) as dirty:
                for e in real:
                    clean.add_edge(e.source, e.target, e.transform, e.information)
                    dirty.add_edge(e.source, e.target, e.transform, e.information)
                for source, target, transform, information in wrong:
                    dirty.add_edge(source, target, transform, information)
                reference, solution = clean.optimize(), dirty.optimize()
            run_accepted = int(np.asarray(solution.accepted[len(real) :]).sum())
            run_moved = 0
            for k in range(n):
                difference = np.linalg.inv(reference.poses[k]) @ solution.poses[k]
                far = angle_deg(difference[:3, :3]) > 0.1 or np.linalg.norm(difference[:3, 3]) > 0.1 * voxel
                run_moved += int(not solution.placed[k] or far)
            accepted += run_accepted
            rejected += int((~np.asarray(solution.accepted[: len(real)])).sum())
            moved += run_moved
            bent += int(run_accepted > 0 or run_moved > 0)
        print(
            f"| {scan_set.label} | {len(real)} | {count} | {bent} of {seeds} | {accepted} of {count * seeds} | "
            f"{rejected} of {len(real) * seeds} | {moved} of {n * seeds} | {statistics.median(ours_ms):.2f} | "
            f"{statistics.median(theirs_ms):.2f} | {gap:.1e} |"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--nodes", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--outliers", type=float, nargs="+", default=[0.0, 0.3], help="share of loop closures wrong")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--shared-sets", action="store_true", help="wrong edges added to the shared multi-scan sets")
    parser.add_argument("--seeds", type=int, default=20, help="runs per set with --shared-sets")
    args = parser.parse_args()
    if args.shared_sets:
        shared_sets(args.seeds)
        return 0
    print("| nodes | edges | wrong | kissm s | GTSAM LM s | max pose difference | wrong accepted | right rejected |")
    print("|--:|--:|--:|--:|--:|--:|--:|--:|")
    for n in args.nodes:
        for share in args.outliers:
            edges, wrong = drive(n, share, args.seed)
            ours, theirs = [], []
            for _ in range(args.repeats):
                t, solution = run_kissm(n, edges)
                ours.append(t)
                # GTSAM gets the edges kissm accepted: the optimum of those is what kissm's must equal.
                t, gtsam_poses = run_gtsam(n, edges, np.asarray(solution.accepted))
                theirs.append(t)
            difference = float(np.abs(solution.poses[:, :3, :] - gtsam_poses[:, :3, :]).max())
            accepted = np.asarray(solution.accepted)
            print(
                f"| {n} | {len(edges)} | {int(wrong.sum())} | {statistics.median(ours):.3f} | "
                f"{statistics.median(theirs):.3f} | {difference:.1e} | {int((accepted & wrong).sum())} | "
                f"{int((~accepted & ~wrong).sum())} |"
            )
    return 0
