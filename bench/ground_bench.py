#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Ground-vehicle mode benchmark (issue 16): kissm's ground model against Patchwork++, ground suppression in
registration, and the 4-DoF (yaw-only) solver against the reference's Quatro mode. Writes docs/reports/ground.md,
docs/reports/img/ground_*.png and bench/results/ground_latest.json.

    python bench/ground_bench.py [--threads 1] [--repeats 3] [--seg-repeats 9] [--out DIR]
    python bench/ground_bench.py --smoke        # well under a minute: one scan, one pair, a temp dir
    python bench/ground_bench.py --report-from bench/results/ground_latest.json   # rewrite the page

Needs numpy and kissm importable; Patchwork++ (PyPI ``pypatchworkpp`` 1.4.1), the reference (PyPI
``kiss-matcher`` 1.0.2) and matplotlib when installed (each part that needs a missing one says so and is
skipped). The data is ../shared/data (or KISSM_DATA_DIR, or --data); the pairs, voxel sizes and success
thresholds are those of bindings/python/tests/realdata.py (LiDAR: valid within 5 degrees and 2 m).

1. **Segmentation.** Every raw LiDAR scan of the data (the full KITTI-style sweeps, the small_gicp scans, and
   the KITTI 07 keyframes, which are pre-thinned to about 0.27 m): kissm's ``ground_mask`` (voxel 0.3 and 0.5)
   against Patchwork++ with its default (KITTI) parameters, fed the file's intensity (1.0 when it has none).
   Agreement: IoU of the ground point sets, precision and recall of kissm's set taking Patchwork++'s as the
   truth (Patchwork++'s labels from the first call of a fresh instance: it keeps per-frame history). Time: the
   median of --seg-repeats interleaved calls after one warm-up, kissm's whole ``ground_mask`` call (Matcher,
   voxelisation, model) against Patchwork++'s ``estimateGround`` (one instance, as in a stream).
2. **Suppression.** Every LiDAR pair, raw and with the source turned about up (z) by 60, 120, 180 and -90
   degrees, ``suppression`` 'none' against 'ground'; and "wrong up": the source turned about x by 30 and 90
   degrees, where its +z is no longer up, with suppression on (and off, as the baseline).
3. **4-DoF.** The same raw and yaw-turned pairs, ``rotation_dof`` 3 against 1, and the reference with
   ``KISSMatcherConfig(voxel, use_quatro=True)`` in the same run; and tilted pairs (source turned about x by
   5, 10 and 30 degrees) under ``rotation_dof=1``, where the right answer is valid = 0 (reason "the clouds'
   relative roll or pitch is not zero") or a pose within the thresholds.

Everything runs pinned to the first --threads CPUs (``sched_setaffinity``, ``OMP_NUM_THREADS``); kissm gets
``num_threads``. The reference runs in one helper process per voxel size (its Quatro solver keeps its noise
bound in function-local statics, so one process must not see two voxel sizes), pinned the same way. The
timed registration calls of a case alternate between methods after one warm-up call each, and medians are
reported. Exits 0 without running when the data is absent, 1 when a call raised or kissm reported a wrong
pose valid, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import datetime as _dt
import importlib.util
import json
import math
import multiprocessing
import os
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "bindings" / "python" / "tests"))
from bench import (  # noqa: E402
    REFERENCE_MIN_INLIERS,
    cpus_for,
    machine_info,
    package_versions,
    reference_transform,
)

YAWS_DEG = (60.0, 120.0, 180.0, -90.0)  # source turned about up (z): fixed angles, no randomness needed
WRONG_UP_DEG = (30.0, 90.0)  # source turned about x with suppression on: its +z is no longer up
TILTS_DEG = (5.0, 10.0, 30.0)  # source turned about x under rotation_dof=1
SEG_VOXELS = (0.3, 0.5)
TILT_REASON = "the clouds' relative roll or pitch is not zero"
TILT_LIMIT_DEG = 2.0  # Config.max_rotation_uncertainty's default, the tilt limit of rotation_dof=1
ABOUT_UP_TOL = 1e-9
IOU_TARGET, SPEED_TARGET = 0.85, 2.0
# The raw LiDAR scans for the segmentation comparison: (path under the data folder, format, label).
SCANS = (
    ("kitti_demo_scans_unverified/000000.bin", "kitti_bin_xyzi_f32", "KITTI-style sweep 000000"),
    ("kitti_demo_scans_unverified/000015.bin", "kitti_bin_xyzi_f32", "KITTI-style sweep 000015"),
    ("small_gicp_lidar/target.ply", "ply", "small_gicp target"),
    ("small_gicp_lidar/source.ply", "ply", "small_gicp source"),
    *(
        (f"kitti07_keyframes_gtsam_points/{k:06d}/points.bin", "bin_xyz_f32", f"KITTI 07 keyframe {k}")
        for k in range(5)
    ),
)
SMOKE_SCANS = ("small_gicp_lidar/source.ply",)
SMOKE_PAIR = "small_gicp_lidar"
# kissm's methods (Config changes) and the reference's.
KISSM_METHODS = {
    "none": {},
    "ground": {"suppression": "ground"},
    "dof1": {"rotation_dof": 1},
}
LABEL = {
    "none": "kissm (3-DoF, no suppression)",
    "ground": "kissm, suppression='ground'",
    "dof1": "kissm, rotation_dof=1",
    "ref_quatro": "reference, use_quatro=True",
}


# ---- data ------------------------------------------------------------------------------------------------


def read_xyzi(path: Path, fmt: str) -> tuple[np.ndarray, np.ndarray | None]:
    """Points (N, 3) float64 via ``kissm.read_points`` and the file's intensity (N,) when it has one."""
    import kissm

    xyz = np.ascontiguousarray(kissm.read_points(path, format=fmt), dtype=np.float64)
    intensity = None
    if fmt == "kitti_bin_xyzi_f32":
        intensity = np.fromfile(path, dtype="<f4").reshape(-1, 4)[:, 3].astype(np.float64)
    elif fmt == "ply":
        intensity = ply_property(path, ("intensity", "scalar_intensity"))
    if intensity is not None and len(intensity) != len(xyz):
        intensity = None
    return xyz, intensity


def ply_property(path: Path, names: tuple[str, ...]) -> np.ndarray | None:
    """One float property of a binary little-endian PLY's vertices (the small_gicp scans), else None."""
    raw = path.read_bytes()
    end = raw.find(b"end_header\n")
    if end < 0:
        return None
    header = raw[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in header:
        return None
    types = {
        "float": "<f4",
        "float32": "<f4",
        "double": "<f8",
        "float64": "<f8",
        "uchar": "u1",
        "uint8": "u1",
        "int": "<i4",
        "int32": "<i4",
        "uint": "<u4",
        "uint32": "<u4",
        "short": "<i2",
        "ushort": "<u2",
    }
    fields, count, in_vertex = [], 0, False
    for line in header:
        parts = line.split()
        if parts[:2] == ["element", "vertex"]:
            count, in_vertex = int(parts[2]), True
        elif parts and parts[0] == "element":
            in_vertex = False
        elif in_vertex and parts[:1] == ["property"] and parts[1] in types:
            fields.append((parts[2], types[parts[1]]))
    names_in = [n for n, _ in fields]
    pick = next((n for n in names if n in names_in), None)
    if pick is None:
        return None
    data = np.frombuffer(raw, dtype=np.dtype(fields), count=count, offset=end + len(b"end_header\n"))
    return data[pick].astype(np.float64)


def data_missing(data: Path) -> str | None:
    if not (data / "index.tsv").is_file():
        return f"no index.tsv under {data}"
    return None


def lidar_pairs(data: Path, smoke: bool) -> list[Any]:
    import realdata

    pairs = [p for p in realdata.load_pairs(data) if p.is_lidar]
    if smoke:
        pairs = [p for p in pairs if p.name.startswith(SMOKE_PAIR)][:1] or pairs[:1]
    return pairs


def rot_about(axis: str, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == "z":
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    if axis == "x":
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    raise ValueError(axis)


def pose_errors(transform: np.ndarray, gt: np.ndarray) -> tuple[float | None, float | None]:
    t = np.asarray(transform, dtype=np.float64)
    if not np.isfinite(t).all():
        return None, None
    cos = (np.trace(gt[:3, :3].T @ t[:3, :3]) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, cos)))), float(np.linalg.norm(t[:3, 3] - gt[:3, 3]))


def about_up_deviation(rotation: np.ndarray) -> float | None:
    """The largest of |R22 - 1|, |R02|, |R12|, |R20|, |R21|: 0 for a rotation exactly about z."""
    r = np.asarray(rotation, dtype=np.float64)
    if not np.isfinite(r).all():
        return None
    return float(max(abs(r[2, 2] - 1.0), abs(r[0, 2]), abs(r[1, 2]), abs(r[2, 0]), abs(r[2, 1])))


def finite(v: float) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


# ---- 1. segmentation -------------------------------------------------------------------------------------


def seg_scores(mask: np.ndarray, truth: np.ndarray) -> dict[str, float | None]:
    both = int(np.count_nonzero(mask & truth))
    union = int(np.count_nonzero(mask | truth))
    km, pw = int(mask.sum()), int(truth.sum())
    return {
        "iou": both / union if union else None,
        "precision": both / km if km else None,
        "recall": both / pw if pw else None,
        "kissm_ground": km,
    }


def run_segmentation(args: argparse.Namespace, results: dict[str, Any], threads: int) -> None:
    import kissm

    if importlib.util.find_spec("pypatchworkpp") is None:
        results["notes"].append("Patchwork++ (pypatchworkpp) is not installed: the segmentation part was skipped.")
        print("ground_bench: pypatchworkpp not installed: segmentation skipped", flush=True)
        return
    import pypatchworkpp

    scans = [s for s in SCANS if (args.data / s[0]).is_file() and (not args.smoke or s[0] in SMOKE_SCANS)]
    for rel, fmt, label in scans:
        xyz, intensity = read_xyzi(args.data / rel, fmt)
        xyzi = np.ascontiguousarray(
            np.column_stack([xyz, intensity if intensity is not None else np.ones(len(xyz))]), dtype=np.float64
        )
        rng = np.linalg.norm(xyz[:, :2], axis=1)
        params = pypatchworkpp.Parameters()  # its defaults: KITTI's
        params.verbose = False
        pw = pypatchworkpp.patchworkpp(params)
        pw.estimateGround(xyzi)  # labels of a fresh instance's first call
        truth = np.zeros(len(xyz), dtype=bool)
        truth[np.asarray(pw.getGroundIndices(), dtype=np.int64)] = True
        pw.estimateGround(xyzi)
        again = np.zeros(len(xyz), dtype=bool)
        again[np.asarray(pw.getGroundIndices(), dtype=np.int64)] = True
        rec: dict[str, Any] = {
            "scan": rel,
            "label": label,
            "points": len(xyz),
            "intensity": intensity is not None,
            "pw_ground": int(truth.sum()),
            "pw_second_call_same": bool(np.array_equal(truth, again)),
            "pw_in_range_share": float(np.mean((rng >= params.min_range) & (rng <= params.max_range))),
            "kissm": {},
        }
        in_range = (rng >= params.min_range) & (rng <= params.max_range)
        masks = {}
        for v in SEG_VOXELS:
            m = kissm.ground_mask(xyz, v, num_threads=threads)
            m2 = kissm.ground_mask(xyz, v, num_threads=threads)
            masks[v] = m
            sc = seg_scores(m, truth)
            sc["deterministic"] = bool(np.array_equal(m, m2))
            sc["iou_in_pw_range"] = seg_scores(m & in_range, truth & in_range)["iou"]
            rec["kissm"][str(v)] = sc
        # Timing: one warm-up each, then interleaved calls (kissm 0.3, kissm 0.5, Patchwork++, again).
        times: dict[str, list[float]] = {str(v): [] for v in SEG_VOXELS}
        times["pw"], pw_own = [], []
        for rep in range(args.seg_repeats + 1):
            for v in SEG_VOXELS:
                t0 = time.perf_counter()
                kissm.ground_mask(xyz, v, num_threads=threads)
                dt = (time.perf_counter() - t0) * 1e3
                if rep:
                    times[str(v)].append(dt)
            t0 = time.perf_counter()
            pw.estimateGround(xyzi)
            dt = (time.perf_counter() - t0) * 1e3
            if rep:
                times["pw"].append(dt)
                pw_own.append(float(pw.getTimeTaken()) / 1e3)  # its own timer, microseconds
        rec["times_ms"] = times
        rec["pw_ms"] = statistics.median(times["pw"])
        rec["pw_own_ms"] = statistics.median(pw_own)
        for v in SEG_VOXELS:
            k = rec["kissm"][str(v)]
            k["ms"] = statistics.median(times[str(v)])
            k["speedup"] = rec["pw_ms"] / k["ms"] if k["ms"] else None
        results["seg"].append(rec)
        if rel == args.bev_scan or (args.smoke and not results.get("bev")):
            results["bev"] = {"scan": rel, "voxel": SEG_VOXELS[0]}
            results["_bev_arrays"] = (xyz, masks[SEG_VOXELS[0]], truth)
        k3, k5 = rec["kissm"]["0.3"], rec["kissm"]["0.5"]
        print(
            f"ground_bench: seg {label:26s} {len(xyz):7,d} pts | IoU {k3['iou']:.3f} / {k5['iou']:.3f} | "
            f"kissm {k3['ms']:.1f} / {k5['ms']:.1f} ms, Patchwork++ {rec['pw_ms']:.1f} ms | "
            f"{k3['speedup']:.2f}x / {k5['speedup']:.2f}x",
            flush=True,
        )


# ---- 2 and 3. registration -------------------------------------------------------------------------------


def _pin_worker(cpus: list[int], threads: int) -> None:
    os.environ["OMP_NUM_THREADS"] = str(threads)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)


def reference_call(voxel: float, src: np.ndarray, tgt: np.ndarray, quatro: bool) -> dict[str, Any]:
    """In a helper process: the reference as bench/bench.py calls it, with ``use_quatro``."""
    import kiss_matcher as km

    t0 = time.perf_counter()
    matcher = km.KISSMatcher(km.KISSMatcherConfig(voxel, use_quatro=quatro))
    solution = matcher.estimate(src, tgt)
    transform = reference_transform(solution)
    wall = (time.perf_counter() - t0) * 1e3
    inliers = int(matcher.get_num_final_inliers())
    matching = matcher.get_matching_time() * 1e3
    pruning = matcher.get_rejection_time() * 1e3
    return {
        "wall_ms": wall,
        "transform": transform.tolist(),
        "valid": bool(solution.valid) and inliers >= REFERENCE_MIN_INLIERS,
        "reason": "solution.valid" if solution.valid else "solution not valid",
        "inliers": inliers,
        "features_ms": matcher.get_extraction_time() * 1e3,
        "matching_ms": max(0.0, matching - pruning),
        "pruning_ms": pruning,
        "solver_ms": matcher.get_solver_time() * 1e3,
        "voxelize_ms": matcher.get_processing_time() * 1e3,
    }


class References:
    """One helper process per voxel size (Quatro's statics), started on first use."""

    def __init__(self, cpus: list[int], threads: int):
        self.cpus, self.threads = cpus, threads
        self.pools: dict[float, concurrent.futures.ProcessPoolExecutor] = {}
        self.warm: set[float] = set()

    def call(self, voxel: float, src: np.ndarray, tgt: np.ndarray, quatro: bool) -> dict[str, Any]:
        if voxel not in self.pools:
            self.pools[voxel] = concurrent.futures.ProcessPoolExecutor(
                max_workers=1,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_pin_worker,
                initargs=(self.cpus, self.threads),
            )
        return self.pools[voxel].submit(reference_call, voxel, src, tgt, quatro).result()

    def close(self) -> None:
        for pool in self.pools.values():
            pool.shutdown()


def kissm_call(src: np.ndarray, tgt: np.ndarray, voxel: float, threads: int, change: dict[str, Any]) -> dict[str, Any]:
    import kissm

    t0 = time.perf_counter()
    r = kissm.register(src, tgt, voxel, num_threads=threads, **change)
    wall = (time.perf_counter() - t0) * 1e3
    return {
        "wall_ms": wall,
        "transform": r.transform.tolist(),
        "rotation": r.rotation.tolist(),
        "valid": bool(r.valid),
        "reason": str(r.reason),
        "inliers": int(r.num_final_inliers),
        "keypoints": int(r.num_source_keypoints) + int(r.num_target_keypoints),
        "suppressed": int(r.num_source_suppressed) + int(r.num_target_suppressed),
        "voxels": int(r.num_source_voxels) + int(r.num_target_voxels),
        "initial_corr": int(r.num_initial_correspondences),
        "inlier_ratio": finite(r.inlier_ratio),
        "tilt_deg": None if not math.isfinite(r.tilt) else math.degrees(r.tilt),
        "voxelize_ms": r.time_voxelize_ms,
        "features_ms": r.time_features_ms,
        "suppression_ms": r.time_suppression_ms,
        "matching_ms": r.time_matching_ms,
        "pruning_ms": r.time_pruning_ms,
        "solver_ms": r.time_solver_ms,
        "total_ms": r.time_total_ms,
    }


def make_cases(pairs: list[Any], smoke: bool) -> list[dict[str, Any]]:
    """The variants of every pair: raw, yaw-turned (timed, every method), wrong up and tilted (once)."""
    import realdata

    yaws = (120.0,) if smoke else YAWS_DEG
    wrong = (90.0,) if smoke else WRONG_UP_DEG
    tilts = (10.0,) if smoke else TILTS_DEG
    cases = []
    for p in pairs:
        src = realdata.read_cached(p.source, p.source_format)
        tgt = realdata.read_cached(p.target, p.target_format)
        base = {
            "pair": p.name,
            "voxel": p.kind.voxel,
            "max_rot": p.kind.max_rot_deg,
            "max_trans": p.kind.max_trans_m,
            "tgt": tgt,
            "src0": src,
            "gt0": p.gt,
        }
        cases.append({**base, "group": "yaw", "axis": "z", "deg": 0.0, "variant": "raw"})
        for d in yaws:
            cases.append({**base, "group": "yaw", "axis": "z", "deg": d, "variant": f"yaw {d:+g}°"})
        for d in sorted(set(wrong) | set(tilts)):
            groups = [g for g, angles in (("wrong_up", wrong), ("tilt", tilts)) if d in angles]
            cases.append({**base, "group": "+".join(groups), "axis": "x", "deg": d, "variant": f"about x {d:g}°"})
    for c in cases:
        r = rot_about(c["axis"], c["deg"])
        c["src"] = np.ascontiguousarray(c["src0"] @ r.T)
        gt = c["gt0"].copy()
        gt[:3, :3] = c["gt0"][:3, :3] @ r.T  # p_t = R_gt p_s + t = (R_gt R^T)(R p_s) + t
        c["gt"] = gt
    return cases


def case_methods(case: dict[str, Any], reference: bool) -> list[str]:
    groups = case["group"].split("+")
    methods: list[str] = []
    if "yaw" in groups:
        methods = ["none", "ground", "dof1"] + (["ref_quatro"] if reference else [])
    if "wrong_up" in groups:
        methods += ["none", "ground"]
    if "tilt" in groups:
        methods += ["dof1"] + (["ref_quatro"] if reference else [])
    return list(dict.fromkeys(methods))


def run_registration(args: argparse.Namespace, results: dict[str, Any], threads: int, cpus: list[int]) -> None:
    reference = not args.no_reference and importlib.util.find_spec("kiss_matcher") is not None
    results["meta"]["reference"] = reference
    if not reference:
        results["notes"].append("The reference (kiss_matcher) is not installed or --no-reference: kissm only.")
    refs = References(cpus, threads)
    try:
        for case in make_cases(lidar_pairs(args.data, args.smoke), args.smoke):
            methods = case_methods(case, reference)
            timed = case["group"] == "yaw"
            reps = args.repeats if timed else 1
            where = {
                "pair": case["pair"],
                "variant": case["variant"],
                "group": case["group"],
                "axis": case["axis"],
                "deg": case["deg"],
                "voxel": case["voxel"],
            }

            def one(method: str, case: dict[str, Any] = case) -> dict[str, Any]:
                if method == "ref_quatro":
                    return refs.call(case["voxel"], case["src"], case["tgt"], True)
                return kissm_call(case["src"], case["tgt"], case["voxel"], threads, KISSM_METHODS[method])

            for rep in range(-1 if timed else 0, reps):  # rep -1: the untimed warm-up
                for method in methods:
                    if rep == -1 and method == "ref_quatro" and case["voxel"] in refs.warm:
                        continue  # the reference's helper process is warm from an earlier case
                    try:
                        rec = one(method)
                    except Exception as exc:  # noqa: BLE001 - recorded, counted, and the run goes on
                        results["errors"].append(
                            {**where, "method": method, "rep": rep, "error": f"{type(exc).__name__}: {exc}"}
                        )
                        print(f"ground_bench: ERROR {where} {method}: {type(exc).__name__}: {exc}", flush=True)
                        continue
                    if method == "ref_quatro":
                        refs.warm.add(case["voxel"])
                    if rep == -1:
                        continue
                    rot, trans = pose_errors(np.asarray(rec["transform"]), case["gt"])
                    rec.update(where, method=method, rep=rep, rre_deg=rot, rte_m=trans)
                    rec["within"] = rot is not None and rot < case["max_rot"] and trans < case["max_trans"]
                    rec["success"] = bool(rec["valid"] and rec["within"])
                    rec["wrong_valid"] = bool(rec["valid"] and not rec["within"])
                    rec["about_up_dev"] = about_up_deviation(np.asarray(rec["transform"])[:3, :3])
                    results["runs"].append(rec)
                    if rec["wrong_valid"] and method != "ref_quatro":
                        print(
                            f"ground_bench: !!! WRONG VALID: kissm {method} on {where}: {rot:.2f}° / {trans:.2f} m",
                            file=sys.stderr,
                            flush=True,
                        )
            print(f"ground_bench: {progress_line(results, where)}", flush=True)
    finally:
        refs.close()


def progress_line(results: dict[str, Any], where: dict[str, Any]) -> str:
    runs = [r for r in results["runs"] if r["pair"] == where["pair"] and r["variant"] == where["variant"]]
    parts = [f"{where['pair'].split('/')[0][:18]}/{where['pair'].split('/')[-1]} {where['variant']}"]
    for m in ("none", "ground", "dof1", "ref_quatro"):
        mine = [r for r in runs if r["method"] == m]
        if mine:
            ok = sum(r["success"] for r in mine)
            v0 = sum(not r["valid"] for r in mine)
            parts.append(f"{m} {ok}/{len(mine)} ok {v0} v0 {statistics.median(r['wall_ms'] for r in mine):.0f} ms")
    return " | ".join(parts)


# ---- summary ---------------------------------------------------------------------------------------------


def med(values: Any) -> float | None:
    kept = [v for v in values if v is not None]
    return statistics.median(kept) if kept else None


def fmp(r: dict[str, Any]) -> float:
    return r["features_ms"] + r["matching_ms"] + r["pruning_ms"]


def case_summary(runs: list[dict[str, Any]]) -> dict[str, Any] | None:
    """One method on one case: success count, median errors and counts, median times."""
    if not runs:
        return None
    ok = [r for r in runs if r["success"]]
    first = runs[0]
    out = {
        "calls": len(runs),
        "success": len(ok),
        "valid0": sum(not r["valid"] for r in runs),
        "wrong_valid": sum(r["wrong_valid"] for r in runs),
        "reasons": sorted({r["reason"] for r in runs if not r["valid"]}),
        "rre_deg": med(r["rre_deg"] for r in runs),
        "rte_m": med(r["rte_m"] for r in runs),
        "fmp_ms": med(fmp(r) for r in runs),
        "solver_ms": med(r["solver_ms"] for r in runs),
        "wall_ms": med(r["wall_ms"] for r in runs),
        "inliers": med(r["inliers"] for r in runs),
        "same_pose": len({json.dumps(r["transform"]) for r in runs}) == 1,
        "about_up_dev": max((r["about_up_dev"] for r in runs if r["about_up_dev"] is not None), default=None),
    }
    for key in ("keypoints", "suppressed", "initial_corr", "inlier_ratio", "tilt_deg", "suppression_ms"):
        if key in first:
            out[key] = med(r[key] for r in runs)
    return out


def summarise(results: dict[str, Any]) -> dict[str, Any]:
    runs = results["runs"]
    keys = list(dict.fromkeys((r["pair"], r["variant"], r["group"]) for r in runs))
    cases = []
    for pair, variant, group in keys:
        mine = [r for r in runs if r["pair"] == pair and r["variant"] == variant]
        row = {"pair": pair, "variant": variant, "group": group, "deg": mine[0]["deg"], "voxel": mine[0]["voxel"]}
        for m in ("none", "ground", "dof1", "ref_quatro"):
            row[m] = case_summary([r for r in mine if r["method"] == m])
        cases.append(row)
    yaw = [c for c in cases if c["group"] == "yaw"]

    def change(a: str, b: str, key: str) -> float | None:
        vals = [c[b][key] / c[a][key] for c in yaw if c[a] and c[b] and c[a].get(key) and c[b].get(key) is not None]
        return med(vals)

    supp = {
        "cases": len([c for c in yaw if c["ground"]]),
        "ground_success": sum(c["ground"]["success"] == c["ground"]["calls"] for c in yaw if c["ground"]),
        "none_success": sum(c["none"]["success"] == c["none"]["calls"] for c in yaw if c["none"]),
        "wrong_valid": sum(c["ground"]["wrong_valid"] for c in yaw if c["ground"]),
        **{f"change_{k}": change("none", "ground", k) for k in ("keypoints", "initial_corr", "inlier_ratio", "fmp_ms")},
        "fmp_faster_cases": sum(
            1 for c in yaw if c["ground"] and c["none"] and c["ground"]["fmp_ms"] < c["none"]["fmp_ms"]
        ),
    }
    dof = {
        "cases": len([c for c in yaw if c["dof1"]]),
        "dof1_success": sum(c["dof1"]["success"] == c["dof1"]["calls"] for c in yaw if c["dof1"]),
        "dof3_success": sum(c["none"]["success"] == c["none"]["calls"] for c in yaw if c["none"]),
        "ref_success": sum(c["ref_quatro"]["success"] == c["ref_quatro"]["calls"] for c in yaw if c["ref_quatro"]),
        "ref_cases": len([c for c in yaw if c["ref_quatro"]]),
        "dof1_wrong_valid": sum(c["dof1"]["wrong_valid"] for c in yaw if c["dof1"]),
        "ref_wrong_valid": sum(c["ref_quatro"]["wrong_valid"] for c in yaw if c["ref_quatro"]),
        "about_up_max_dev": max(
            (r["about_up_dev"] for r in runs if r["method"] == "dof1" and r["about_up_dev"] is not None), default=None
        ),
        "about_up_bad": sum(
            1
            for r in runs
            if r["method"] == "dof1" and (r["about_up_dev"] is None or r["about_up_dev"] >= ABOUT_UP_TOL)
        ),
        "dof1_calls": sum(1 for r in runs if r["method"] == "dof1"),
        "solver_ratio": change("dof1", "none", "solver_ms"),  # 3-DoF solver time over 1-DoF
        "solver_faster_cases": sum(
            1 for c in yaw if c["dof1"] and c["none"] and c["dof1"]["solver_ms"] < c["none"]["solver_ms"]
        ),
    }
    wrong_up = []
    for d in sorted({c["deg"] for c in cases if "wrong_up" in c["group"]}):
        sel = [c for c in cases if "wrong_up" in c["group"] and c["deg"] == d]
        entry = {"deg": d}
        for m in ("none", "ground"):
            rs = [r for r in runs if r["method"] == m and r["axis"] == "x" and r["deg"] == d]
            entry[m] = {
                "calls": len(rs),
                "success": sum(r["success"] for r in rs),
                "valid0": sum(not r["valid"] for r in rs),
                "wrong_valid": sum(r["wrong_valid"] for r in rs),
                "reasons": sorted({r["reason"] for r in rs if not r["valid"]}),
            }
        entry["cases"] = len(sel)
        wrong_up.append(entry)
    tilt = []
    for d in sorted({c["deg"] for c in cases if "tilt" in c["group"]}):
        entry = {"deg": d}
        for m in ("dof1", "ref_quatro"):
            rs = [r for r in runs if r["method"] == m and r["axis"] == "x" and r["deg"] == d]
            entry[m] = {
                "calls": len(rs),
                "success": sum(r["success"] for r in rs),
                "valid0": sum(not r["valid"] for r in rs),
                "valid0_tilt": sum(not r["valid"] and TILT_REASON in r["reason"] for r in rs),
                "wrong_valid": sum(r["wrong_valid"] for r in rs),
                "reasons": sorted({r["reason"] for r in rs if not r["valid"]}),
                "tilt_deg": med(r.get("tilt_deg") for r in rs),
            }
        tilt.append(entry)
    seg = results["seg"]
    segsum = {}
    for v in SEG_VOXELS:
        ks = [s["kissm"][str(v)] for s in seg]
        full = [s["kissm"][str(v)] for s in seg if "keyframe" not in s["label"]]
        segsum[str(v)] = {
            "min_iou": min((k["iou"] for k in ks if k["iou"] is not None), default=None),
            "min_iou_raw": min((k["iou"] for k in full if k["iou"] is not None), default=None),
            "iou_pass": sum(1 for k in ks if k["iou"] is not None and k["iou"] >= IOU_TARGET),
            "min_speedup": min((k["speedup"] for k in ks if k["speedup"]), default=None),
            "speed_pass": sum(1 for k in ks if k["speedup"] and k["speedup"] >= SPEED_TARGET),
            "speed_pass_raw": sum(1 for k in full if k["speedup"] and k["speedup"] >= SPEED_TARGET),
            "scans_raw": len(full),
            "scans": len(ks),
        }
    kissm_wrong = sum(1 for r in runs if r["wrong_valid"] and r["method"] != "ref_quatro")
    return {
        "cases": cases,
        "supp": supp,
        "dof": dof,
        "wrong_up": wrong_up,
        "tilt": tilt,
        "seg": segsum,
        "kissm_wrong_valid": kissm_wrong,
    }


# ---- report ----------------------------------------------------------------------------------------------


def f2(v: float | None, nd: int = 2) -> str:
    return "–" if v is None else f"{v:.{nd}f}"


def fms(v: float | None) -> str:
    if v is None:
        return "–"
    return f"{v:,.0f}" if v >= 100 else f"{v:.1f}" if v >= 1 else f"{v:.2f}" if v >= 0.1 else f"{v:.3f}"


def fe(v: float | None) -> str:
    return "–" if v is None else f"{v:.1e}"


def fx(v: float | None) -> str:
    return "–" if v is None else f"{v:.2f}x"


def pct(v: float | None) -> str:
    return "–" if v is None else f"{100 * (v - 1):+.0f}%"


def ferr(s: dict[str, Any] | None) -> str:
    if not s or s["rre_deg"] is None:
        return "–"
    return f"{s['rre_deg']:.2f}°, {100 * s['rte_m']:.0f} cm"


def fok(s: dict[str, Any] | None) -> str:
    if not s:
        return "–"
    txt = f"{s['success']}/{s['calls']}"
    if s["wrong_valid"]:
        txt += f" **{s['wrong_valid']} WRONG VALID**"
    elif s["valid0"]:
        txt += f" ({s['valid0']} valid=0)"
    return txt


def short_pair(name: str) -> str:
    ds, _, pair = name.partition("/pairs/")
    short = {
        "small_gicp_lidar": "small_gicp",
        "kitti07_keyframes_gtsam_points": "KITTI 07 kf",
        "kitti_demo_scans_unverified": "KITTI sweeps",
    }.get(ds, ds)
    return f"{short} {pair}"


def verdict(ok: bool) -> str:
    return "**met**" if ok else "**MISSED**"


def write_report(results: dict[str, Any], out_dir: Path) -> list[Path]:
    s = summarise(results)
    meta = results["meta"]
    cmd = meta["command"]
    mach = meta["machine"]
    pk = meta["versions"]
    written: list[Path] = []
    img = out_dir / "img"
    plot_paths = make_plots(results, s, img)
    written += plot_paths
    L = [
        "# Ground-vehicle mode: ground suppression and the 4-DoF solver",
        "",
        f"Measured by `bench/ground_bench.py` (the command: `{cmd}`; this page is its output). The machine "
        f"has {mach.get('cpus_online', '?')} CPUs shared with other work, so the timings are noisy: the "
        "methods are interleaved call by call and medians are reported; ratios are of medians from the same run. "
        "Rewrite this page from the saved results with `python bench/ground_bench.py --report-from "
        f"{meta['raw']}`.",
        "",
    ]
    for note in results["notes"]:
        L.append(f"> {note}")
    if results["notes"]:
        L.append("")
    # --- 1
    L += ["## 1. Ground segmentation against Patchwork++", ""]
    seg = results["seg"]
    if seg:
        sv = s["seg"]
        L += [
            f"kissm's `ground_mask(points, voxel, num_threads={meta['threads']})` at voxel 0.3 m and 0.5 m against "
            "Patchwork++ (`pypatchworkpp` "
            f"{pk.get('pypatchworkpp', '?')}, `Parameters()` = its KITTI defaults: sensor height 1.723 m, range "
            "2.7–80 m), fed the file's intensity (1.0 for the keyframes, which have none). Patchwork++'s labels "
            "are the truth for precision (share of kissm's ground that Patchwork++ calls ground) and recall; its "
            "labels come from the first call of a fresh instance. Time: median of "
            f"{meta['args']['seg_repeats']} interleaved calls after one warm-up, kissm's whole call (a Matcher, "
            "voxelisation, the ground model, the per-point labels) against Patchwork++'s `estimateGround` (one "
            f"instance reused, as in a stream); 1 CPU{'s' if meta['threads'] > 1 else ''} pinned.",
            "",
            "| scan | points | PW++ ground | IoU 0.3 | P / R 0.3 | IoU 0.5 | P / R 0.5 | IoU 0.3 in 2.7–80 m | "
            "kissm 0.3 ms | kissm 0.5 ms | PW++ ms | speed-up 0.3 | speed-up 0.5 |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for r in seg:
            a, b = r["kissm"]["0.3"], r["kissm"]["0.5"]
            label = r["label"] + ("" if r["intensity"] else " (no intensity)")
            L.append(
                f"| {label} | {r['points']:,d} | {r['pw_ground']:,d} | {f2(a['iou'], 3)} | "
                f"{f2(a['precision'])} / {f2(a['recall'])} | {f2(b['iou'], 3)} | {f2(b['precision'])} / "
                f"{f2(b['recall'])} | {f2(a['iou_in_pw_range'], 3)} | {fms(a['ms'])} | {fms(b['ms'])} | "
                f"{fms(r['pw_ms'])} | {fx(a['speedup'])} | {fx(b['speedup'])} |"
            )
        L.append("")
        for v in SEG_VOXELS:
            x = sv[str(v)]
            L.append(
                f"- Voxel {v} m: IoU >= {IOU_TARGET} on {x['iou_pass']}/{x['scans']} scans (lowest "
                f"{f2(x['min_iou'], 3)}; lowest on the full sweeps and small_gicp scans {f2(x['min_iou_raw'], 3)}): "
                f"{verdict(x['iou_pass'] == x['scans'])}. At least {SPEED_TARGET:g}x faster on "
                f"{x['speed_pass']}/{x['scans']} scans (lowest {fx(x['min_speedup'])}): "
                f"{verdict(x['speed_pass'] == x['scans'])}; on the raw scans (the full sweeps and small_gicp's, the "
                f"issue's measure) {x.get('speed_pass_raw', '?')}/{x.get('scans_raw', '?')}: "
                f"{verdict(x.get('speed_pass_raw') == x.get('scans_raw'))}."
            )
        unstable = [r["label"] for r in seg if not r["pw_second_call_same"]]
        nondet = [r["label"] for r in seg if not all(k["deterministic"] for k in r["kissm"].values())]
        L.append(
            "- kissm's labels were the same on a second call on every scan."
            if not nondet
            else f"- **kissm's labels changed between two calls on: {', '.join(nondet)}.**"
        )
        if unstable:
            L.append(
                f"- Patchwork++'s labels differ between its first and second call on the same scan for "
                f"{len(unstable)}/{len(seg)} scans ({', '.join(unstable)}): it carries per-frame history (its "
                "adaptive elevation and flatness thresholds), so the IoU above uses the fresh instance's labels."
            )
        L.append(
            "- The KITTI 07 keyframes are pre-thinned (0.27 m median spacing), so every voxel holds a point or "
            "two; Patchwork++ is tuned for raw sweeps. The small_gicp scans are from an unnamed sensor at an "
            "unknown height (Patchwork++ assumes KITTI's 1.723 m); judge the target on the KITTI sweeps first."
        )
        inside = suppression_inside(results)
        if inside:
            L += [
                "",
                "Not the target's measurement, but what registration pays: inside `register(..., "
                "suppression='ground')` the ground model runs on the voxels the features use anyway, so its cost "
                "(`Result.time_suppression_ms`, both clouds, median over the raw case's calls) is far below a "
                "standalone `ground_mask` call:",
                "",
                "| pair | voxel | suppression inside register, both clouds, ms | Patchwork++ on the same two scans, ms "
                "| ratio |",
                "|---|---:|---:|---:|---:|",
            ]
            for row in inside:
                L.append(
                    f"| {short_pair(row['pair'])} | {row['voxel']:g} | {fms(row['supp_ms'])} | {fms(row['pw_ms'])} "
                    f"| {fx(row['pw_ms'] / row['supp_ms'] if row['supp_ms'] else None)} |"
                )
        if (img / "ground_agreement.png").is_file():
            L += ["", "![agreement](img/ground_agreement.png)", ""]
        L.append("")
    else:
        L += ["Not measured in this run (Patchwork++ missing or no scan).", ""]
    # --- 2
    cases = s["cases"]
    yaw = [c for c in cases if c["group"] == "yaw"]
    sp = s["supp"]
    L += [
        "## 2. Ground suppression in registration",
        "",
        "Every LiDAR pair of `../shared/data` (voxel 0.3 m for the sweeps and small_gicp scans, 0.5 m for the "
        f"keyframes), raw and with the source turned about up (z) by {', '.join(f'{d:g}°' for d in YAWS_DEG)}; "
        f"`kissm.register(src, tgt, voxel, num_threads={meta['threads']})` with `suppression='none'` and "
        f"`'ground'`, {meta['args']['repeats']} timed calls each after a warm-up, interleaved. Success: valid "
        "within 5° and 2 m. Keypoints: source + target; F+M+P: features (suppression included) + matching + "
        "pruning, median ms.",
        "",
        "| pair | variant | success none / ground | error none / ground | suppressed voxels | keypoints none → ground "
        "| initial corr. | inlier ratio | F+M+P ms none → ground | suppression ms |",
        "|---|---|---|---|---:|---|---|---|---|---:|",
    ]
    for c in yaw:
        a, b = c["none"], c["ground"]
        if not a or not b:
            continue
        L.append(
            f"| {short_pair(c['pair'])} | {c['variant']} | {fok(a)} / {fok(b)} | {ferr(a)} / {ferr(b)} | "
            f"{b['suppressed']:,.0f} | {a['keypoints']:,.0f} → {b['keypoints']:,.0f} | "
            f"{a['initial_corr']:,.0f} → {b['initial_corr']:,.0f} | {f2(a['inlier_ratio'], 3)} → "
            f"{f2(b['inlier_ratio'], 3)} | {fms(a['fmp_ms'])} → {fms(b['fmp_ms'])} | {fms(b['suppression_ms'])} |"
        )
    L += [
        "",
        f"- Median change with suppression over the {sp['cases']} cases: keypoints {pct(sp['change_keypoints'])}, "
        f"initial correspondences {pct(sp['change_initial_corr'])}, inlier ratio {pct(sp['change_inlier_ratio'])}, "
        f"features + matching + pruning time {pct(sp['change_fmp_ms'])} (faster in {sp['fmp_faster_cases']}/"
        f"{sp['cases']} cases).",
        f'- Target "every LiDAR pair, raw and yaw-turned, still succeeds": {sp["ground_success"]}/{sp["cases"]} '
        f"cases succeed on every call with suppression ({sp['none_success']}/{sp['cases']} without): "
        f"{verdict(sp['ground_success'] == sp['cases'])}. Wrong poses reported valid with suppression: "
        f"{sp['wrong_valid']}.",
        "",
        "### Wrong up",
        "",
        "The source turned about x (a horizontal axis), so its +z is not up and the ground model looks for a "
        "ground in the wrong direction; one call per pair. Success / valid = 0 / WRONG VALID (a valid pose "
        "outside the thresholds; must be 0).",
        "",
        "| source turned about x | pairs | suppression 'ground': ok / valid=0 / WRONG VALID | reasons | "
        "'none' (baseline): ok / valid=0 / WRONG VALID |",
        "|---|---:|---|---|---|",
    ]
    for w in s["wrong_up"]:
        g, n = w["ground"], w["none"]
        L.append(
            f"| {w['deg']:g}° | {w['cases']} | {g['success']} / {g['valid0']} / "
            f"{'**' + str(g['wrong_valid']) + '**' if g['wrong_valid'] else 0} | {'; '.join(g['reasons']) or '–'} | "
            f"{n['success']} / {n['valid0']} / {'**' + str(n['wrong_valid']) + '**' if n['wrong_valid'] else 0} |"
        )
    wu = sum(w["ground"]["wrong_valid"] for w in s["wrong_up"])
    L += ["", f"- Wrong-up wrong valids with suppression: **{wu}** ({verdict(wu == 0)}).", ""]
    # --- 3
    dof = s["dof"]
    L += [
        "## 3. 4-DoF (yaw-only) solver",
        "",
        f"The same raw and yaw-turned cases, `rotation_dof` 3 (default) against 1, and the reference "
        f"(`kiss-matcher` {pk.get('kiss-matcher', 'not installed')}) with `KISSMatcherConfig(voxel, "
        "use_quatro=True)` (its config has that flag), in its own helper process per voxel size, interleaved "
        "with kissm's calls. Solver: `Result.time_solver_ms` and the reference's `get_solver_time()`, median ms. "
        "Tilt: `Result.tilt` of the 1-DoF call. About z: the largest of |R22 − 1|, |R02|, |R12|, |R20|, |R21| "
        "of the returned rotation over the calls.",
        "",
        "| pair | variant | success 3-DoF / 1-DoF / ref Quatro | error 1-DoF | error ref Quatro | solver ms 3-DoF "
        "→ 1-DoF | ref Quatro solver ms | tilt ° | about z (1-DoF) | about z (ref) |",
        "|---|---|---|---|---|---|---:|---:|---:|---:|",
    ]
    for c in yaw:
        a, b, q = c["none"], c["dof1"], c["ref_quatro"]
        if not a or not b:
            continue
        L.append(
            f"| {short_pair(c['pair'])} | {c['variant']} | {fok(a)} / {fok(b)} / {fok(q)} | {ferr(b)} | {ferr(q)} | "
            f"{fms(a['solver_ms'])} → {fms(b['solver_ms'])} | {fms(q['solver_ms']) if q else '–'} | "
            f"{f2(b.get('tilt_deg'))} | {fe(b['about_up_dev'])} | "
            f"{fe(q['about_up_dev'] if q else None)} |"
        )
    ref_txt = (
        f"{dof['ref_success']}/{dof['ref_cases']} cases for the reference's Quatro mode "
        f"({dof['ref_wrong_valid']} wrong valid)"
        if dof["ref_cases"]
        else "the reference was not run"
    )
    L += [
        "",
        f'- Target "every run succeeds": {dof["dof1_success"]}/{dof["cases"]} cases succeed on every 1-DoF call '
        f"({dof['dof3_success']}/{dof['cases']} with 3-DoF; {ref_txt}): "
        f"{verdict(dof['dof1_success'] == dof['cases'])}.",
        f'- Target "the rotation is exactly about up": {dof["dof1_calls"] - dof["about_up_bad"]}/{dof["dof1_calls"]} '
        f"1-DoF calls within {ABOUT_UP_TOL:g} (largest deviation {fe(dof['about_up_max_dev'])}): "
        f"{verdict(dof['about_up_bad'] == 0)}.",
        f'- Target "the solver is faster than the 3-DoF one": faster in {dof["solver_faster_cases"]}/{dof["cases"]} '
        f"cases, median 3-DoF / 1-DoF solver time {fx(dof['solver_ratio'])}: "
        f"{verdict(dof['solver_faster_cases'] == dof['cases'])}"
        + (
            " (the slower cases differ by a few ms on a shared machine, possibly noise; the target is judged per case)."
            if 0 < dof["cases"] - dof["solver_faster_cases"] <= 2
            else "."
        ),
    ]
    vs = [
        (c["dof1"]["solver_ms"] / c["ref_quatro"]["solver_ms"], c["dof1"]["wall_ms"] / c["ref_quatro"]["wall_ms"])
        for c in yaw
        if c["dof1"] and c["ref_quatro"] and c["ref_quatro"]["solver_ms"] and c["ref_quatro"]["wall_ms"]
    ]
    if vs:
        L.append(
            "- Against the reference's Quatro mode: kissm's 1-DoF solver stage takes a median "
            f"{fx(med(v[0] for v in vs))} the reference's `get_solver_time()` (the two timers need not cover the same "
            f"work), while kissm's whole call takes {fx(med(v[1] for v in vs))} "
            "the reference's wall time."
        )
    L += [
        "- Where the pair itself has some relative roll or pitch (KITTI 07 000000__000001: `tilt` about 1.3°), the "
        "yaw-only pose keeps that much rotation error in every variant (both kissm and the reference), within the "
        "5° success threshold and under the 2° tilt limit.",
        "",
        "### Tilted pairs under rotation_dof=1",
        "",
        "The source turned about x, so the pair's relative roll is that angle: the yaw-only model cannot "
        'express it. Right: valid = 0 (reason "' + TILT_REASON + '"), or a valid pose within the '
        "thresholds. One call per pair.",
        "",
        "| turned about x | kissm 1-DoF: valid=0 (tilt reason) / ok / WRONG VALID | median tilt ° | other reasons | "
        "ref Quatro: ok / valid=0 / WRONG VALID |",
        "|---|---|---:|---|---|",
    ]
    for t in s["tilt"]:
        k, q = t["dof1"], t["ref_quatro"]
        others = [r for r in k["reasons"] if TILT_REASON not in r]
        L.append(
            f"| {t['deg']:g}° | {k['valid0']} ({k['valid0_tilt']}) / {k['success']} / "
            f"{'**' + str(k['wrong_valid']) + '**' if k['wrong_valid'] else 0} of {k['calls']} | {f2(k['tilt_deg'])} | "
            f"{'; '.join(others) or '–'} | "
            + (f"{q['success']} / {q['valid0']} / {q['wrong_valid']} of {q['calls']} |" if q["calls"] else "– |")
        )
    tw = sum(t["dof1"]["wrong_valid"] for t in s["tilt"])
    L += [
        "",
        f"- kissm tilted wrong valids: **{tw}** ({verdict(tw == 0)}). The reference has no such check: its "
        "Quatro mode reports what it finds.",
        "",
        "## Wrong poses reported valid",
        "",
        f"kissm, every call of this run: **{s['kissm_wrong_valid']}**"
        + (" — **NOT ZERO: a wrong pose was reported valid.**" if s["kissm_wrong_valid"] else "."),
        "",
    ]
    for r in results["runs"]:
        if r["wrong_valid"] and r["method"] != "ref_quatro":
            L.append(
                f"- **{LABEL[r['method']]}, {short_pair(r['pair'])}, {r['variant']}** (voxel {r['voxel']:g}): valid "
                f"with {r['rre_deg']:.2f}° / {r['rte_m']:.2f} m error; {r['inliers']} final inliers of "
                f"{r['initial_corr']:,d} initial correspondences (inlier ratio {f2(r['inlier_ratio'], 4)}), "
                f"`Result.tilt` {f2(r.get('tilt_deg'))}° against the {TILT_LIMIT_DEG:g}° limit "
                f"(`max_rotation_uncertainty`): the tilt measured on so few inliers missed the {r['deg']:g}° the "
                "source was turned by."
            )
    if s["kissm_wrong_valid"]:
        L.append("")
    if any(p.name == "ground_times.png" for p in plot_paths):
        L += ["![times](img/ground_times.png)", ""]
    # --- how
    L += [
        "## How it was measured",
        "",
        f"- Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online', '?')} CPUs online (allowed "
        f"{mach.get('cpus_allowed', '?')}), {mach.get('mem_total_gb', '?')} GB, {mach.get('platform', '?')}, "
        f"Python {mach.get('python', '?')}; kissm {pk.get('kissm') or 'from the checkout'} "
        f"(`{mach.get('kissm_library', '?')}`), kiss-matcher {pk.get('kiss-matcher', 'not installed')}, "
        f"pypatchworkpp {pk.get('pypatchworkpp', 'not installed')}, numpy {pk.get('numpy', '?')}; git "
        f"{mach.get('git', '?')}.",
        f"- Run: {meta['started']} to {meta.get('finished', '?')} ({meta.get('duration_s', 0) / 60:.1f} min); load "
        f"average {meta['load_start'][0]:.2f} at the start, {meta.get('load_end', [math.nan])[0]:.2f} at the end. "
        "Other work shared the 2 CPUs during the run.",
        f"- Pinning: the process (and the reference's helpers) to CPUs {meta['cpus']} with `sched_setaffinity`, "
        f"`OMP_NUM_THREADS={meta['threads']}`; kissm `num_threads={meta['threads']}`; Patchwork++ is "
        "single-threaded.",
        "- Cases: each pair's source read once (`kissm.read_points`), turned about its own origin (the sensor) by "
        "the variant's rotation R, ground truth `R_gt R^T`; success, errors and validity as in "
        "`bindings/python/tests/realdata.py` (LiDAR: 5° and 2 m). The reference is valid when `solution.valid` "
        f"and it has at least {REFERENCE_MIN_INLIERS} final inliers (as in `bench/bench.py`).",
        "- Timed registration cases (raw and yaw): one untimed warm-up call per method (the reference's helper "
        "once per voxel size), then the methods in turn, repeated. Wrong-up and tilted cases: one call each "
        "(kissm is deterministic: `same pose` held on every repeated case"
        + (
            ""
            if all(c[m]["same_pose"] for c in yaw for m in ("none", "ground", "dof1") if c[m])
            else " — **except some; see the raw results**"
        )
        + ").",
        f"- Raw results: `{meta['raw']}`.",
    ]
    if results["errors"]:
        L += ["", "## Calls that raised", ""]
        for e in results["errors"]:
            L.append(f"- {e}")
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "ground.md"
    path.write_text("\n".join(L) + "\n")
    return [path, *written]


def suppression_inside(results: dict[str, Any]) -> list[dict[str, Any]]:
    """Per pair: suppression's time inside register (raw case, both clouds) and Patchwork++ on its two scans."""
    rows = []
    pairs = list(dict.fromkeys(r["pair"] for r in results["runs"]))
    for pair in pairs:
        runs = [r for r in results["runs"] if r["pair"] == pair and r["variant"] == "raw" and r["method"] == "ground"]
        dataset, names = pair.split("/")[0], pair.split("/")[-1].split("__")
        scans = [
            s
            for s in results["seg"]
            if s["scan"].startswith(dataset + "/")
            and any(Path(s["scan"]).stem == n or Path(s["scan"]).parent.name == n for n in names)
        ]
        if not runs or len(scans) != 2:
            continue
        rows.append(
            {
                "pair": pair,
                "voxel": runs[0]["voxel"],
                "supp_ms": med(r["suppression_ms"] for r in runs),
                "pw_ms": sum(s["pw_ms"] for s in scans),
            }
        )
    return rows


def make_plots(results: dict[str, Any], s: dict[str, Any], img: Path) -> list[Path]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    img.mkdir(parents=True, exist_ok=True)
    out = []
    bev = results.get("_bev_arrays")
    if bev is not None:
        xyz, mask, truth = bev
        fig, ax = plt.subplots(figsize=(7, 7))
        keep = np.linalg.norm(xyz[:, :2], axis=1) < 50
        cats = [
            (~mask & ~truth, "#c8c8c8", "neither"),
            (mask & truth, "#2ca02c", "both ground"),
            (mask & ~truth, "#d62728", "kissm only"),
            (~mask & truth, "#1f77b4", "Patchwork++ only"),
        ]
        for sel, color, label in cats:
            sel = sel & keep
            ax.scatter(xyz[sel, 0], xyz[sel, 1], s=0.3, c=color, label=f"{label} ({sel.sum():,d})", linewidths=0)
        ax.set_aspect("equal")
        ax.set_title(
            f"{results['bev']['scan']}: kissm ground_mask (voxel {results['bev']['voxel']}) vs Patchwork++", fontsize=9
        )
        ax.legend(markerscale=20, fontsize=8, loc="upper right")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        fig.tight_layout()
        p = img / "ground_agreement.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        out.append(p)
    seg = results["seg"]
    yaw = [c for c in s["cases"] if c["group"] == "yaw" and c["none"] and c["ground"]]
    if seg or yaw:
        fig, axes = plt.subplots(1, 2, figsize=(12, 4.6))
        if seg:
            ax = axes[0]
            x = np.arange(len(seg))
            for i, (key, label, color) in enumerate(
                (("0.3", "kissm 0.3", "#d62728"), ("0.5", "kissm 0.5", "#ff7f0e"), ("pw", "Patchwork++", "#1f77b4"))
            ):
                vals = [r["pw_ms"] if key == "pw" else r["kissm"][key]["ms"] for r in seg]
                ax.bar(x + (i - 1) * 0.27, vals, 0.27, label=label, color=color)
            ax.set_xticks(x)
            ax.set_xticklabels(
                [r["label"].replace("KITTI-style sweep", "sweep").replace("KITTI 07 keyframe", "kf") for r in seg],
                rotation=35,
                ha="right",
                fontsize=7,
            )
            ax.set_ylabel("ms per scan (median, 1 thread)")
            ax.set_title("Ground segmentation time", fontsize=10)
            ax.legend(fontsize=8)
        if yaw:
            ax = axes[1]
            x = np.arange(len(yaw))
            ax.bar(x - 0.2, [c["none"]["fmp_ms"] for c in yaw], 0.4, label="suppression none", color="#7f7f7f")
            ax.bar(x + 0.2, [c["ground"]["fmp_ms"] for c in yaw], 0.4, label="suppression ground", color="#2ca02c")
            ax.set_xticks(x)
            ax.set_xticklabels(
                [f"{short_pair(c['pair'])} {c['variant']}" for c in yaw], rotation=60, ha="right", fontsize=6
            )
            ax.set_ylabel("features + matching + pruning ms (median)")
            ax.set_title("Registration front end with and without suppression", fontsize=10)
            ax.legend(fontsize=8)
        fig.tight_layout()
        p = img / "ground_times.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        out.append(p)
    return out


# ---- main ------------------------------------------------------------------------------------------------


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    data = Path(os.environ.get("KISSM_DATA_DIR", REPO.parent / "shared" / "data"))
    p.add_argument("--data", type=Path, default=data, help="the data folder (KISSM_DATA_DIR, else ../shared/data)")
    p.add_argument("--threads", type=int, default=1, help="CPUs pinned and kissm's num_threads (1)")
    p.add_argument("--repeats", type=int, default=3, help="timed registration calls per method and case (3)")
    p.add_argument("--seg-repeats", type=int, default=9, help="timed segmentation calls per method and scan (9)")
    p.add_argument(
        "--bev-scan",
        default="kitti_demo_scans_unverified/000000.bin",
        help="the scan drawn in docs/reports/img/ground_agreement.png",
    )
    p.add_argument("--no-reference", action="store_true", help="kissm only")
    p.add_argument("--no-seg", action="store_true", help="skip the segmentation part")
    p.add_argument("--no-reg", action="store_true", help="skip the registration parts")
    p.add_argument("--out", type=Path, default=REPO / "docs" / "reports", help="writes OUT/ground.md and OUT/img/ (docs)")
    p.add_argument(
        "--raw",
        type=Path,
        default=None,
        help="raw results (bench/results/ground_latest.json with the default --out, else OUT/ground_raw.json)",
    )
    p.add_argument("--report-from", type=Path, default=None, help="only rewrite the report from saved raw results")
    p.add_argument(
        "--smoke",
        action="store_true",
        help="well under a minute: one scan, the small_gicp pair (raw, one yaw, one wrong up, one tilt), "
        "1 repeat, results in a temp dir",
    )
    args = p.parse_args(argv)
    if args.smoke:
        explicit = {a.split("=")[0] for a in argv if a.startswith("--")}
        if "--repeats" not in explicit:
            args.repeats = 1
        if "--seg-repeats" not in explicit:
            args.seg_repeats = 2
    if args.repeats < 1 or args.seg_repeats < 1 or args.threads < 1:
        p.error("--repeats, --seg-repeats and --threads take at least 1")
    return args


def versions() -> dict[str, str | None]:
    return package_versions(("kissm", "kiss-matcher", "pypatchworkpp", "numpy", "matplotlib"))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.report_from is not None:
        saved = json.loads(args.report_from.read_text())
        for path in write_report(saved, args.out):
            print(f"ground_bench: wrote {path}")
        return 0
    why = data_missing(args.data)
    if why is not None:
        print(f"ground_bench: skipped: {why} (set --data or KISSM_DATA_DIR)", flush=True)
        return 0
    cpus = cpus_for(args.threads)
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)  # before Patchwork++ or kissm start any thread
    if importlib.util.find_spec("kissm") is None:
        print("ground_bench: the kissm Python package is not importable", file=sys.stderr)
        return 2
    explicit = {a.split("=")[0] for a in argv if a.startswith("--")}
    if args.smoke and "--out" not in explicit:
        args.out = Path(tempfile.mkdtemp(prefix="kissm-ground-smoke-"))
    if args.raw is None:
        committed = not args.smoke and args.out.resolve() == (REPO / "docs" / "reports").resolve()
        args.raw = HERE / "results" / "ground_latest.json" if committed else args.out / "ground_raw.json"
    command = os.environ.get("KISSM_BENCH_COMMAND") or "python bench/ground_bench.py " + " ".join(
        shlex.quote(a) for a in argv
    )
    raw_rel = args.raw.resolve()
    results: dict[str, Any] = {
        "meta": {
            "command": command.strip(),
            "args": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
            "threads": args.threads,
            "cpus": cpus,
            "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
            "load_start": os.getloadavg(),
            "machine": machine_info(sys.executable),
            "versions": versions(),
            "raw": str(raw_rel.relative_to(REPO)) if raw_rel.is_relative_to(REPO) else str(args.raw),
        },
        "notes": [],
        "seg": [],
        "runs": [],
        "errors": [],
    }
    print(
        f"ground_bench: threads {args.threads} (CPUs {cpus}), repeats {args.repeats}, seg repeats "
        f"{args.seg_repeats}, data {args.data}, load {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    t0 = time.monotonic()
    if not args.no_seg:
        run_segmentation(args, results, args.threads)
    if not args.no_reg:
        run_registration(args, results, args.threads, cpus)
    meta = results["meta"]
    meta["duration_s"] = time.monotonic() - t0
    meta["load_end"] = os.getloadavg()
    meta["finished"] = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    bev = results.pop("_bev_arrays", None)
    args.raw.parent.mkdir(parents=True, exist_ok=True)
    args.raw.write_text(json.dumps(results, indent=1) + "\n")
    if bev is not None:
        results["_bev_arrays"] = bev
    written = write_report(results, args.out)
    print(f"ground_bench: wrote {', '.join(str(p) for p in [*written, args.raw])} in {meta['duration_s']:.0f} s")
    s = summarise(results)
    status = 0
    if s["kissm_wrong_valid"]:
        print(f"ground_bench: !!! kissm reported {s['kissm_wrong_valid']} WRONG pose(s) valid", file=sys.stderr)
        status = 1
    if results["errors"]:
        print(f"ground_bench: {len(results['errors'])} call(s) raised", file=sys.stderr)
        status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
