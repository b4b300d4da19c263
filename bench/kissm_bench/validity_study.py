# SPDX-License-Identifier: MIT
"""The evidence behind the validity rules (docs/design/accuracy.md, "The validity rules"): registrations whose truth is
known, each without refinement, with GICP and with point-to-plane, and the fields each rule reads. A run is
RIGHT when its pose is within the success thresholds of SPEC section 7 and WRONG otherwise; a WRONG run reported
valid is the worst bug kissm can ship, and the summary counts them per family and mode.

The families:
  * every pair of ../shared/data, raw, with the source turned by 6 random rotations (54-180 degrees), and with
    the source's frame moved 20, 40 and 60 voxels away from its sensor (and turned): normals then face a point
    that is not the sensor. For the moved frames the translation error is taken at the source's centroid, where
    the data is: at the moved origin a 1 degree error alone would be a centimetre on the bunny;
  * KITTI 07 keyframes two to four apart (ground truth chained through the pairs), raw and turned;
  * scan to map: each KITTI 07 keyframe, raw and turned, against a map of the other four (described once), and a
    scan of another dataset against the same maps (no pose right);
  * pairs of unrelated scans (no overlap: every valid pose is wrong): LiDAR scans of three datasets against each
    other at 0.3 and 0.5 m, and the bunny against a scaled 3DMatch fragment and back;
  * with suppression="ground", every pair of KITTI 07 keyframes 1 to 4 apart and the other LiDAR pairs, raw and
    yawed twice;
  * the committed synthetic pair (tests/data) with its target turned about z every 15 degrees and moved;
  * scenes with a second right-looking pose (kissm_bench.repetitive): a street of identical buildings, a pillar
    grid, a symmetric table, each beside a control with the repetition broken; and 30 compound objects of spheres
    and boxes (kissm_bench.raycast), whose parts match themselves turned;
  * with --priors, kissm.refine from the ground truth disturbed by 0-180 degrees and 0-30 voxels (the refine
    rule: overlap, conditioning, convergence, the residual).

Every registration runs through both entry points: ``kissm.register`` on the points, and ``register_features`` on
features computed apart (``Matcher.compute_features``), whose result must be the same bits (a mismatch is counted
and listed); the priors run through ``Matcher.refine`` on the points and ``refine_features`` on the features alike.

    python3 bench/validity_study.py [--data ../shared/data] [--threads 2] [--rotations 6] [--priors] [--rows]

Needs the kissm Python package (e.g. build/venv-python from bindings/python/run_tests.sh) and numpy. About 4
minutes at 2 threads (7 more with --priors).
"""

from __future__ import annotations

import argparse
import collections
import json
import math
from pathlib import Path
from typing import Any, Literal

import kissm
import numpy as np

from .common import REPO, SHARED_DATA
from .data import (  # the real-data tests' pairs and the multi-scan sets
    KEYFRAME_KIND,
    KINDS,
    SCAN_SETS,
    Kind,
    Trial,
    has_index,
    keyframes,
    load_pairs,
    read_scan_set,
)
from .geometry import axis_angle, judge_at
from .repetitive import FAMILIES

SYNTHETIC_KIND = Kind("synthetic", 0.25, 5.0, 0.3)  # the committed synthetic pair (tests/data): a yard in metres
RefineMode = Literal["none", "gicp", "point_to_plane"]
MODES: tuple[RefineMode, ...] = ("none", "gicp", "point_to_plane")


# The fields the rules read, with the mode whose rule reads them.
RULE_FIELDS = (
    ("rotation uncertainty (deg)", "none", lambda r: math.degrees(r.rotation_uncertainty)),
    ("ambiguity", "none", lambda r: r.ambiguity),
    ("inlier coverage", "gicp", lambda r: r.inlier_coverage),
    ("overlap", "gicp", lambda r: r.overlap),
    ("refine condition", "gicp", lambda r: r.refine_condition),
    ("information's rotation sigma (deg), GICP", "gicp", lambda r: information_rotation_sigma_deg(r)),
    (
        "information's rotation sigma (deg), point-to-plane",
        "point_to_plane",
        lambda r: information_rotation_sigma_deg(r),
    ),
)


def information_rotation_sigma_deg(r: kissm.Result) -> float:
    """The 1-sigma rotation error about the worst axis that the refined information states (NaN unrefined)."""
    info = np.asarray(r.information)
    if not np.isfinite(info).all():
        return math.nan
    cov = np.linalg.pinv(info)
    return math.degrees(math.sqrt(max(0.0, float(np.linalg.eigvalsh(cov[:3, :3]).max()))))


class Tally:
    def __init__(self) -> None:
        self.counts: dict[tuple[str, str], collections.Counter[str]] = collections.defaultdict(collections.Counter)
        self.wrong_valid: list[str] = []
        self.entry_points_differ: list[str] = []  # register and register_features gave other bits
        # (field, family kind, right?) -> values, for the separation table
        self.values: dict[tuple[str, str, bool], list[float]] = collections.defaultdict(list)
        self.records: list[dict[str, object]] = []  # every run's numbers, for --records

    def add(self, family: str, mode: str, valid: bool, right: bool, line: str, r: kissm.Result | None = None) -> None:
        key = (
            "right, valid"
            if valid and right
            else "WRONG, VALID"
            if valid
            else "right, invalid"
            if right
            else "wrong, invalid"
        )
        self.counts[(family, mode)][key] += 1
        if valid and not right:
            self.wrong_valid.append(line)
        if r is not None:
            self.records.append(record(family, mode, line[:48].strip(), right, r))
        if r is None or not np.isfinite(np.asarray(r.transform)).all():
            return
        kind = (
            family
            if family in ("unrelated scans", "synthetic pair")
            else "repetitive scenes"
            if "(repetitive)" in family
            else "their controls"
            if "(control)" in family
            else "symmetric parts"
            if "(symmetric parts)" in family
            else "real pairs"
        )
        for name, rule_mode, get in RULE_FIELDS:
            if mode == rule_mode and r.num_final_inliers >= 10 and math.isfinite(get(r)):
                self.values[(name, kind, right)].append(get(r))

    def print(self) -> None:
        print(f"\n{'family':44s} {'mode':25s} right,valid  WRONG,VALID  right,invalid  wrong,invalid")
        for (family, mode), c in sorted(self.counts.items()):
            print(
                f"{family:44s} {mode:25s} {c['right, valid']:11d} {c['WRONG, VALID']:12d} "
                f"{c['right, invalid']:14d} {c['wrong, invalid']:14d}"
            )
        print(f"\nwrong poses reported valid: {len(self.wrong_valid)}")
        for line in self.wrong_valid:
            print("  " + line)
        print(f"register and register_features disagreeing (bits): {len(self.entry_points_differ)}")
        for line in self.entry_points_differ:
            print("  " + line)
        print("\nwhat the rules read, runs with at least 10 inliers: range over right poses | over wrong poses")
        for name, _, _ in RULE_FIELDS:
            for kind in (
                "real pairs",
                "synthetic pair",
                "unrelated scans",
                "repetitive scenes",
                "their controls",
                "symmetric parts",
            ):
                right = self.values.get((name, kind, True), [])
                wrong = self.values.get((name, kind, False), [])
                print(f"  {name:28s} {kind:16s} {span(right)} | {span(wrong)}")


def record(family: str, mode: str, name: str, right: bool, r: kissm.Result) -> dict[str, object]:
    """A run's numbers for --records: what a confidence could read, and whether the pose was right."""
    out: dict[str, object] = {"family": family, "mode": mode, "name": name, "right": right}
    out.update({k: v for k, v in r.to_dict().items() if isinstance(v, (bool, int, float))})
    return out


def span(values: list[float]) -> str:
    return f"{min(values):8.4f} .. {max(values):8.4f} ({len(values)})" if values else f"{'-':>24s}"


def fields(r: kissm.Result, voxel: float) -> str:
    return (
        f"inliers {r.num_final_inliers:4d} sigma {math.degrees(r.rotation_uncertainty):6.2f} deg "
        f"ambiguity {r.ambiguity:5.3f} "
        f"coverage {r.inlier_coverage:5.2f} overlap {r.overlap:5.3f} condition {r.refine_condition:7.4f} "
        f"rmse/v {r.refine_rmse / voxel:5.3f} it {r.refine_iterations:2d}{'' if r.refine_converged else '!'} "
        f"reason {r.reason}"
    )


def same_result(a: kissm.Result, b: kissm.Result) -> bool:
    """The same pose, validity and reason, bit for bit."""
    return (
        a.valid == b.valid
        and a.reason_code == b.reason_code
        and np.asarray(a.transform).tobytes() == np.asarray(b.transform).tobytes()
    )


def run(tally: Tally, family: str, t: Trial, args: argparse.Namespace, **config: Any) -> None:
    k = t.kind
    for mode in MODES:
        r = kissm.register(t.source, t.target, voxel_size=k.voxel, num_threads=args.threads, refine=mode, **config)
        e_rot, e_trans, right = judge_at(r.transform, t.gt, k.max_rot_deg, k.max_trans_m, t.at)
        line = (
            f"{t.name:48s} {mode:14s} valid={int(r.valid)} error {e_rot:7.2f} deg {e_trans:8.4f} m "
            f"{'right' if right else 'wrong'}  {fields(r, k.voxel)}"
        )
        tally.add(family, mode, r.valid, right, line, r)
        if args.rows:
            print(line, flush=True)
        # The same pair through features described apart: the same bits, or the difference is listed.
        with kissm.Matcher(voxel_size=k.voxel, num_threads=args.threads, refine_mode=mode, **config) as m:
            f = m.register_features(m.compute_features(t.source), m.compute_features(t.target))
        _, _, f_right = judge_at(f.transform, t.gt, k.max_rot_deg, k.max_trans_m, t.at)
        tally.add(family, mode + " (features)", f.valid, f_right, line.replace(mode, mode + " (features)", 1), f)
        if not same_result(r, f):
            tally.entry_points_differ.append(f"{t.name} {mode}: register {r.reason}, register_features {f.reason}")


def turned(points: np.ndarray, turn: np.ndarray, shift: np.ndarray | None = None) -> np.ndarray:
    out: np.ndarray = points @ turn.T
    return out if shift is None else out + shift


def real_pairs(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    for p in load_pairs(args.data):
        src, tgt = p.read()
        k = p.kind
        family = p.name.split("/")[0]
        run(tally, family, Trial(f"{p.name} raw", src, tgt, p.gt, k), args)
        for i in range(args.rotations):
            turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
            gt = p.gt.copy()
            gt[:3, :3] = p.gt[:3, :3] @ turn.T  # the source turned by `turn`
            run(tally, family, Trial(f"{p.name} rot{i}", turned(src, turn), tgt, gt, k), args)
        for i in range(3):  # the frame moved away from the sensor: p' = turn p + d
            turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
            d = rng.normal(size=3)
            d *= k.voxel * 20 * (i + 1) / np.linalg.norm(d)
            gt = np.eye(4)
            gt[:3, :3] = p.gt[:3, :3] @ turn.T
            gt[:3, 3] = p.gt[:3, 3] - gt[:3, :3] @ d
            moved = turned(src, turn, d)
            run(
                tally,
                family + " (moved frame)",
                Trial(f"{p.name} moved{i}", moved, tgt, gt, k, at=moved.mean(axis=0)),
                args,
            )


def far_keyframes(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    kf = keyframes(args.data)
    if kf is None:
        return
    chain, cloud = kf
    for a in range(5):
        for b in range(a + 2, 5):
            gt = np.linalg.inv(chain[a]) @ chain[b]
            far = "kitti07 keyframes 2-4 apart"
            run(tally, far, Trial(f"kitti07 {a}<-{b} raw", cloud[b], cloud[a], gt, KEYFRAME_KIND), args)
            turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
            g2 = gt.copy()
            g2[:3, :3] = gt[:3, :3] @ turn.T
            run(tally, far, Trial(f"kitti07 {a}<-{b} rot", turned(cloud[b], turn), cloud[a], g2, KEYFRAME_KIND), args)


def ground_suppressed(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    """With suppression="ground": every pair of KITTI 07 keyframes 1 to 4 apart and the other LiDAR pairs, raw and
    yawed twice (ground suppression assumes the sensor's up), where fewer keypoints leave fewer inliers."""
    kf = keyframes(args.data)
    if kf is None:
        return
    chain, cloud = kf
    trials = [
        Trial(f"kitti07 {a}<-{b}", cloud[b], cloud[a], np.linalg.inv(chain[a]) @ chain[b], KEYFRAME_KIND)
        for a in range(5)
        for b in range(a + 1, 5)
    ]
    for p in load_pairs(args.data):
        if p.kind.category == "lidar" and not p.name.startswith("kitti07"):
            src, tgt = p.read()
            trials.append(Trial(p.name, src, tgt, p.gt, p.kind))
    for t in trials:
        run(
            tally,
            "ground suppressed (LiDAR)",
            Trial(f"{t.name} raw", t.source, t.target, t.gt, t.kind),
            args,
            suppression="ground",
        )
        for _ in range(2):
            turn = axis_angle(np.array([0.0, 0.0, 1.0]), rng.uniform(0, 360))
            gt = t.gt.copy()
            gt[:3, :3] = t.gt[:3, :3] @ turn.T
            yawed = Trial(f"{t.name} yawed", turned(t.source, turn), t.target, gt, t.kind)
            run(tally, "ground suppressed (LiDAR)", yawed, args, suppression="ground")


def scan_to_map(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    """Each KITTI 07 keyframe against a map of the other four in keyframe 0's frame (the map described once), raw
    and turned; and a scan of another dataset against the same maps, where no pose is right."""
    kf = keyframes(args.data)
    other = args.data / "small_gicp_lidar/source.ply"
    if kf is None or not other.is_file():
        return
    chain, cloud = kf
    stranger = kissm.read_points(other)
    nowhere = np.eye(4)
    nowhere[0, 3] = 1e6
    for k in range(5):
        world = np.concatenate([turned(cloud[m], chain[m][:3, :3], chain[m][:3, 3]) for m in range(5) if m != k])
        for mode in MODES:
            with kissm.Matcher(voxel_size=KEYFRAME_KIND.voxel, num_threads=args.threads, refine_mode=mode) as m:
                the_map = m.compute_features(world)
                turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
                gt_turned = chain[k].copy()
                gt_turned[:3, :3] = chain[k][:3, :3] @ turn.T
                for name, scan, gt in (
                    (f"keyframe {k} -> map of the others", cloud[k], chain[k]),
                    (f"keyframe {k} turned -> map of the others", turned(cloud[k], turn), gt_turned),
                    (f"small_gicp scan -> map without keyframe {k}", stranger, nowhere),
                ):
                    r = m.register_features(m.compute_features(scan), the_map)
                    _, _, right = judge_at(r.transform, gt, KEYFRAME_KIND.max_rot_deg, KEYFRAME_KIND.max_trans_m)
                    line = f"{name:48s} {mode:14s} valid={int(r.valid)} {'right' if right else 'wrong'}  {r.reason}"
                    tally.add("scan to map (keyframes)", mode, r.valid, right, line, r)
                    if args.rows:
                        print(line, flush=True)


def scan_sets(tally: Tally, args: argparse.Namespace, rng: np.random.Generator) -> None:
    """The object multi-scan sets: every neighbouring pair of the bunny's turntable ring (45-90 degrees apart) and of
    the happy Buddha's (24 degrees apart, a closed loop), raw and turned; the truth from the set's own poses."""
    for s in SCAN_SETS:
        if s.label == "kitti07":  # the same keyframes as kitti07_keyframes_gtsam_points above
            continue
        folder = args.data / s.folder
        if not (folder / "scans.tsv").is_file():
            continue
        names, files, formats, poses = read_scan_set(folder)
        ring = list(s.order) or names
        index = {n: i for i, n in enumerate(names)}
        kind = Kind("object", s.voxel, 5.0, s.max_trans)
        family = f"{s.label} multi-scan set, neighbours"
        for i in range(len(ring) if s.closed else len(ring) - 1):
            a, b = ring[i], ring[(i + 1) % len(ring)]
            target = kissm.read_points(files[index[a]], format=formats[index[a]])
            source = kissm.read_points(files[index[b]], format=formats[index[b]])
            gt = np.linalg.inv(poses[a]) @ poses[b]
            run(tally, family, Trial(f"{s.label} {a}<-{b} raw", source, target, gt, kind), args)
            turn = axis_angle(rng.normal(size=3), rng.uniform(54, 180))
            g2 = gt.copy()
            g2[:3, :3] = gt[:3, :3] @ turn.T
            run(tally, family, Trial(f"{s.label} {a}<-{b} rot", turned(source, turn), target, g2, kind), args)


def unrelated(tally: Tally, args: argparse.Namespace) -> None:
    d = args.data
    lidar = [
        ("kitti07/000000", d / "kitti07_keyframes_gtsam_points/000000/points.bin", "bin_xyz"),
        ("kitti07/000004", d / "kitti07_keyframes_gtsam_points/000004/points.bin", "bin_xyz"),
        ("small_gicp/source", d / "small_gicp_lidar/source.ply", None),
        ("small_gicp/target", d / "small_gicp_lidar/target.ply", None),
        ("kitti_demo/000000", d / "kitti_demo_scans_unverified/000000.bin", "kitti_bin"),
        ("kitti_demo/000015", d / "kitti_demo_scans_unverified/000015.bin", "kitti_bin"),
    ]
    if not all(p.is_file() for _, p, _ in lidar):
        return
    clouds = [kissm.read_points(p, format=f) if f else kissm.read_points(p) for _, p, f in lidar]
    nowhere = np.eye(4)
    nowhere[0, 3] = 1e6  # no pose is right
    for a in range(len(lidar)):
        for b in range(len(lidar)):
            if a // 2 == b // 2:
                continue  # the same dataset's scans overlap
            for voxel in (0.3, 0.5):
                name = f"{lidar[a][0]} -> {lidar[b][0]} v{voxel}"
                run(
                    tally,
                    "unrelated scans",
                    Trial(name, clouds[a], clouds[b], nowhere, Kind("lidar", voxel, 5, 2)),
                    args,
                )
    bunny = d / "stanford_bunny_scans/bun000.ply"
    fragment = d / "3dmatch_geotransformer_demo/src.npy"
    if bunny.is_file() and fragment.is_file():
        bun, frag = kissm.read_points(bunny), kissm.read_points(fragment)
        bunny_kind = KINDS["object_range_scan"]  # voxel 0.006, 5 degrees and 0.01 m
        run(tally, "unrelated scans", Trial("bunny -> fragment / 20", bun, frag * 0.05, nowhere, bunny_kind), args)
        run(tally, "unrelated scans", Trial("fragment / 20 -> bunny", frag * 0.05, bun, nowhere, bunny_kind), args)


def synthetic(tally: Tally, args: argparse.Namespace) -> None:
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
        moved = tgt @ turn.T + shift
        run(tally, "synthetic pair", Trial(f"synthetic, target yaw {yaw}", src, moved, gt, SYNTHETIC_KIND), args)


def repetitive_scenes(tally: Tally, args: argparse.Namespace) -> None:
    """Scenes with a second right-looking pose (a street of identical buildings, a pillar grid, a symmetric table)
    and their controls with the repetition broken: right or refused, never wrong and valid."""
    for family in FAMILIES:
        for t in family.trials():
            run(tally, family.name, t, args)


def priors(args: argparse.Namespace, rng: np.random.Generator, records: list[dict[str, object]]) -> None:
    """kissm.refine from the ground truth disturbed by growing amounts: the basin, and what the refine rule says."""
    counts: dict[tuple[int, int], collections.Counter[str]] = collections.defaultdict(collections.Counter)
    differ = 0  # refine on the points and refine_features on the features, other bits
    for p in load_pairs(args.data):
        src, tgt = p.read()
        k = p.kind
        with kissm.Matcher(voxel_size=k.voxel, num_threads=args.threads, refine_mode="gicp") as m:
            fs, ft = m.compute_features(src), m.compute_features(tgt)
            for deg in (0, 3, 10, 20, 45, 90, 180):
                for vox in (0, 1, 3, 10, 30):
                    for _ in range(2):
                        start = p.gt.copy()
                        start[:3, :3] = axis_angle(rng.normal(size=3), deg) @ p.gt[:3, :3]
                        step = rng.normal(size=3)
                        start[:3, 3] += step / np.linalg.norm(step) * vox * k.voxel
                        r = m.refine_features(fs, ft, start)
                        differ += not same_result(r, m.refine(src, tgt, start))
                        _, _, right = judge_at(r.transform, p.gt, k.max_rot_deg, k.max_trans_m)
                        records.append(record("refine from a prior", "gicp", f"{p.name} {deg} {vox}", right, r))
                        key = (
                            "right, valid"
                            if r.valid and right
                            else "WRONG, VALID"
                            if r.valid
                            else "right, invalid"
                            if right
                            else "wrong, invalid"
                        )
                        counts[(deg, vox)][key] += 1
    print(f"\nMatcher.refine and refine_features disagreeing (bits): {differ}")
    print("\nkissm.refine from the ground truth disturbed by (degrees, voxels), every real pair, GICP:")
    print("  start             right,valid  WRONG,VALID  right,invalid  wrong,invalid")
    for (deg, vox), c in sorted(counts.items()):
        print(
            f"  {deg:3d} deg {vox:2d} vox  {c['right, valid']:11d} {c['WRONG, VALID']:12d} "
            f"{c['right, invalid']:14d} {c['wrong, invalid']:14d}"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=SHARED_DATA)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rotations", type=int, default=6)
    parser.add_argument("--priors", action="store_true", help="also kissm.refine from disturbed ground truth")
    parser.add_argument("--rows", action="store_true", help="print every run, not only the summary")
    parser.add_argument("--records", type=Path, help="write every run's numbers here (JSON lines)")
    args = parser.parse_args()
    rng = np.random.default_rng(12345)
    tally = Tally()
    if has_index(args.data):
        real_pairs(tally, args, rng)
        far_keyframes(tally, args, rng)
        scan_to_map(tally, args, rng)
        scan_sets(tally, args, np.random.default_rng(33))  # its own draws: the others keep theirs
        ground_suppressed(tally, args, np.random.default_rng(44))
        unrelated(tally, args)
    else:
        print(f"(no real data at {args.data}: the synthetic pair only)")
    synthetic(tally, args)
    repetitive_scenes(tally, args)
    tally.print()
    if args.priors and has_index(args.data):
        priors(args, rng, tally.records)
    if args.records:
        args.records.write_text("".join(json.dumps(row, allow_nan=True) + "\n" for row in tally.records))
    return 0
