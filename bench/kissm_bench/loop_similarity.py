# SPDX-License-Identifier: MIT
"""Loop candidates by similarity (``python bench/loop_similarity.py --help``; docs/multiway.md, "Loop candidates
by similarity"): on a simulated drive (``kissm simulate``), the recall of true loops among each scan's k most
similar earlier scans by ``Features.signature()``, and ``kissm.multiway.align(pairs="sequence")`` end to end with
the chain broken by dropped windows of scans, judged against the exact poses.

Recall: for each true-loop scan j (a later scan of loops.tsv), whether one of its k nearest earlier scans
i <= j - gap (``kissm._candidates.similar_candidates``) is a true partner of j. End to end: placed right is within
2 degrees and 2 voxels of the truth anchored on the first scan kept; a wrong registration is more than 2 degrees or
2 voxels off; a true-loop scan is closed when an accepted right edge joins it to a scan within 10 m at least 50
scans away.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import time
from collections.abc import Hashable, Sequence
from pathlib import Path
from typing import Any

import kissm
import kissm.batch
import kissm.multiway
import numpy as np
from kissm._candidates import similar_candidates

from .drive import LOOP_DISTANCE_M, MAX_ANGLE_DEG, MAX_VOXELS, angle_deg, position, read_drive

#: A closing edge's scans are at least this many scans apart (loops.tsv's 100 m at kissm simulate's 2 m spacing).
MIN_LOOP_SCANS = 50


def recall(signatures: np.ndarray, true: dict[int, set[int]], gap: int, k: int) -> float:
    apart = np.zeros(max(len(signatures) - 1, 0), dtype=np.uint8)  # every scan a piece of its own: no restriction
    pairs = similar_candidates(signatures, gap, k, apart)
    hit = {j for i, j in pairs if i in true.get(j, set())}
    return len(hit) / max(len(true), 1)


def end_to_end(
    features: dict[int, kissm.Features],
    poses: np.ndarray,
    true: dict[int, set[int]],
    voxel: float,
    similar: int,
    executor: cf.Executor,
) -> dict[str, object]:
    start = time.monotonic()
    alignment = kissm.multiway.align(features, voxel, pairs="sequence", similar_per_scan=similar, executor=executor)
    wall = time.monotonic() - start
    keys = [position(key) for key in alignment.keys]

    def wrong(source: int, target: int, transform: np.ndarray) -> bool:
        error = np.linalg.inv(np.linalg.inv(poses[target]) @ poses[source]) @ transform
        return angle_deg(error[:3, :3]) > MAX_ANGLE_DEG or float(np.linalg.norm(error[:3, 3])) > MAX_VOXELS * voxel

    valid = {(keys[e.source], keys[e.target]) for e in alignment.edges}
    breaks = [(keys[k], keys[k + 1]) for k in range(len(keys) - 1) if (keys[k + 1], keys[k]) not in valid]
    right = 0
    for k, key in enumerate(keys):
        if alignment.placed[k]:
            right += not wrong(key, keys[0], np.linalg.inv(alignment.poses[0]) @ alignment.poses[k])
    closed = set()
    for e in alignment.edges:
        source, target = keys[e.source], keys[e.target]
        if e.accepted and e.source != e.target + 1 and not wrong(source, target, e.transform):
            j, i = max(source, target), min(source, target)
            near = float(np.linalg.norm(poses[j][:3, 3] - poses[i][:3, 3])) <= LOOP_DISTANCE_M
            if j in true and j - i >= MIN_LOOP_SCANS and near:
                closed.add(j)
    return {
        "similar_per_scan": similar,
        "scans": len(keys),
        "breaks": breaks,
        "registrations": alignment.registrations,
        "valid": len(alignment.edges),
        "wrong_valid": sum(wrong(keys[e.source], keys[e.target], e.transform) for e in alignment.edges),
        "wrong_accepted": sum(
            e.accepted and wrong(keys[e.source], keys[e.target], e.transform) for e in alignment.edges
        ),
        "placed": int(alignment.placed.sum()),
        "placed_right": right,
        "true_loop_scans": len(true),
        "closed": len(closed),
        "wall_s": round(wall, 1),
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--drive", type=Path, required=True, help="a folder written by kissm simulate")
    parser.add_argument("--scans", type=int, default=None, help="the first N scans only (default all)")
    parser.add_argument("--voxel", type=float, default=0.5)
    parser.add_argument("--gap", type=int, default=10, help="recall: candidates at least this many scans back")
    parser.add_argument("--k", type=int, nargs="+", default=[1, 3, 5, 10])
    parser.add_argument("--drop", default="", help="end to end: windows of scans left out, e.g. 300:330,600:630")
    parser.add_argument("--similar", type=int, nargs="*", default=[], help="end to end: similar_per_scan values")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args(argv)
    drive = read_drive(args.drive)
    n = len(drive.files) if args.scans is None else args.scans
    with cf.ThreadPoolExecutor(args.jobs) as executor:
        clouds: dict[Hashable, Any] = {
            k: kissm.batch.CloudFile(str(drive.files[k]), drive.formats[k]) for k in range(n)
        }
        features = kissm.batch.describe_many(clouds, executor, voxel_size=args.voxel)
        described = {position(k): f for k, f in features.items() if isinstance(f, kissm.Features)}
        true: dict[int, set[int]] = {}
        for i, j in drive.loops.tolist():
            if j < n:
                true.setdefault(j, set()).add(i)
        signatures = np.array([described[k].signature() for k in range(n)])
        for k in args.k:
            print(json.dumps({"k": k, "gap": args.gap, "recall": round(recall(signatures, true, args.gap, k), 3)}))
        dropped: set[int] = set()
        for window in filter(None, args.drop.split(",")):
            low, high = (int(v) for v in window.split(":"))
            dropped.update(range(low, high))
        kept = {k: described[k] for k in range(n) if k not in dropped}
        kept_true = {j: {i for i in s if i in kept} for j, s in true.items() if j in kept}
        kept_true = {j: s for j, s in kept_true.items() if s}
        for similar in args.similar:
            print(json.dumps(end_to_end(kept, drive.poses, kept_true, args.voxel, similar, executor)), flush=True)
    return 0
