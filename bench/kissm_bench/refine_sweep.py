# SPDX-License-Identifier: MIT
"""The evidence behind refinement's defaults (docs/parameters.md, "Refinement"): every pair of ../shared/data,
raw and with the source turned by 3 random rotations, refined from kissm's own coarse pose under each setting
given (or a default sweep), with the median and largest errors against the ground truth, iterations,
convergence and the refinement's own time per dataset. Each setting refines the same coarse poses (the solver's
pose does not depend on refinement's settings), from features computed under the setting.

    python3 bench/refine_sweep.py [--data ../shared/data] [--threads 2] [SETTING ...]

A SETTING is comma-separated config fields, e.g. "refine_mode=gicp,refine_max_distance_gain=2". Needs the kissm
Python package and numpy. Times are noisy unless the machine is quiet; the errors are deterministic.
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
from pathlib import Path
from typing import Any

import kissm
import numpy as np

from .common import SHARED_DATA
from .data import has_index, load_pairs
from .geometry import axis_angle, rotation_error_deg

DEFAULT_SWEEP = [
    "refine_mode=gicp",
    "refine_mode=point_to_plane",
    "refine_mode=gicp,refine_rotation_epsilon=1e-4,refine_translation_epsilon_gain=1e-3",
    "refine_mode=gicp,refine_rotation_epsilon=1e-3,refine_translation_epsilon_gain=1e-2",
    "refine_mode=gicp,refine_max_distance_gain=2",
    "refine_mode=gicp,refine_max_distance_gain=5",
    "refine_mode=gicp,refine_kernel_gain=0.5",
    "refine_mode=gicp,refine_kernel_gain=2",
    "refine_mode=gicp,refine_normal_radius_gain=1.5",
    "refine_mode=gicp,refine_normal_radius_gain=2.5",
    "refine_mode=gicp,refine_normal_radius_gain=3.5",
]


def parse(setting: str) -> dict[str, Any]:
    """A SETTING's config fields (Matcher's keyword arguments): ints, floats, else strings."""
    out: dict[str, Any] = {}
    for item in setting.split(","):
        key, value = item.split("=")
        try:
            out[key] = int(value)
        except ValueError:
            try:
                out[key] = float(value)
            except ValueError:
                out[key] = value
    return out


def errors(transform: np.ndarray, gt: np.ndarray) -> tuple[float, float]:
    return rotation_error_deg(transform[:3, :3], gt[:3, :3]), float(np.linalg.norm(transform[:3, 3] - gt[:3, 3]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=SHARED_DATA)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("settings", nargs="*")
    args = parser.parse_args()
    if not has_index(args.data):
        print(f"no real data at {args.data}")
        return 1
    rng = np.random.default_rng(777)
    cases = []  # (dataset, voxel, source points, target points, coarse pose, ground truth)
    for p in load_pairs(args.data):
        src, tgt = p.read()
        with kissm.Matcher(voxel_size=p.kind.voxel, num_threads=args.threads, refine_mode="gicp") as m:
            ft = m.compute_features(tgt)
            variants = [(src, p.gt)]
            for _ in range(3):
                axis = rng.normal(size=3)
                turn = axis_angle(axis, rng.uniform(54, 180))
                gt = p.gt.copy()
                gt[:3, :3] = p.gt[:3, :3] @ turn.T
                variants.append((src @ turn.T, gt))
            for points, gt in variants:
                coarse = m.register_features(m.compute_features(points), ft).coarse_transform
                if np.isfinite(coarse).all():
                    cases.append((p.name.split("/")[0], p.kind.voxel, points, tgt, coarse, gt))
    for setting in args.settings or DEFAULT_SWEEP:
        config = parse(setting)
        rows: dict[str, list[tuple[float, ...]]] = collections.defaultdict(list)
        for dataset, voxel, src, tgt, coarse, gt in cases:
            with kissm.Matcher(voxel_size=voxel, num_threads=args.threads, **config) as m:
                # Features under the setting: refinement's planes are computed with them.
                fs, ft = m.compute_features(src), m.compute_features(tgt)
                times = []
                for _ in range(3):
                    r = m.refine_features(fs, ft, coarse)
                    times.append(r.time_refine_ms)
            rot, trans = errors(r.transform, gt)
            c_rot, c_trans = errors(coarse, gt)
            rows[dataset].append(
                (rot, trans, min(times), r.refine_iterations, float(r.refine_converged), c_rot, c_trans)
            )
        print(f"== {setting}")
        for dataset, v in sorted(rows.items()):
            col = list(zip(*v, strict=True))
            print(
                f"  {dataset:30s} n={len(v):2d} coarse {statistics.median(col[5]):.3f} deg"
                f" {100 * statistics.median(col[6]):.2f} cm"
                f" | refined {statistics.median(col[0]):.3f} deg (max {max(col[0]):.3f})"
                f" {100 * statistics.median(col[1]):.2f} cm (max {100 * max(col[1]):.2f})"
                f" | {statistics.median(col[2]):.1f} ms, {statistics.median(col[3]):.0f} it,"
                f" converged {int(sum(col[4]))}/{len(v)}"
            )
        sys.stdout.flush()
    return 0
