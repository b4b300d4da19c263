# SPDX-License-Identifier: MIT
"""Does registration depend on the clouds' coordinate frames? The evidence behind the default viewpoint_mode
(docs/design/frames.md): each viewpoint mode on the same runs, coarse (no refinement), success as in SPEC section 7.

The families:
  * pairs: every pair of ../shared/data raw and with the source turned by 3 random rotations (54-180 degrees),
    the runs of docs/design/accuracy.md;
  * moved frames: the same pairs with each cloud given in its own frame moved 40-80 m (LiDAR; 80-160 voxels
    otherwise) from its sensor and turned at random; the translation error is taken at the source's centroid;
  * scan-to-map: each KITTI 07 keyframe (its sensor frame) against the other four merged in the world frame,
    and the same in the world frame on both sides;
  * shifted: both clouds translated by metres and by 1e7 m (float64): the relative pose must change only by
    rounding; reported as the largest change against the unshifted run.

    python3 bench/frame_study.py [--data ../shared/data] [--threads 2] [--modes none fixed cloud_center] [--rows]

Needs the kissm Python package and numpy. About 5 minutes per mode at 2 threads.
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
from pathlib import Path

import kissm
import numpy as np

from .common import SHARED_DATA
from .data import KEYFRAME_KIND, Trial, has_index, keyframes, load_pairs  # the real-data tests' pairs and thresholds
from .geometry import apply, axis_angle, judge_at, rigid, rotation_error_deg


class Tally:
    """Per (family, mode): runs, successes, wrong poses reported valid, errors and inliers of the successes."""

    def __init__(self) -> None:
        self.runs: dict[tuple[str, str], int] = collections.Counter()
        self.right: dict[tuple[str, str], int] = collections.Counter()
        self.wrong_valid: dict[tuple[str, str], int] = collections.Counter()
        self.errors: dict[tuple[str, str], list[tuple[float, float]]] = collections.defaultdict(list)
        self.inliers: dict[tuple[str, str], list[int]] = collections.defaultdict(list)
        self.bad_lines: list[str] = []

    def add(
        self, family: str, mode: str, r: kissm.Result, e_rot: float, e_trans: float, right: bool, line: str
    ) -> None:
        key = (family, mode)
        self.runs[key] += 1
        if r.valid and right:
            self.right[key] += 1
            self.errors[key].append((e_rot, e_trans))
        if r.valid and not right:
            self.wrong_valid[key] += 1
            self.bad_lines.append(line)
        self.inliers[key].append(r.num_final_inliers)


def run(tally: Tally, args: argparse.Namespace, family: str, t: Trial) -> None:
    for mode in args.modes:
        r = kissm.register(
            t.source,
            t.target,
            voxel_size=t.kind.voxel,
            num_threads=args.threads,
            viewpoint_mode=mode,
            refine=args.refine,
        )
        e_rot, e_trans, right = judge_at(r.transform, t.gt, t.kind.max_rot_deg, t.kind.max_trans_m, t.at)
        line = (
            f"{t.name:52s} {mode:12s} valid={int(r.valid)} {e_rot:7.3f} deg {e_trans:8.4f} m "
            f"{'right' if right else 'wrong'} inliers {r.num_final_inliers:4d} reason {r.reason}"
        )
        tally.add(family, mode, r, e_rot, e_trans, right, line)
        if args.rows:
            print(line, flush=True)


def pairs(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    for p in load_pairs(args.data):
        src, tgt = p.read()
        family = "pairs, " + ("LiDAR" if p.is_lidar else p.kind_name.split("_")[0])
        run(tally, args, family, Trial(f"{p.name} raw", src, tgt, p.gt, p.kind))
        for i in range(args.rotations):
            turn = rigid(axis_angle(rng.normal(size=3), rng.uniform(54, 180)), np.zeros(3))
            run(
                tally,
                args,
                family,
                Trial(f"{p.name} rot{i}", apply(turn, src), tgt, p.gt @ np.linalg.inv(turn), p.kind),
            )


def random_frame(rng: np.random.Generator, distance: float) -> np.ndarray:
    d = rng.normal(size=3)
    return rigid(axis_angle(rng.normal(size=3), rng.uniform(0, 180)), d / np.linalg.norm(d) * distance)


def moved_frames(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    for p in load_pairs(args.data):
        src, tgt = p.read()
        k, family = p.kind, "moved frames, " + ("LiDAR" if p.is_lidar else p.kind_name.split("_")[0])
        for i in range(3):
            scale = 1.0 if p.is_lidar else k.voxel * 2.0  # 40-80 m, or 80-160 voxels
            fs, ft = random_frame(rng, rng.uniform(40, 80) * scale), random_frame(rng, rng.uniform(40, 80) * scale)
            s2, t2 = apply(fs, src), apply(ft, tgt)
            gt = ft @ p.gt @ np.linalg.inv(fs)
            run(tally, args, family, Trial(f"{p.name} moved{i}", s2, t2, gt, k, at=s2.mean(axis=0)))


def scan_to_map(tally: Tally, args: argparse.Namespace) -> None:
    kf = keyframes(args.data)
    if kf is None:
        return
    chain, cloud = kf
    for k in range(5):
        world_map = np.concatenate([apply(chain[j], cloud[j]) for j in range(5) if j != k])
        dist = np.linalg.norm(chain[k][:3, 3])
        name = f"kf{k} ({dist:4.0f} m from the map origin)"
        run(tally, args, "scan-to-map, scan in sensor frame", Trial(name, cloud[k], world_map, chain[k], KEYFRAME_KIND))
        in_world = Trial(
            f"kf{k} in world", apply(chain[k], cloud[k]), world_map, np.eye(4), KEYFRAME_KIND, chain[k][:3, 3]
        )
        run(tally, args, "scan-to-map, scan in world frame", in_world)


def shifted(args: argparse.Namespace) -> list[str]:
    """How the relative pose changes when both clouds move by the same offset, per mode: in how many pairs the
    rotation is bitwise the same, and the largest change among the pairs valid in both runs."""
    lines = []
    offsets = {
        "0.5 m": np.array([0.5, -12.25, 3.0]),
        "3.7 m": np.array([3.7, -12.3, 0.1]),
        "1e7 m": np.array([1e7, -3e6, 250.0]),
    }
    pairs = load_pairs(args.data)
    for mode in args.modes:
        for label, off in offsets.items():
            same = valid_both = 0
            worst = (0.0, 0.0)
            for p in pairs:
                src, tgt = p.read()
                base = kissm.register(src, tgt, voxel_size=p.kind.voxel, num_threads=args.threads, viewpoint_mode=mode)
                r = kissm.register(
                    src + off, tgt + off, voxel_size=p.kind.voxel, num_threads=args.threads, viewpoint_mode=mode
                )
                same += int(np.array_equal(r.rotation, base.rotation))
                if r.valid and base.valid:
                    valid_both += 1
                    shift = rigid(np.eye(3), off)
                    back = np.linalg.inv(shift) @ np.asarray(r.transform) @ shift
                    t0 = np.asarray(base.transform)
                    c = src.mean(axis=0)
                    worst = (
                        max(worst[0], rotation_error_deg(back[:3, :3], t0[:3, :3])),
                        max(worst[1], float(np.linalg.norm(apply(back, c) - apply(t0, c)))),
                    )
            lines.append(
                f"  {mode:12s} shift by {label:6s}: rotation bitwise the same in {same}/{len(pairs)} pairs; "
                f"valid in both runs {valid_both}, largest change there {worst[0]:.2e} deg, {worst[1]:.2e} m"
            )
    return lines


def report(tally: Tally, shift_lines: list[str], modes: list[str]) -> None:
    families = sorted({f for f, _ in tally.runs}, key=lambda f: (f.split(",")[0], f))
    print(
        "\nsuccess (valid and right) / runs, wrong poses reported valid, median error of the successes, median inliers"
    )
    header = f"{'family':40s}" + "".join(f" | {m:>40s}" for m in modes)
    print(header)
    for fam in families:
        row = f"{fam:40s}"
        for m in modes:
            key = (fam, m)
            errs = tally.errors.get(key, [])
            med = (
                f"{statistics.median(e[0] for e in errs):.3f}° {100 * statistics.median(e[1] for e in errs):.1f} cm"
                if errs
                else "-"
            )
            inl = statistics.median(tally.inliers[key]) if tally.inliers.get(key) else 0
            row += f" | {tally.right[key]:2d}/{tally.runs[key]:2d} wrong {tally.wrong_valid[key]} {med:>16s} {inl:5.0f}"
        print(row)
    if shift_lines:
        print("\nboth clouds shifted by the same offset (float64), against the unshifted run:")
        print("\n".join(shift_lines))
    if tally.bad_lines:
        print("\nWRONG POSES REPORTED VALID:")
        print("\n".join("  " + line for line in tally.bad_lines))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", type=Path, default=SHARED_DATA)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--modes", nargs="+", default=["none", "fixed", "cloud_center"])
    ap.add_argument("--families", nargs="+", default=["pairs", "moved", "map", "shift"])
    ap.add_argument("--seed", type=int, default=15)
    ap.add_argument("--rotations", type=int, default=3, help="turned copies of each pair (3)")
    ap.add_argument("--refine", default="none", help="refine mode of every run (none)")
    ap.add_argument("--rows", action="store_true", help="print every run")
    args = ap.parse_args()
    if not has_index(args.data):
        print(f"frame_study: no data at {args.data} (--data)", file=sys.stderr)
        return 2
    tally = Tally()
    rng = np.random.default_rng(args.seed)
    if "pairs" in args.families:
        pairs(tally, args, rng)
    if "moved" in args.families:
        moved_frames(tally, args, rng)
    if "map" in args.families:
        scan_to_map(tally, args)
    shift_lines = shifted(args) if "shift" in args.families else []
    report(tally, shift_lines, args.modes)
    return 0
