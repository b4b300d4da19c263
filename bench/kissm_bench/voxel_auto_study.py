# SPDX-License-Identifier: MIT
"""The evidence behind ``voxel_size="auto"`` (docs/design/voxel_auto.md): every pair of the real data, raw and with the
source turned by large random rotations (as the real-data tests turn it), and the neighbouring pairs and the multiway
alignment of every multi-scan set, each registered with the voxel the data README suggests for its kind and with the
voxel each candidate rule chooses from the points alone. Per rule: runs that succeed (valid and within the SPEC
section 7 thresholds), wrong poses reported valid (the worst bug kissm can ship), and the time against the README
voxel's.

Candidate rules (each a per-cloud suggestion; a pair or a set takes the smallest of its clouds' suggestions, which
does not depend on their order, or with the suffix ``@median`` their lower median):
  * ``readme``: the data README's voxel for the kind (the reference, not a rule);
  * ``xM``: the README voxel times M (how wide the band of working voxels is);
  * ``countK``: the voxel whose grid holds K occupied voxels (found by bisection on the logarithm of the voxel);
  * ``spacingK``: K times the median nearest-neighbour spacing;
  * ``slopeK``: ``count`` of K (2 / s)^2 voxels, s the count's growth exponent (surfaces near 2, scan lines less);
  * ``compactK``: ``count3000``, or ``countK`` for a compact cloud (dense coverage of its principal spread);
  * ``auto``: the library's own rule (``voxel_size="auto"``, ``kissm.suggest_voxel_size``).

Besides the pairs and the sets, pairs of unrelated scans (no overlap, scenes of very different sizes): every valid
pose there is wrong.

    python bench/voxel_auto_study.py [--data ../shared/data] [--rotations 2] [--rules readme count3000 auto]
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections import defaultdict
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Literal

import kissm
import numpy as np

from .common import add_data_option
from .data import SCAN_SETS, Kind, has_index, load_pairs, read_cached, read_scan_set
from .geometry import axis_angle, judge_at

Rule = Callable[[np.ndarray], float]


def occupied(points: np.ndarray, voxel: float) -> int:
    """How many voxels of side ``voxel`` (anchored at the bounding box's minimum) hold a point."""
    keys = np.floor((points - points.min(axis=0)) / voxel).astype(np.int64)
    return len(np.unique((keys[:, 0] << 42) | (keys[:, 1] << 21) | keys[:, 2]))


def count_rule(target: int) -> Rule:
    def rule(points: np.ndarray) -> float:
        extent = float(np.max(points.max(axis=0) - points.min(axis=0)))
        lo, hi = math.log(extent / 2e6), math.log(extent)  # the grid's limit of voxels per axis; one voxel
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if occupied(points, math.exp(mid)) > target:
                lo = mid
            else:
                hi = mid
        return math.exp(hi)

    return rule


def slope_rule(k: int) -> Rule:
    """count_rule(K') with K' = K (2 / s)^2, s the growth exponent of the count between the count-K voxel and half of
    it: a surface (s near 2) keeps about K voxels, a cloud of scan lines (s near 1) gets up to 4K."""

    def rule(points: np.ndarray) -> float:
        v0 = count_rule(k)(points)
        s = math.log2(occupied(points, v0 / 2) / occupied(points, v0))
        return count_rule(int(k * min(4.0, max(1.0, (2.0 / max(s, 1e-9)) ** 2))))(points)

    return rule


def coverage(points: np.ndarray, voxel: float) -> float:
    """Occupied voxels per unit of the voxel grid's principal spread (sigma_1 sigma_2 of the occupied voxels, in
    voxels): near 12 for a plane, 17-24 for an object scan or an indoor fragment, 5-11 for a LiDAR scan, sparse
    away from its sensor."""
    keys = np.unique(np.floor((points - points.min(axis=0)) / voxel).astype(np.int64), axis=0).astype(np.float64)
    w = np.linalg.eigvalsh(np.cov(keys.T))
    return len(keys) / math.sqrt(max(w[2] * w[1], 1e-300))


def compact_rule(k: int) -> Rule:
    """count_rule(3000), or count_rule(k) for a compact cloud (coverage at the 3000-voxel rung of 14 or more)."""

    def rule(points: np.ndarray) -> float:
        v = count_rule(3000)(points)
        return count_rule(k)(points) if coverage(points, v) >= 14.0 else v

    return rule


def spacing_rule(k: float) -> Rule:
    def rule(points: np.ndarray) -> float:
        from scipy.spatial import cKDTree  # type: ignore[import-untyped]  # only for this rule

        d, _ = cKDTree(points).query(points, k=2)
        return k * float(np.median(d[:, 1]))

    return rule


def library_rule(points: np.ndarray) -> float:
    return float(kissm.suggest_voxel_size(points))


def pair_voxel(rule: str, clouds: Sequence[np.ndarray], readme: float) -> float:
    if rule == "readme":
        return readme
    if rule.startswith("x"):
        return readme * float(rule[1:])
    if rule == "auto":  # the library's own pair or set rule
        return float(kissm.suggest_voxel_size(*clouds))
    rule, _, combine = rule.partition("@")  # "@median": a set takes its clouds' lower median, not their smallest
    per_cloud = RULES[rule.rstrip("0123456789.")](float(rule.lstrip("abcdefghijklmnopqrstuvwxyz")))
    voxels = sorted(per_cloud(c) for c in clouds)
    return voxels[(len(voxels) - 1) // 2] if combine == "median" else voxels[0]


RULES: dict[str, Callable[[float], Rule]] = {
    "count": lambda k: count_rule(int(k)),
    "slope": lambda k: slope_rule(int(k)),
    "spacing": spacing_rule,
    "compact": lambda k: compact_rule(int(k)),
}


class Tally:
    def __init__(self) -> None:
        # (rule, family) -> counts and times
        self.runs: dict[tuple[str, str], dict[str, Any]] = defaultdict(
            lambda: {"runs": 0, "ok": 0, "wrong_valid": 0, "ms": [], "voxels": [], "rre": [], "rte": []}
        )
        self.lines: list[str] = []


def turned(points: np.ndarray, turn: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(points @ turn.T)


def register(
    tally: Tally,
    rules: list[str],
    family: str,
    name: str,
    src: np.ndarray,
    tgt: np.ndarray,
    gt: np.ndarray,
    kind: Kind,
    threads: int,
) -> None:
    for rule in rules:
        voxel = pair_voxel(rule, (src, tgt), kind.voxel)
        t0 = time.perf_counter()
        if rule == "auto":
            r = kissm.register(src, tgt, voxel_size="auto", num_threads=threads)
            assert r.voxel_size_used == voxel, (r.voxel_size_used, voxel)
        else:
            r = kissm.register(src, tgt, voxel_size=voxel, num_threads=threads)
        ms = (time.perf_counter() - t0) * 1e3
        rre, rte, right = judge_at(r.transform, gt, kind.max_rot_deg, kind.max_trans_m)
        t = tally.runs[(rule, family)]
        t["runs"] += 1
        t["ok"] += bool(r.valid and right)
        t["wrong_valid"] += bool(r.valid and not right)
        t["ms"].append(ms)
        t["voxels"].append(voxel)
        if r.valid and right:
            t["rre"].append(rre)
            t["rte"].append(rte)
        tally.lines.append(
            f"{name:58s} {rule:12s} v={voxel:8.5f} voxels={r.num_source_voxels:6d}/{r.num_target_voxels:6d} "
            f"RRE {rre:7.3f} RTE {rte:8.4f} "
            f"{'OK  ' if r.valid and right else 'WRONG-VALID' if r.valid else 'invalid'} {ms:7.1f} ms"
        )


def pairs(tally: Tally, args: argparse.Namespace) -> None:
    rng = np.random.default_rng(12345)
    for p in load_pairs(args.data):
        src, tgt = p.read()
        family = p.name.split("/")[0]
        register(tally, args.rules, family, f"{p.name} raw", src, tgt, p.gt, p.kind, args.threads)
        for i in range(args.rotations):
            turn = axis_angle(rng.normal(size=3), rng.uniform(90, 180))
            gt = p.gt.copy()
            gt[:3, :3] = p.gt[:3, :3] @ turn.T
            register(tally, args.rules, family, f"{p.name} rot{i}", turned(src, turn), tgt, gt, p.kind, args.threads)


def set_neighbours(tally: Tally, args: argparse.Namespace) -> None:
    """The neighbouring scans of each object set (the turntable rings), raw and turned once."""
    rng = np.random.default_rng(33)
    for s in SCAN_SETS:
        if s.label == "kitti07":  # its neighbouring pairs are the keyframe pairs above
            continue
        folder = args.data / s.folder
        names, files, formats, poses = read_scan_set(folder)
        ring = list(s.order) or names
        index = {n: i for i, n in enumerate(names)}
        kind = Kind("object", s.voxel, 5.0, s.max_trans)
        for i in range(len(ring) if s.closed else len(ring) - 1):
            a, b = ring[i], ring[(i + 1) % len(ring)]
            tgt = read_cached(files[index[a]], formats[index[a]])
            src = read_cached(files[index[b]], formats[index[b]])
            gt = np.linalg.inv(poses[a]) @ poses[b]
            family = f"{s.label} neighbours"
            register(tally, args.rules, family, f"{s.label} {a}<-{b} raw", src, tgt, gt, kind, args.threads)
            turn = axis_angle(rng.normal(size=3), rng.uniform(90, 180))
            g2 = gt.copy()
            g2[:3, :3] = gt[:3, :3] @ turn.T
            register(
                tally, args.rules, family, f"{s.label} {a}<-{b} rot", turned(src, turn), tgt, g2, kind, args.threads
            )


#: Unrelated scans (no overlap: every valid pose is wrong), each with the data README voxel of its source's kind:
#: scenes of one kind and of very different sizes, where a pair rule meets two clouds that need other voxels.
UNRELATED = (
    ("kitti07_keyframes_gtsam_points/000000/points.bin", "bin_xyz", "small_gicp_lidar/source.ply", "ply", 0.5),
    (
        "kitti_demo_scans_unverified/000000.bin",
        "kitti_bin",
        "kitti07_keyframes_gtsam_points/000004/points.bin",
        "bin_xyz",
        0.3,
    ),
    ("stanford_bunny_scans/bun000.ply", "ply", "3dmatch_geotransformer_demo/ref.npy", "npy", 0.006),
    ("stanford_happy_stand_scans/happyStandRight_0.ply", "ply", "stanford_bunny_scans/bun045.ply", "ply", 0.004),
    ("3dmatch_geotransformer_demo/src.npy", "npy", "small_gicp_lidar/target.ply", "ply", 0.05),
    ("stanford_bunny_scans/bun090.ply", "ply", "kitti07_keyframes_gtsam_points/000002/points.bin", "bin_xyz", 0.006),
)


def unrelated(tally: Tally, args: argparse.Namespace) -> None:
    """Scans that do not overlap, raw and turned: no pose is right, so every valid one counts as wrong."""
    rng = np.random.default_rng(77)
    never = np.eye(4)  # with a negative translation threshold no pose is judged right
    for src_path, src_fmt, tgt_path, tgt_fmt, voxel in UNRELATED:
        if not (args.data / src_path).is_file() or not (args.data / tgt_path).is_file():
            continue
        src = read_cached(args.data / src_path, src_fmt)
        tgt = read_cached(args.data / tgt_path, tgt_fmt)
        kind = Kind("unrelated", voxel, 5.0, -1.0)
        name = f"{Path(src_path).stem} vs {Path(tgt_path).stem}"
        register(tally, args.rules, "unrelated scans", f"{name} raw", src, tgt, never, kind, args.threads)
        turn = axis_angle(rng.normal(size=3), rng.uniform(90, 180))
        register(tally, args.rules, "unrelated scans", f"{name} rot", turned(src, turn), tgt, never, kind, args.threads)


def multiway(tally: Tally, args: argparse.Namespace) -> None:
    """Each set aligned as a whole (kissm.multiway.align, every pair, GICP) with one voxel for all its scans; a scan
    is placed right within 2 degrees and 2 of the set's README voxels of its ground truth (anchored on scan 0)."""
    import kissm.multiway

    for s in SCAN_SETS:
        names, files, formats, poses = read_scan_set(args.data / s.folder)
        clouds = [read_cached(f, fmt) for f, fmt in zip(files, formats, strict=True)]
        for rule in args.rules:
            voxel = pair_voxel(rule, clouds, s.voxel)
            t0 = time.perf_counter()
            given: float | Literal["auto"] = "auto" if rule == "auto" else voxel  # multiway.align's own set rule
            alignment = kissm.multiway.align(dict(zip(names, clouds, strict=True)), given, pairs="all", refine="gicp")
            ms = (time.perf_counter() - t0) * 1e3
            right = wrong = 0
            for name, pose in zip(names, alignment.poses, strict=True):
                if not np.isfinite(pose).all():
                    continue
                error = np.linalg.inv(poses[name]) @ poses[names[0]] @ pose
                angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(error[:3, :3]) - 1) / 2))))
                ok = bool(angle <= 2.0 and np.linalg.norm(error[:3, 3]) <= 2.0 * s.voxel)
                right += int(ok)
                wrong += int(not ok)
            t = tally.runs[(rule, f"{s.label} multiway")]
            t["runs"] += len(names)
            t["ok"] += right
            t["wrong_valid"] += wrong
            t["ms"].append(ms)
            t["voxels"].append(voxel)
            tally.lines.append(
                f"{s.label + ' multiway':58s} {rule:12s} v={voxel:8.5f} placed right {right}/"
                f"{len(names)}, wrong {wrong} {ms:7.1f} ms"
            )


def median(values: list[float]) -> float:
    return statistics.median(values) if values else math.nan


def report(tally: Tally, rules: list[str]) -> None:
    families = sorted({f for _, f in tally.runs}, key=lambda f: (f.endswith("multiway"), f))
    print(
        "| family | rule | voxel (median) | success | wrong valid | median error of successes (deg, m) "
        "| time (ms, sum) | time / readme |"
    )
    print("|---|---|--:|--:|--:|--:|--:|--:|")
    totals: dict[str, list[float]] = defaultdict(lambda: [0, 0, 0, 0.0])
    for family in families:
        base = sum(tally.runs[("readme", family)]["ms"]) if ("readme", family) in tally.runs else math.nan
        for rule in rules:
            t = tally.runs.get((rule, family))
            if t is None:
                continue
            ms = sum(t["ms"])
            print(
                f"| {family} | {rule} | {statistics.median(t['voxels']):.4g} | {t['ok']}/{t['runs']} | "
                f"{t['wrong_valid']} | {median(t['rre']):.3f}, {median(t['rte']):.4f} | {ms:.0f} | {ms / base:.2f}x |"
            )
            tot = totals[rule]
            tot[0] += t["ok"]
            tot[1] += t["runs"]
            tot[2] += t["wrong_valid"]
            tot[3] += ms
    base = totals["readme"][3] if "readme" in totals else math.nan
    for rule in rules:
        ok, runs, wrong, ms = totals[rule]
        print(f"| **all** | {rule} | | {ok:.0f}/{runs:.0f} | {wrong:.0f} | | {ms:.0f} | {ms / base:.2f}x |")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_data_option(parser)
    parser.add_argument("--rotations", type=int, default=2, help="turned copies of each pair's source (default 2)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rules", nargs="+", default=["readme", "auto"])
    parser.add_argument("--no-multiway", action="store_true", help="skip the multiway alignment of the sets")
    parser.add_argument("--rows", action="store_true", help="print every run")
    args = parser.parse_args(argv)
    if not has_index(args.data):
        print(f"voxel_auto_study: no index.tsv in {args.data}")
        return 1
    tally = Tally()
    pairs(tally, args)
    set_neighbours(tally, args)
    unrelated(tally, args)
    if not args.no_multiway:
        multiway(tally, args)
    if args.rows:
        print("\n".join(tally.lines))
    report(tally, args.rules)
    return 0
