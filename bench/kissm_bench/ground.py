# SPDX-License-Identifier: MIT
"""Ground-vehicle mode benchmark (issue 16): kissm's ground model against Patchwork++, ground suppression in
registration, and the 4-DoF (yaw-only) solver against the reference's Quatro mode. Writes docs/reports/ground.md,
docs/reports/img/ground_*.png and bench/results/ground_latest.json.gz (the results the page is rendered from; the
page itself is kissm_bench.reports.ground's).

    python bench/ground_bench.py [--threads 1] [--repeats 3] [--seg-repeats 9] [--out DIR]
    python bench/ground_bench.py --smoke        # well under a minute: one scan, one pair, a temp dir
    python bench/ground_bench.py --report-from bench/results/ground_latest.json.gz   # rewrite the page

Needs numpy and kissm importable; Patchwork++ (PyPI ``pypatchworkpp`` 1.4.1), the reference (PyPI
``kiss-matcher`` 1.0.2) and matplotlib when installed (each part that needs a missing one says so and is
skipped). The data is ../shared/data (or KISSM_DATA_DIR, or --data); the pairs, voxel sizes and success
thresholds are kissm_bench.data's, the same as the real-data tests' (LiDAR: valid within 5 degrees and 2 m).

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
import importlib.util
import math
import multiprocessing
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import common
from .common import (
    RESULTS,
    cpus_for,
    finite,
    package_versions,
    pin,
)
from .data import Pair, has_index, load_pairs, read_cached
from .geometry import pose_errors, rot_about
from .reference import estimate
from .reports.ground import (
    SEG_VOXELS,
    TILTS_DEG,
    WRONG_UP_DEG,
    YAWS_DEG,
    BevArrays,
    reduce,
    summarise,
    write_report,
)
from .results import destinations, rewrite_page, save, shown

COMMITTED = RESULTS / "ground_latest.json.gz"  # what docs/reports/ground.md is rendered from
RAW_NAME = "ground_raw.json"  # the raw results' name in any other --out
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
KISSM_METHODS: dict[str, dict[str, Any]] = {
    "none": {},
    "ground": {"suppression": "ground"},
    "dof1": {"rotation_dof": 1},
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
    if not has_index(data):
        return f"no index.tsv under {data}"
    return None


def lidar_pairs(data: Path, smoke: bool) -> list[Pair]:
    pairs = [p for p in load_pairs(data) if p.is_lidar]
    if smoke:
        pairs = [p for p in pairs if p.name.startswith(SMOKE_PAIR)][:1] or pairs[:1]
    return pairs


def about_up_deviation(rotation: np.ndarray) -> float | None:
    """The largest of |R22 - 1|, |R02|, |R12|, |R20|, |R21|: 0 for a rotation exactly about z."""
    r = np.asarray(rotation, dtype=np.float64)
    if not np.isfinite(r).all():
        return None
    return float(max(abs(r[2, 2] - 1.0), abs(r[0, 2]), abs(r[1, 2]), abs(r[2, 0]), abs(r[2, 1])))


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


def run_segmentation(args: argparse.Namespace, results: dict[str, Any], threads: int) -> BevArrays | None:
    """Every scan's segmentation into ``results``; the points and labels of the scan the agreement plot shows."""
    import kissm

    if importlib.util.find_spec("pypatchworkpp") is None:
        results["notes"].append("Patchwork++ (pypatchworkpp) is not installed: the segmentation part was skipped.")
        print("ground_bench: pypatchworkpp not installed: segmentation skipped", flush=True)
        return None
    import pypatchworkpp

    bev: BevArrays | None = None
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
            bev = (xyz, masks[SEG_VOXELS[0]], truth)
        k3, k5 = rec["kissm"]["0.3"], rec["kissm"]["0.5"]
        print(
            f"ground_bench: seg {label:26s} {len(xyz):7,d} pts | IoU {k3['iou']:.3f} / {k5['iou']:.3f} | "
            f"kissm {k3['ms']:.1f} / {k5['ms']:.1f} ms, Patchwork++ {rec['pw_ms']:.1f} ms | "
            f"{k3['speedup']:.2f}x / {k5['speedup']:.2f}x",
            flush=True,
        )
    return bev


# ---- 2 and 3. registration -------------------------------------------------------------------------------


def _pin_worker(cpus: list[int], threads: int) -> None:
    os.environ["OMP_NUM_THREADS"] = str(threads)
    pin(cpus)


def reference_call(voxel: float, src: np.ndarray, tgt: np.ndarray, quatro: bool) -> dict[str, Any]:
    """In a helper process: the reference as bench/bench.py calls it, with ``use_quatro``."""
    import kiss_matcher as km

    e = estimate(km, voxel, src, tgt, use_quatro=quatro)
    return {
        "wall_ms": e.wall_ms,
        "transform": e.transform.tolist(),
        "valid": e.valid,
        "reason": "solution.valid" if e.solution_valid else "solution not valid",
        "inliers": e.inliers,
        "features_ms": e.extraction_ms,
        "matching_ms": max(0.0, e.matching_ms - e.rejection_ms),
        "pruning_ms": e.rejection_ms,
        "solver_ms": e.solver_ms,
        "voxelize_ms": e.processing_ms,
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


def make_cases(pairs: list[Pair], smoke: bool) -> list[dict[str, Any]]:
    """The variants of every pair: raw, yaw-turned (timed, every method), wrong up and tilted (once)."""
    yaws = (120.0,) if smoke else YAWS_DEG
    wrong = (90.0,) if smoke else WRONG_UP_DEG
    tilts = (10.0,) if smoke else TILTS_DEG
    cases: list[dict[str, Any]] = []
    for p in pairs:
        src = read_cached(p.source, p.source_format)
        tgt = read_cached(p.target, p.target_format)
        base: dict[str, Any] = {
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


# ---- main ------------------------------------------------------------------------------------------------


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = common.script_parser(__doc__)
    common.add_data_option(p)
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
    common.add_output_options(p, "OUT/ground.md and OUT/img/", COMMITTED, RAW_NAME)
    p.add_argument(
        "--smoke",
        action="store_true",
        help="well under a minute: one scan, the small_gicp pair (raw, one yaw, one wrong up, one tilt), "
        "1 repeat, results in a temp dir",
    )
    args = p.parse_args(argv)
    if args.smoke:
        explicit = common.explicit_options(argv)
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
        return rewrite_page("ground_bench", args.report_from, args.out, write_report)
    why = data_missing(args.data)
    if why is not None:
        return common.no_data("ground_bench", why)
    cpus = cpus_for(args.threads)
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    pin(cpus)  # before Patchwork++ or kissm start any thread
    if importlib.util.find_spec("kissm") is None:
        print("ground_bench: the kissm Python package is not importable", file=sys.stderr)
        return 2
    if args.smoke and "--out" not in common.explicit_options(argv):
        args.out = Path(tempfile.mkdtemp(prefix="kissm-ground-smoke-"))
    committed, raw = destinations(COMMITTED, RAW_NAME, args.out, args.smoke, args.raw)
    results: dict[str, Any] = {
        "meta": common.run_meta(
            "ground_bench.py",
            argv,
            args,
            threads=args.threads,
            cpus=cpus,
            versions=versions(),
            raw=shown(committed, raw),
        ),
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
    bev = None
    if not args.no_seg:
        bev = run_segmentation(args, results, args.threads)
    if not args.no_reg:
        run_registration(args, results, args.threads, cpus)
    meta = results["meta"]
    common.finish_meta(meta, t0)
    save(results, reduce(results), committed, raw)
    written = write_report(results, args.out, bev)
    files = [*written, *(path for path in (committed, raw) if path is not None)]
    print(f"ground_bench: wrote {', '.join(str(path) for path in files)} in {meta['duration_s']:.0f} s")
    s = summarise(reduce(results))
    status = 0
    if s["kissm_wrong_valid"]:
        print(f"ground_bench: !!! kissm reported {s['kissm_wrong_valid']} WRONG pose(s) valid", file=sys.stderr)
        status = 1
    if results["errors"]:
        print(f"ground_bench: {len(results['errors'])} call(s) raised", file=sys.stderr)
        status = 1
    return status
