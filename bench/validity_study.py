#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The evidence behind the validity rule: every registration of the real-data pairs (raw and with the source
turned by 3 random rotations, fixed seed) and of the committed synthetic pair (target turned about z every
15 degrees and moved), with the pose error and the fields a validity rule can read (final inliers, inlier
extent in voxels, inlier ratio) and, with --overlap, the aligned overlap of the estimated and of the
true pose (the share of the voxelised source within 2 voxels of a voxelised target point). A row marked
WRONG-VALID is a wrong pose reported valid: the worst bug kissm can ship. docs/accuracy.md quotes the
output.

    python3 bench/validity_study.py [--data ../shared/data] [--threads 2] [--overlap]

Needs the kissm Python package (e.g. build/venv-python from bindings/python/run_tests.sh) and numpy.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import kissm

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "bindings" / "python" / "tests"))
import realdata  # noqa: E402  (the pairs and success thresholds of the real-data tests)


def rotation_error_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(a.T @ b) - 1.0) / 2.0))))


def axis_angle(axis: np.ndarray, deg: float) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = math.radians(deg)
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def voxel_centres(points: np.ndarray, voxel: float) -> np.ndarray:
    """One point per occupied voxel (the first), as a stand-in for the library's centroids."""
    _, first = np.unique(np.floor(points / voxel).astype(np.int64), axis=0, return_index=True)
    return points[np.sort(first)]


def aligned_overlap(source: np.ndarray, target: np.ndarray, pose: np.ndarray, voxel: float) -> float:
    """Share of the voxelised source that `pose` lays within 2 voxels of a voxelised target point."""
    radius = 2.0 * voxel
    src = voxel_centres(source, voxel) @ pose[:3, :3].T + pose[:3, 3]
    tgt = voxel_centres(target, voxel)
    cells: dict[tuple[int, int, int], list[int]] = {}
    for i, key in enumerate(map(tuple, np.floor(tgt / radius).astype(np.int64))):
        cells.setdefault(key, []).append(i)
    offsets = [(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)]
    hits = 0
    for p, (cx, cy, cz) in zip(src, np.floor(src / radius).astype(np.int64)):
        near = [i for dx, dy, dz in offsets for i in cells.get((cx + dx, cy + dy, cz + dz), ())]
        hits += bool(near) and float(np.min(np.sum((tgt[near] - p) ** 2, axis=1))) <= radius * radius
    return hits / len(src)


def run(name, source, target, gt, voxel, max_rot, max_trans, threads, overlap=False):
    r = kissm.register(source, target, voxel_size=voxel, num_threads=threads)
    t = np.asarray(r.transform)
    if not np.isfinite(t).all():
        print(f"{name:58s} valid={int(r.valid)} inliers={r.num_final_inliers:4d} (no pose: {r.reason})")
        return
    e_rot = rotation_error_deg(t[:3, :3], gt[:3, :3])
    e_trans = float(np.linalg.norm(t[:3, 3] - gt[:3, 3]))
    right = e_rot <= max_rot and e_trans <= max_trans
    extent = " ".join(f"{x / voxel:5.1f}" for x in r.inlier_extent)
    flag = "  WRONG-VALID" if r.valid and not right else ""
    if overlap:
        flag = (
            f"  overlap {aligned_overlap(source, target, t, voxel):.3f}"
            f" (true pose {aligned_overlap(source, target, gt, voxel):.3f}){flag}"
        )
    print(
        f"{name:58s} valid={int(r.valid)} inliers={r.num_final_inliers:4d} error {e_rot:7.2f} deg {e_trans:7.3f} m "
        f"{'right' if right else 'wrong'}  extent/voxel {extent}  ratio {r.inlier_ratio:.3f}{flag}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=REPO.parent / "shared" / "data")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--overlap", action="store_true", help="also the aligned overlap (slow: pure Python)")
    args = parser.parse_args()
    ov = args.overlap
    rng = np.random.default_rng(12345)
    if (args.data / "index.tsv").is_file():
        for p in realdata.load_pairs(args.data):
            src = kissm.read_points(p.source, format=p.source_format)
            tgt = kissm.read_points(p.target, format=p.target_format)
            k = p.kind
            run(f"{p.name} raw", src, tgt, p.gt, k.voxel, k.max_rot_deg, k.max_trans_m, args.threads, ov)
            for i in range(3):
                turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
                gt = p.gt.copy()
                gt[:3, :3] = p.gt[:3, :3] @ turn.T  # the source turned by `turn`
                run(f"{p.name} rot{i}", src @ turn.T, tgt, gt, k.voxel, k.max_rot_deg, k.max_trans_m, args.threads, ov)
    else:
        print(f"(no real data at {args.data})")
    data = REPO / "tests" / "data"
    src = kissm.read_points(data / "roundtrip_source.ply")
    tgt = kissm.read_points(data / "roundtrip_target.ply")
    truth = np.loadtxt(data / "roundtrip_ground_truth.txt")
    shift = np.array([10.0, -5.0, 1.0])
    for yaw in range(0, 360, 15):
        turn = axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
        gt = np.eye(4)
        gt[:3, :3] = turn @ truth[:3, :3]
        gt[:3, 3] = turn @ truth[:3, 3] + shift
        run(f"synthetic pair, target yaw {yaw}", src, tgt @ turn.T + shift, gt, 0.25, 5.0, 0.3, args.threads, ov)
    return 0


if __name__ == "__main__":
    sys.exit(main())
