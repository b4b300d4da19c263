#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Scan-to-map benchmark (issue 15): the time to register one LiDAR scan against maps of growing size, for
kissm with the map described once and reused, kissm's full register per call, and the reference
KISS-Matcher, which has no reusable map side. Writes docs/reports/scan_to_map.md, docs/reports/img/scan_to_map_time.png and
bench/results/map_latest.json.

    python bench/map_bench.py [--threads 1 2] [--sizes 100000 330000 1300000 5300000] [--repeats 3] [--out DIR]
    python bench/map_bench.py --smoke           # well under a minute: one keyframe, 100K and 330K, a temp dir
    bash bench/run.sh --maps [options]          # the same, after bench/run.sh's venv setup

The scans are the KITTI 07 keyframes of ../shared/data (or KISSM_DATA_DIR, or --data), each in its own sensor
frame; the map of keyframe k is the other four merged in the world frame (about 85K points), grown to each
size with distractor tiles: the other real LiDAR clouds of the data (never the keyframes) placed on a grid at
least 300 m away, each under a random yaw and shift, a random 70% subsample and 2 cm Gaussian jitter (seeded:
the same maps on every run). Per thread count, map size and scan, after one warm-up, the median of --repeats
timed calls of

* kissm, map reused: the map's features computed once (``Matcher.compute_features(map)``, reported as the
  map preparation), then per scan ``compute_features(scan)`` + ``register_features(scan_features, map_features)``;
* kissm, full: ``Matcher.register(scan, map)``;
* the reference (PyPI kiss-matcher): ``KISSMatcher(KISSMatcherConfig(voxel)).estimate(scan, map)``, once per
  scan above --reference-once-above map points (1.5M).

Each thread count runs in its own worker process pinned to that many CPUs with ``OMP_NUM_THREADS`` set, as
in bench/bench.py. A call succeeds when its pose is reported valid and is within 2 degrees and 0.5 m of the
ground truth. Needs numpy and kissm; the reference and matplotlib when installed. Exits 0 without running
when the data is absent, 1 when a call raised, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import importlib
import importlib.util
import json
import math
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
from bench import (  # noqa: E402
    REFERENCE_MIN_INLIERS,
    _proc_status,
    _trim_heap,
    cpus_for,
    machine_info,
    package_versions,
    reference_transform,
)

DEFAULT_SIZES = [100_000, 330_000, 1_300_000, 5_300_000]
SMOKE_SIZES = [100_000, 330_000]
SMOKE_KEYFRAMES = [1]
KEYFRAMES_DIR = "kitti07_keyframes_gtsam_points"
# The distractor tiles: the other real LiDAR clouds of the data, never the KITTI 07 keyframes (path, format).
TILE_SOURCES = (
    ("kitti_demo_scans_unverified/000000.bin", "kitti_bin_xyzi_f32"),
    ("kitti_demo_scans_unverified/000015.bin", "kitti_bin_xyzi_f32"),
    ("small_gicp_lidar/target.ply", "ply"),
    ("small_gicp_lidar/source.ply", "ply"),
)
TILE_KEEP = 0.7  # share of a source cloud's points in one tile (a random subset)
TILE_JITTER_M = 0.02  # Gaussian noise added to every tile point (sigma)
TILE_SHIFT_M = 30.0  # a tile's random shift from its grid cell's centre, in x and in y (uniform, +-)
TILE_Z_SHIFT_M = 1.0  # and in z, from the base map's median height
MAX_ROT_DEG, MAX_TRANS_M = 2.0, 0.5  # success: valid and within these of the ground truth
METHODS = ("kissm_reuse", "kissm_full", "reference")
LABEL = {
    "kissm_reuse": "kissm, map features reused",
    "kissm_full": "kissm, full register per scan",
    "reference": "reference KISS-Matcher",
    "prep": "kissm map preparation (once per map)",
}
COLOR = {"kissm_reuse": "#d62728", "kissm_full": "#ff7f0e", "reference": "#1f77b4", "prep": "#7f7f7f"}
TARGET_TEXT = "the target: per-scan time at 5M map points at most 2x the time at 100K"


# ---- data and maps --------------------------------------------------------------------------------------


def data_missing(data: Path) -> str | None:
    """Why the benchmark cannot run on ``data``, or None."""
    root = data / KEYFRAMES_DIR
    needed = [root / f"{k:06d}" / "points.bin" for k in range(5)]
    needed += [root / "pairs" / f"{k - 1:06d}__{k:06d}" / "gt_T_target_source.txt" for k in range(1, 5)]
    absent = [p for p in needed if not p.is_file()]
    if absent:
        return f"no KITTI 07 keyframes at {root} ({absent[0].relative_to(root)} missing)"
    if not any((data / rel).is_file() for rel, _ in TILE_SOURCES):
        return "none of the distractor clouds " + ", ".join(rel for rel, _ in TILE_SOURCES) + f" under {data}"
    return None


def load_keyframes(data: Path) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """World pose of each keyframe (chained ground truth, keyframe 0 at the identity) and its points."""
    from frame_study import keyframes  # the same chain as docs/design/frames.md's scan-to-map runs

    kf = keyframes(argparse.Namespace(data=data))
    if kf is None:
        raise FileNotFoundError(f"no KITTI 07 keyframes under {data}")
    return kf


def apply(t: np.ndarray, points: np.ndarray) -> np.ndarray:
    return np.asarray(points @ t[:3, :3].T + t[:3, 3])


def yaw_matrix(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def grid_cells(centre: np.ndarray, first_ring: float, spacing: float, count: int) -> list[np.ndarray]:
    """The ``count`` grid cell centres (spacing ``spacing``, centred on ``centre``) nearest to ``centre`` at
    ``first_ring`` or farther, nearest first (ties by angle): the distractor tiles grow outward."""
    half = 1
    while True:
        ij = [(i, j) for i in range(-half, half + 1) for j in range(-half, half + 1)]
        far = [(math.hypot(i, j) * spacing, math.atan2(j, i), i, j) for i, j in ij]
        far = sorted(c for c in far if c[0] >= first_ring)
        # Every cell within the square's inscribed circle is listed, so the nearest `count` are final.
        if len(far) >= count and far[count - 1][0] <= half * spacing:
            return [centre + spacing * np.array([i, j], dtype=np.float64) for _, _, i, j in far[:count]]
        half += 1


class Distractors:
    """The seeded stream of distractor points: tile after tile, each tile's points in a random order, so the
    first n points of the stream are whole tiles plus a random part of the next one. Every map is a base map
    plus a prefix of this stream: the maps are nested and the same on every run with the same seed."""

    def __init__(self, sources: list[tuple[str, np.ndarray]], base: np.ndarray, args: argparse.Namespace):
        self.sources = sources
        self.rng = np.random.default_rng(args.seed)
        self.centre = base[:, :2].mean(axis=0)
        self.z = float(np.median(base[:, 2]))
        self.base_radius = float(np.linalg.norm(base[:, :2] - self.centre, axis=1).max())
        self.tile_radius = max(
            float(np.linalg.norm(p[:, :2] - p[:, :2].mean(axis=0), axis=1).max()) for _, p in sources
        )
        # The farthest a tile point gets from its cell centre in x-y (the jitter's 6 sigma included).
        reach = self.tile_radius + TILE_SHIFT_M * math.sqrt(2.0) + 6.0 * TILE_JITTER_M
        if args.tile_spacing < 2.0 * reach:
            raise SystemExit(
                f"map_bench: --tile-spacing {args.tile_spacing} m would let tiles overlap (< {2 * reach:.0f})"
            )
        self.first_ring = self.base_radius + args.min_gap + reach  # every tile point >= min_gap from the base map
        self.spacing = args.tile_spacing
        self.cells: list[np.ndarray] = []
        self.chunks: list[np.ndarray] = []
        self.tiles: list[dict[str, Any]] = []
        self.length = 0

    def points(self, n: int) -> np.ndarray:
        """The first ``n`` points of the stream (float64, (n, 3))."""
        while self.length < n:
            self._add_tile()
        if n <= 0:
            return np.empty((0, 3))
        stream = np.concatenate(self.chunks) if len(self.chunks) > 1 else self.chunks[0]
        self.chunks = [stream]
        return stream[:n]

    def tiles_in(self, n: int) -> int:
        """How many tiles the first ``n`` points touch (the last one possibly in part)."""
        return sum(1 for t in self.tiles if t["start"] < n)

    def _add_tile(self) -> None:
        i = len(self.tiles)
        if i % 16 == 0:  # cells in batches, always the same ones for the same layout
            self.cells = grid_cells(self.centre, self.first_ring, self.spacing, i + 16)
        name, cloud = self.sources[i % len(self.sources)]
        rng = self.rng
        keep = rng.permutation(len(cloud))[: int(round(TILE_KEEP * len(cloud)))]
        yaw = float(rng.uniform(0.0, 360.0))
        shift = rng.uniform(-TILE_SHIFT_M, TILE_SHIFT_M, size=2)
        dz = float(rng.uniform(-TILE_Z_SHIFT_M, TILE_Z_SHIFT_M))
        local = cloud[keep] - np.array([*cloud[:, :2].mean(axis=0), np.median(cloud[:, 2])])
        pts = local @ yaw_matrix(yaw).T + rng.normal(0.0, TILE_JITTER_M, size=local.shape)
        centre = np.array([*(self.cells[i] + shift), self.z + dz])
        pts += centre
        self.tiles.append(
            {"source": name, "points": len(pts), "yaw_deg": yaw, "centre": centre.tolist(), "start": self.length}
        )
        self.chunks.append(pts)
        self.length += len(pts)

    def describe(self) -> dict[str, Any]:
        return {
            "base_centre_xy": self.centre.tolist(),
            "base_radius_m": self.base_radius,
            "tile_radius_m": self.tile_radius,
            "spacing_m": self.spacing,
            "first_ring_m": self.first_ring,
            "tiles": self.tiles,
        }


def load_sources(data: Path) -> list[tuple[str, np.ndarray]]:
    import kissm

    out = []
    for rel, fmt in TILE_SOURCES:
        if (data / rel).is_file():
            out.append((rel, np.ascontiguousarray(kissm.read_points(data / rel, format=fmt), dtype=np.float64)))
    return out


# ---- calls ----------------------------------------------------------------------------------------------


def pose_errors(transform: np.ndarray, gt: np.ndarray) -> tuple[float | None, float | None]:
    """Rotation error (degrees) and translation error at the scan's sensor (metres); None when not finite."""
    from validity_study import rotation_error_deg

    t = np.asarray(transform, dtype=np.float64)
    if not np.isfinite(t).all():
        return None, None
    return rotation_error_deg(t[:3, :3], gt[:3, :3]), float(np.linalg.norm(t[:3, 3] - gt[:3, 3]))


def judged(rec: dict[str, Any], transform: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    rot, trans = pose_errors(transform, gt)
    rec["rot_err_deg"], rec["trans_err_m"] = rot, trans
    rec["success"] = bool(
        rec["valid"] and rot is not None and trans is not None and rot < MAX_ROT_DEG and trans < MAX_TRANS_M
    )
    rec["transform"] = np.asarray(transform, dtype=np.float64).tolist()
    return rec


def kissm_fields(r: Any) -> dict[str, Any]:
    return {
        "valid": bool(r.valid),
        "reason": str(r.reason),
        "inliers": int(r.num_final_inliers),
        "map_voxels": int(r.num_target_voxels),
        "map_keypoints": int(r.num_target_keypoints),
        "scan_keypoints": int(r.num_source_keypoints),
        "stages": {
            "voxelize": r.time_voxelize_ms,
            "features": r.time_features_ms,
            "matching": r.time_matching_ms,
            "pruning": r.time_pruning_ms,
            "solver": r.time_solver_ms,
            "total": r.time_total_ms,
        },
    }


def describe(matcher: Any, cloud: np.ndarray) -> Any:
    """``Matcher.compute_features`` (``features`` in kissm builds that predate the name)."""
    compute = getattr(matcher, "compute_features", None) or matcher.features
    return compute(cloud)


def call_reuse(matcher: Any, scan: np.ndarray, map_features: Any, gt: np.ndarray) -> dict[str, Any]:
    t0 = time.perf_counter()
    scan_features = describe(matcher, scan)
    t1 = time.perf_counter()
    r = matcher.register_features(scan_features, map_features)
    t2 = time.perf_counter()
    rec = {"wall_ms": (t2 - t0) * 1e3, "features_ms": (t1 - t0) * 1e3, "register_ms": (t2 - t1) * 1e3}
    rec["matching_ms"] = float(r.time_matching_ms)  # the registration stage that reads the map's descriptors
    rec.update(kissm_fields(r))
    return judged(rec, r.transform, gt)


def call_full(matcher: Any, scan: np.ndarray, world_map: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    t0 = time.perf_counter()
    r = matcher.register(scan, world_map)
    rec = {"wall_ms": (time.perf_counter() - t0) * 1e3}
    rec.update(kissm_fields(r))
    return judged(rec, r.transform, gt)


def call_reference(km: Any, voxel: float, scan: np.ndarray, world_map: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    """The reference as bench/bench.py calls it: a fresh matcher per call, its own C++ stage times."""
    t0 = time.perf_counter()
    matcher = km.KISSMatcher(km.KISSMatcherConfig(voxel))
    solution = matcher.estimate(scan, world_map)
    transform = reference_transform(solution)
    wall = (time.perf_counter() - t0) * 1e3
    inliers = int(matcher.get_num_final_inliers())
    stages = {
        "voxelize": matcher.get_processing_time() * 1e3,
        "features": matcher.get_extraction_time() * 1e3,
        "matching": matcher.get_matching_time() * 1e3,  # its pruning (ROBIN) included
        "pruning": matcher.get_rejection_time() * 1e3,
        "solver": matcher.get_solver_time() * 1e3,
    }
    stages["total"] = stages["voxelize"] + stages["features"] + stages["matching"] + stages["solver"]
    rec = {
        "wall_ms": wall,
        "cxx_ms": stages["total"],
        "valid": bool(solution.valid) and inliers >= REFERENCE_MIN_INLIERS,
        "reason": "solution.valid" if solution.valid else "solution not valid",
        "inliers": inliers,
        "stages": stages,
    }
    return judged(rec, transform, gt)


# ---- the worker: one thread count, every size and scan ------------------------------------------------


def worker(args: argparse.Namespace, threads: int, out: Path) -> int:
    cpus = cpus_for(threads)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)  # before the reference's TBB and OpenMP size their pools
    import kissm

    km: Any = None
    if not args.no_reference and importlib.util.find_spec("kiss_matcher") is not None:
        km = importlib.import_module("kiss_matcher")
    chain, cloud = load_keyframes(args.data)
    base_all = np.concatenate([apply(chain[j], cloud[j]) for j in range(len(cloud))])
    stream = Distractors(load_sources(args.data), base_all, args)
    res: dict[str, Any] = {
        "threads": threads,
        "cpus": sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else [],
        "reference": km is not None,
        "maps": [],
        "prep": [],
        "runs": [],
        "errors": [],
    }

    def save() -> None:
        res["layout"] = stream.describe()
        out.write_text(json.dumps(res))

    def attempt(what: dict[str, Any], fn: Any, *fn_args: Any) -> dict[str, Any] | None:
        try:
            return dict(fn(*fn_args))
        except Exception as exc:  # noqa: BLE001 - recorded, counted, and the run goes on
            res["errors"].append({**what, "error": f"{type(exc).__name__}: {exc}"})
            print(f"map_bench: {threads}t ERROR {what}: {type(exc).__name__}: {exc}", flush=True)
            return None

    matcher = kissm.Matcher(voxel_size=args.voxel, num_threads=threads, viewpoint_mode=args.viewpoint)
    state = {"reference_called": False}
    try:
        for size in args.sizes:
            for k in args.keyframes:
                where = {"threads": threads, "size": size, "keyframe": k}
                try:
                    one_map(args, res, where, matcher, km, chain, cloud, stream, state, attempt)
                except Exception as exc:  # noqa: BLE001 - recorded, counted, and the run goes on
                    res["errors"].append({**where, "error": f"{type(exc).__name__}: {exc}"})
                    print(f"map_bench: {threads}t ERROR {where}: {type(exc).__name__}: {exc}", flush=True)
                print(f"map_bench: {threads}t {progress_line(res, size, k)}", flush=True)
                save()
    finally:
        save()
    return 0


def one_map(
    args: argparse.Namespace,
    res: dict[str, Any],
    where: dict[str, Any],
    matcher: Any,
    km: Any,
    chain: list[np.ndarray],
    cloud: list[np.ndarray],
    stream: Distractors,
    state: dict[str, bool],
    attempt: Any,
) -> None:
    """Every measurement of one map size and scan: warm-up, the map side once, the timed calls."""
    size, k = where["size"], where["keyframe"]
    scan, gt = cloud[k], chain[k]
    base = np.concatenate([apply(chain[j], cloud[j]) for j in range(len(cloud)) if j != k])
    if args.absent:  # a control: the scan's place left out, so every pose reported valid is wrong
        extra = size
        world_map = np.ascontiguousarray(stream.points(extra))
    else:
        extra = max(0, size - len(base))
        world_map = np.ascontiguousarray(np.concatenate([base, stream.points(extra)]))
    res["maps"].append(
        {
            **where,
            "points": len(world_map),
            "base_points": 0 if args.absent else len(base),
            "tiles": stream.tiles_in(extra),
        }
    )
    use_reference = km is not None and (args.reference_max_points is None or size <= args.reference_max_points)
    once = size > args.reference_once_above
    # Warm-up (untimed): every method once on this map and scan; the reference above --reference-once-above
    # only when it has not run in this worker yet.
    warm = describe(matcher, world_map)
    attempt({**where, "method": "kissm_reuse", "warmup": True}, call_reuse, matcher, scan, warm, gt)
    del warm
    attempt({**where, "method": "kissm_full", "warmup": True}, call_full, matcher, scan, world_map, gt)
    if use_reference and (not once or not state["reference_called"]):
        state["reference_called"] = True
        attempt({**where, "method": "reference", "warmup": True}, call_reference, km, args.voxel, scan, world_map, gt)
    # The map side, once: its time, its size, and the resident memory it holds.
    _trim_heap()
    rss0 = _proc_status().get("VmRSS", 0)
    t0 = time.perf_counter()
    map_features = describe(matcher, world_map)
    prep_ms = (time.perf_counter() - t0) * 1e3
    _trim_heap()
    rss1 = _proc_status().get("VmRSS", 0)
    memory = getattr(map_features, "memory_bytes", None)  # a newer kissm's size of the Features object
    if callable(memory):
        memory = memory()
    res["prep"].append(
        {
            **where,
            "prep_ms": prep_ms,
            "map_points": int(map_features.num_points),
            "map_voxels": int(map_features.num_voxels),
            "map_keypoints": int(map_features.num_keypoints),
            "memory_bytes": None if memory is None else int(memory),
            "rss_growth_bytes": (rss1 - rss0) * 1024,
        }
    )
    # The timed calls, interleaved method by method.
    for rep in range(args.repeats):
        calls: list[tuple[str, Any, tuple[Any, ...]]] = [
            ("kissm_reuse", call_reuse, (matcher, scan, map_features, gt)),
            ("kissm_full", call_full, (matcher, scan, world_map, gt)),
        ]
        if use_reference and (not once or rep == 0):
            state["reference_called"] = True
            calls.append(("reference", call_reference, (km, args.voxel, scan, world_map, gt)))
        for method, fn, fn_args in calls:
            rec = attempt({**where, "method": method, "rep": rep}, fn, *fn_args)
            if rec is not None:
                res["runs"].append({**where, "method": method, "rep": rep, **rec})


def progress_line(res: dict[str, Any], size: int, k: int) -> str:
    prep = [p for p in res["prep"] if p["size"] == size and p["keyframe"] == k]
    parts = [f"map {size:>9,d} pts kf{k}"]
    if prep:
        parts.append(f"{prep[-1]['map_voxels']:>7,d} voxels, prep {prep[-1]['prep_ms']:8.1f} ms")
    for m in METHODS:
        runs = [r for r in res["runs"] if r["size"] == size and r["keyframe"] == k and r["method"] == m]
        if runs:
            ok = sum(r["success"] for r in runs)
            parts.append(f"{m} {statistics.median(r['wall_ms'] for r in runs):9.1f} ms ({ok}/{len(runs)} ok)")
    return " | ".join(parts)


# ---- summary and report --------------------------------------------------------------------------------


def med(values: list[float | None]) -> float | None:
    kept = [v for v in values if v is not None]
    return statistics.median(kept) if kept else None


def summarise(results: dict[str, Any], threads: int, size: int) -> dict[str, Any]:
    """One table row: medians over the keyframes of each scan's median over its timed calls."""
    runs = [r for r in results["runs"] if r["threads"] == threads and r["size"] == size]
    prep = [p for p in results["prep"] if p["threads"] == threads and p["size"] == size]
    maps = [m for m in results["maps"] if m["threads"] == threads and m["size"] == size]
    row: dict[str, Any] = {
        "size": size,
        "points": med([m["points"] for m in maps]),
        "points_range": (min(m["points"] for m in maps), max(m["points"] for m in maps)) if maps else None,
        "tiles": med([m["tiles"] for m in maps]),
        "voxels": med([p["map_voxels"] for p in prep]),
        "keypoints": med([p["map_keypoints"] for p in prep]),
        "prep_ms": med([p["prep_ms"] for p in prep]),
        "bytes_per_keypoint": med(
            [
                p["memory_bytes"] / p["map_keypoints"]
                for p in prep
                if p["memory_bytes"] is not None and p["map_keypoints"]
            ]
        ),
        "rss_per_keypoint": med([p["rss_growth_bytes"] / p["map_keypoints"] for p in prep if p["map_keypoints"]]),
    }
    keyframes = sorted({p["keyframe"] for p in prep} | {r["keyframe"] for r in runs})
    for m in METHODS:
        mine = [r for r in runs if r["method"] == m]
        per_scan: dict[str, list[float | None]] = {
            k: [] for k in ("wall_ms", "features_ms", "register_ms", "matching_ms", "cxx_ms")
        }
        for k in keyframes:
            calls = [r for r in mine if r["keyframe"] == k]
            for key in per_scan:
                per_scan[key].append(med([r.get(key) for r in calls]))
        ok = [r for r in mine if r["success"]]
        row[m] = {
            "calls": len(mine),
            "success": len(ok),
            "valid_wrong": sum(1 for r in mine if r["valid"] and not r["success"]),
            **{key: med(vals) for key, vals in per_scan.items()},
            "rot_err_deg": med([r["rot_err_deg"] for r in ok]),
            "trans_err_m": med([r["trans_err_m"] for r in ok]),
            "inliers": med([r["inliers"] for r in mine]),
        }
    reuse = {(r["keyframe"], r["rep"]): r["transform"] for r in runs if r["method"] == "kissm_reuse"}
    full = {(r["keyframe"], r["rep"]): r["transform"] for r in runs if r["method"] == "kissm_full"}
    both = [key for key in reuse if key in full]
    row["same_pose"] = (sum(1 for key in both if reuse[key] == full[key]), len(both))
    return row


def ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a is not None and b else None


def fmt_ms(v: float | None) -> str:
    if v is None:
        return "–"
    return f"{v:,.0f}" if v >= 100 else f"{v:.1f}" if v >= 10 else f"{v:.2f}"


def fmt_count(v: float | None) -> str:
    return "–" if v is None else f"{v:,.0f}"


def fmt_x(v: float | None) -> str:
    return "–" if v is None else f"{v:.1f}x" if v >= 10 else f"{v:.2f}x"


def fmt_err(rot: float | None, trans: float | None) -> str:
    return "–" if rot is None or trans is None else f"{rot:.2f}° / {100 * trans:.1f} cm"


def short_points(n: float) -> str:
    return f"{n / 1e6:.3g}M" if n >= 1e6 else f"{n / 1e3:.0f}K" if n >= 1e3 else f"{n:.0f}"


def verdict(rows: list[dict[str, Any]]) -> tuple[str, float | None]:
    """The target's verdict for one thread count: per-scan time at the largest map against the smallest."""
    if len(rows) < 2:
        return "not judged (one map size)", None
    first, last = rows[0], rows[-1]
    growth = ratio(last["kissm_reuse"]["wall_ms"], first["kissm_reuse"]["wall_ms"])
    if growth is None:
        return "not judged (no per-scan time)", None
    pts0, pts1 = first["points"], last["points"]
    judgeable = pts1 >= 5e6 and pts0 <= 1.5e5
    what = f"{growth:.2f}x from {short_points(pts0)} to {short_points(pts1)} map points"
    if not judgeable:
        return f"{what} (not judged: the run's sizes do not span 100K to 5M)", growth
    return f"{what}: {'met' if growth <= 2.0 else 'NOT met'}", growth


def headline(threads: int, rows: list[dict[str, Any]]) -> str:
    if not rows:
        return f"{threads} thread(s): no results."
    first, last = rows[0], rows[-1]
    reuse, full, ref = last["kissm_reuse"], last["kissm_full"], last["reference"]
    plural = "s" if threads > 1 else ""
    text = (
        f"At {threads} thread{plural}, a scan against the {short_points(last['points'])}-point map "
        f"({fmt_count(last['voxels'])} voxels) takes {fmt_ms(reuse['wall_ms'])} ms with the map's features reused "
        f"({fmt_x(ratio(reuse['wall_ms'], first['kissm_reuse']['wall_ms']))} its time against the "
        f"{short_points(first['points'])}-point map; preparing the map once took {fmt_ms(last['prep_ms'])} ms), "
        f"{fmt_ms(full['wall_ms'])} ms with a full register per scan"
    )
    if ref["wall_ms"] is not None:
        text += (
            f" and {fmt_ms(ref['wall_ms'])} ms with the reference, which describes the whole map on every call "
            f"({fmt_x(ratio(ref['wall_ms'], reuse['wall_ms']))} the reused-map time)"
        )
    else:
        text += "; the reference did not run at this size"
    text += (
        f". Successes there: kissm {reuse['success']}/{reuse['calls']} (reused map), "
        f"{full['success']}/{full['calls']} (full)"
    )
    if ref["calls"]:
        text += f", reference {ref['success']}/{ref['calls']}"
    return text + "."


def write_report(results: dict[str, Any], out_dir: Path) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    meta = results["meta"]
    threads_list = sorted({m["threads"] for m in results["maps"]})
    sizes = sorted({m["size"] for m in results["maps"]})
    table = {
        t: [
            summarise(results, t, s)
            for s in sizes
            if any(m["threads"] == t and m["size"] == s for m in results["maps"])
        ]
        for t in threads_list
    }
    written = []
    plot = make_plot(table, out_dir / "img" / "scan_to_map_time.png")
    if plot is not None:
        written.append(plot)

    mach = meta["machine"]
    pk = mach.get("packages", {})
    lay = results.get("layout") or {}
    kfs = meta["args"]["keyframes"]
    L = [
        "# Scan to map: per-scan time against growing maps",
        "",
        "<!-- Generated by bench/map_bench.py from its raw results; rerun the command below, do not edit. -->",
        "",
        "One LiDAR scan registered against maps of growing size (issue 15): kissm with the map described once "
        "(`Matcher.compute_features(map)`) and reused for every scan (`compute_features(scan)` + "
        "`register_features`), kissm's full `register(scan, map)` per scan, and the reference KISS-Matcher "
        f"(PyPI kiss-matcher {pk.get('kiss-matcher', 'not installed')}), which has no reusable map side and "
        "describes the whole map on every call.",
        "",
        f"**{TARGET_TEXT[0].upper() + TARGET_TEXT[1:]}.**",
        "",
    ]
    for t in threads_list:
        text, _ = verdict(table[t])
        L.append(f"- {t} thread{'s' if t > 1 else ''}: {text}.")
    L.append("")
    for t in threads_list:
        L += [headline(t, table[t]), ""]
    if results["errors"]:
        L += [f"**{len(results['errors'])} call(s) raised** (listed at the end); their rows are incomplete.", ""]

    L += ["## Results", ""]
    L += [
        "Times are wall times from Python (numpy arrays in, pose out), in ms: per scan the median over its timed "
        "calls, then the median over the scans. *kissm per scan* is `compute_features(scan)` + "
        "`register_features` (in brackets: the two parts, and the matching stage of the second, *m*); *map prep* "
        "is `compute_features(map)`, paid once per map; *reference* is the call's wall time (in brackets: the "
        "sum of its own C++ stage times). *vs smallest* is kissm's per-scan time against the smallest map's. "
        "Success: calls reported valid within "
        f"{MAX_ROT_DEG:g}° and {MAX_TRANS_M:g} m of the ground truth, out of all timed calls (kissm reused · kissm "
        "full · reference); errors are medians over the successes, inliers over all calls. *Bytes / keypoint*: "
        "the map features' `memory_bytes` per map keypoint (in brackets the resident memory the process grew by "
        "while computing them, per keypoint).",
        "",
    ]
    for t in threads_list:
        rows = table[t]
        L += [
            f"### {t} thread{'s' if t > 1 else ''}",
            "",
            "| map points | voxels | keypoints | map prep | kissm per scan | vs smallest | kissm full | reference "
            "| ref / kissm per scan | success | median error: kissm · ref | median inliers: kissm · ref "
            "| bytes / keypoint |",
            "|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|---|---|---:|",
        ]
        for row in rows:
            reuse, full, ref = row["kissm_reuse"], row["kissm_full"], row["reference"]
            lo, hi = row["points_range"]
            points = f"{lo:,d}" if lo == hi else f"{lo:,d}–{hi:,d}"
            per_scan = (
                f"{fmt_ms(reuse['wall_ms'])} ({fmt_ms(reuse['features_ms'])} + {fmt_ms(reuse['register_ms'])}, "
                f"m {fmt_ms(reuse['matching_ms'])})"
            )
            ref_ms = f"{fmt_ms(ref['wall_ms'])} ({fmt_ms(ref['cxx_ms'])})" if ref["calls"] else "not run"
            success = f"{reuse['success']}/{reuse['calls']} · {full['success']}/{full['calls']} · " + (
                f"{ref['success']}/{ref['calls']}" if ref["calls"] else "–"
            )
            mem = "n/a" if row["bytes_per_keypoint"] is None else f"{row['bytes_per_keypoint']:,.0f}"
            if row["rss_per_keypoint"] is not None:
                mem += f" ({row['rss_per_keypoint']:,.0f})"
            L.append(
                f"| {points} | {fmt_count(row['voxels'])} | {fmt_count(row['keypoints'])} | {fmt_ms(row['prep_ms'])} "
                f"| {per_scan} | {fmt_x(ratio(reuse['wall_ms'], rows[0]['kissm_reuse']['wall_ms']))} "
                f"| {fmt_ms(full['wall_ms'])} | {ref_ms} | {fmt_x(ratio(ref['wall_ms'], reuse['wall_ms']))} "
                f"| {success} | {fmt_err(reuse['rot_err_deg'], reuse['trans_err_m'])} · "
                f"{fmt_err(ref['rot_err_deg'], ref['trans_err_m'])} | {fmt_count(reuse['inliers'])} · "
                f"{fmt_count(ref['inliers'])} | {mem} |"
            )
        same = [row["same_pose"] for row in rows]
        wrong = {m: sum(row[m]["valid_wrong"] for row in rows) for m in METHODS}
        L += [
            "",
            f"kissm's reused-map pose equals its full register's bit for bit in {sum(s for s, _ in same)} of "
            f"{sum(n for _, n in same)} calls. Wrong poses reported valid: kissm reused {wrong['kissm_reuse']}, "
            f"kissm full {wrong['kissm_full']}, reference {wrong['reference']}.",
            "",
        ]
    if plot is not None:
        L += [f"![per-scan time against map points]({plot.relative_to(out_dir).as_posix()})", ""]
    else:
        L += ["(No plot: matplotlib is not installed.)", ""]

    L += ["## How it was measured", ""]
    L += [
        f"- Command: `{meta['command']}`; seed {meta['args']['seed']}, voxel {meta['args']['voxel']} m, "
        f"viewpoint mode `{meta['args']['viewpoint']}`, {meta['args']['repeats']} timed call(s) per method and scan "
        "after one warm-up call.",
        f"- Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online', '?')} CPUs online (allowed "
        f"{mach.get('cpus_allowed', '?')}), {mach.get('mem_total_gb', '?')} GB, {mach.get('platform', '?')}, "
        f"Python {mach.get('python', '?')}; kissm {pk.get('kissm', '?')}, kiss-matcher "
        f"{pk.get('kiss-matcher', 'not installed')}, numpy {pk.get('numpy', '?')}, matplotlib "
        f"{pk.get('matplotlib', 'not installed')}; git {mach.get('git', '?')}.",
        f"- Run: {meta['started']} to {meta.get('finished', '?')} ({meta.get('duration_s', 0) / 60:.1f} min); load "
        f"average {meta['load_start'][0]:.2f} at the start, {meta.get('load_end', [math.nan])[0]:.2f} at the end.",
        f"- Scans: the KITTI 07 keyframes {', '.join(map(str, kfs))} of `../shared/data/{KEYFRAMES_DIR}`, each in "
        "its own sensor frame; ground truth: its world pose, chained through the pairs' `gt_T_target_source.txt` "
        "from keyframe 0 (as `bench/frame_study.py`).",
        "- Maps, in the world frame: the other four keyframes merged (the base map), then distractor tiles up to "
        "the map size: tile after tile, one of " + ", ".join(f"`{rel}`" for rel, _ in TILE_SOURCES) + " in turn, "
        f"a random {TILE_KEEP:.0%} of its points under a random yaw, {100 * TILE_JITTER_M:g} cm Gaussian jitter, "
        f"shifted up to {TILE_SHIFT_M:g} m from the centre of its cell of a grid with {lay.get('spacing_m', 0):g} m "
        f"spacing, nearest cells first, at least {meta['args']['min_gap']:g} m from every base map point; the last "
        "tile a random part of one. The maps of one seed are nested and the same on every run and thread count.",
        "- Each thread count runs in its own worker process pinned to that many CPUs (`sched_setaffinity`) with "
        "`OMP_NUM_THREADS` set before the reference is imported; kissm gets `num_threads`. Per map size and scan: "
        "one untimed warm-up call of each method, the map features computed once (timed: map prep), then the "
        "timed calls interleaved (kissm reused, kissm full, reference, and again). One kissm Matcher per worker.",
        f"- The reference runs as in `bench/bench.py` (a fresh `KISSMatcher(KISSMatcherConfig(voxel))` and "
        f"`estimate(scan, map)` per call; valid when `solution.valid` and at least {REFERENCE_MIN_INLIERS} final "
        f"inliers). Above {meta['args']['reference_once_above']:,d} map points it is called once per scan, "
        "without a warm-up of its own (it has run on the smaller maps in the same process)"
        + (
            f"; above {meta['args']['reference_max_points']:,d} map points it is not run."
            if meta["args"]["reference_max_points"] is not None
            else "."
        ),
        "- Memory: `memory_bytes` of the map's Features object when the kissm build offers it (else n/a), and "
        "the growth of the worker's resident set while computing them (after `malloc_trim`; a rough cross-check).",
    ]
    if lay:
        L.append(
            f"- Layout: base map radius {lay['base_radius_m']:.0f} m around its centre, tile radius up to "
            f"{lay['tile_radius_m']:.0f} m, nearest tile cell centre {lay['first_ring_m']:.0f} m from the base "
            f"map's centre; {len(lay['tiles'])} tile(s) made for the largest map. Raw results: `{meta['raw']}`."
        )
    if results["errors"]:
        L += ["", "## Calls that raised", ""]
        for e in results["errors"]:
            where = ", ".join(f"{key} {e[key]}" for key in ("threads", "size", "keyframe", "method", "rep") if key in e)
            L.append(f"- {where}: `{e['error']}`")
    path = out_dir / "scan_to_map.md"
    path.write_text("\n".join(L) + "\n")
    written.insert(0, path)
    return written


def make_plot(table: dict[int, list[dict[str, Any]]], path: Path) -> Path | None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    except ImportError:
        return None
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    styles = ["-", "--", ":", "-."]
    for i, (threads, rows) in enumerate(sorted(table.items())):
        tag = f", {threads} thread{'s' if threads > 1 else ''}" if len(table) > 1 else ""
        for m in (*METHODS, "prep"):
            pts = [
                (row["points"], row["prep_ms"] if m == "prep" else row[m]["wall_ms"])
                for row in rows
                if (row["prep_ms"] if m == "prep" else row[m]["wall_ms"]) is not None
            ]
            if not pts:
                continue
            xs, ys = zip(*pts, strict=True)
            ax.plot(
                xs,
                ys,
                styles[i % len(styles)],
                marker="o" if m != "prep" else "s",
                ms=4,
                color=COLOR[m],
                alpha=0.6 if m == "prep" else 1.0,
                label=LABEL[m] + tag,
            )
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis, label in ((ax.xaxis, short_points), (ax.yaxis, lambda v: f"{v:,.0f}")):
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _pos, label=label: label(v)))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("map points")
    ax.set_ylabel("wall time per scan [ms] (map prep: per map)")
    ax.set_title("Scan to map: time against map size (median over scans)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    legend_rows = math.ceil(len(ax.get_lines()) / 2)
    if legend_rows:
        fig.legend(fontsize=7, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0.0, 0.035 * legend_rows + 0.02, 1.0, 1.0))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ---- the parent ----------------------------------------------------------------------------------------


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    data = Path(os.environ.get("KISSM_DATA_DIR", REPO.parent / "shared" / "data"))
    p.add_argument("--data", type=Path, default=data, help="the data folder (KISSM_DATA_DIR, else ../shared/data)")
    p.add_argument("--threads", type=int, nargs="+", default=[1], help="thread counts, each measured separately (1)")
    p.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=DEFAULT_SIZES,
        help="total map points (100000 330000 1300000 5300000); a size below the base map's gives the base map",
    )
    p.add_argument("--keyframes", type=int, nargs="+", default=[0, 1, 2, 3, 4], help="the scans (KITTI 07 keyframes)")
    p.add_argument("--repeats", type=int, default=3, help="timed calls per method and scan after one warm-up (3)")
    p.add_argument("--voxel", type=float, default=0.5, help="voxel size in metres (0.5)")
    p.add_argument(
        "--viewpoint",
        default="local",
        choices=["fixed", "cloud_center", "sign_free", "local"],
        help="kissm's viewpoint_mode (local)",
    )
    p.add_argument("--seed", type=int, default=7, help="seed of the distractor tiles (7)")
    p.add_argument("--tile-spacing", type=float, default=300.0, help="grid spacing of the distractor tiles, m (300)")
    p.add_argument("--min-gap", type=float, default=300.0, help="least distance of a tile from the base map, m (300)")
    p.add_argument(
        "--reference-max-points",
        type=int,
        default=None,
        help="run the reference only on maps up to this many points (default: every size)",
    )
    p.add_argument(
        "--reference-once-above",
        type=int,
        default=1_500_000,
        help="above this many map points the reference is called once per scan (1500000)",
    )
    p.add_argument("--no-reference", action="store_true", help="kissm only")
    p.add_argument(
        "--absent",
        action="store_true",
        help="a control: maps of distractor tiles only, without the scan's place (any valid pose is wrong)",
    )
    p.add_argument("--out", type=Path, default=REPO / "docs" / "reports", help="writes OUT/scan_to_map.md and OUT/img/ (docs)")
    p.add_argument(
        "--raw",
        type=Path,
        default=None,
        help="raw results JSON (default bench/results/map_latest.json with the default --out, else OUT/map_raw.json)",
    )
    p.add_argument("--report-from", type=Path, default=None, help="only rewrite the report from saved raw results")
    p.add_argument(
        "--smoke",
        action="store_true",
        help="well under a minute: keyframe 1, sizes 100K and 330K, 1 repeat, 1 thread, results in a temp dir",
    )
    p.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--worker-out", type=Path, default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    explicit = {a.split("=")[0] for a in argv if a.startswith("--")}
    if args.smoke:
        if "--keyframes" not in explicit:
            args.keyframes = SMOKE_KEYFRAMES
        if "--sizes" not in explicit:
            args.sizes = SMOKE_SIZES
        if "--repeats" not in explicit:
            args.repeats = 1
    if any(k not in range(5) for k in args.keyframes) or args.repeats < 1 or min(args.sizes) < 1:
        p.error("--keyframes take 0..4, --repeats and --sizes at least 1")
    args.sizes = sorted(set(args.sizes))
    args.threads = sorted(set(args.threads))
    return args


def run_worker(argv: list[str], threads: int, out: Path) -> int:
    env = dict(os.environ)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
        env[var] = str(threads)
    env["PYTHONUNBUFFERED"] = "1"
    cmd = [sys.executable, str(Path(__file__).resolve()), *argv, "--worker", str(threads), "--worker-out", str(out)]
    return subprocess.run(cmd, env=env, check=False).returncode


def versions() -> dict[str, str | None]:
    return package_versions(("kissm", "kiss-matcher", "numpy", "matplotlib"))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.worker is not None:
        return worker(args, args.worker, args.worker_out)
    if args.report_from is not None:
        saved = json.loads(args.report_from.read_text())
        for path in write_report(saved, args.out):
            print(f"map_bench: wrote {path}")
        return 0

    why = data_missing(args.data)
    if why is not None:
        print(f"map_bench: skipped: {why} (set --data or KISSM_DATA_DIR)", flush=True)
        return 0
    if importlib.util.find_spec("kissm") is None:
        print("map_bench: the kissm Python package is not importable (pip install ./bindings/python)", file=sys.stderr)
        return 2
    import kissm

    try:  # an older kissm build may not know the viewpoint mode: say so now, not in every call
        kissm.Matcher(voxel_size=args.voxel, viewpoint_mode=args.viewpoint).close()
    except ValueError as exc:
        print(f"map_bench: this kissm build refuses the settings: {exc} (--viewpoint, --voxel)", file=sys.stderr)
        return 2
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if max(args.threads) > available:
        print(
            f"map_bench: {max(args.threads)} threads asked for, but {available} CPU(s) are available", file=sys.stderr
        )
        return 2
    reference = not args.no_reference and importlib.util.find_spec("kiss_matcher") is not None
    if not args.no_reference and not reference:
        print("map_bench: the reference (kiss_matcher) is not installed: kissm only (bench/run.sh installs it)")

    explicit = {a.split("=")[0] for a in argv if a.startswith("--")}
    if args.smoke and "--out" not in explicit:
        args.out = Path(tempfile.mkdtemp(prefix="kissm-map-smoke-"))
    if args.raw is None:
        committed = not args.smoke and args.out.resolve() == (REPO / "docs" / "reports").resolve()
        args.raw = HERE / "results" / "map_latest.json" if committed else args.out / "map_raw.json"
    command = os.environ.get("KISSM_BENCH_COMMAND") or "python bench/map_bench.py " + " ".join(
        shlex.quote(a) for a in argv
    )
    results: dict[str, Any] = {
        "meta": {
            "command": command.strip(),
            "args": {
                k: (str(v) if isinstance(v, Path) else v)
                for k, v in vars(args).items()
                if k not in ("worker", "worker_out")
            },
            "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
            "load_start": os.getloadavg(),
            "machine": machine_info(sys.executable),
            "versions": versions(),
            "reference": reference,
            "raw": str(args.raw.resolve().relative_to(REPO))
            if args.raw.resolve().is_relative_to(REPO)
            else str(args.raw),
        },
        "maps": [],
        "prep": [],
        "runs": [],
        "errors": [],
        "layout": None,
    }
    print(
        f"map_bench: threads {args.threads}, sizes {args.sizes}, keyframes {args.keyframes}, repeats {args.repeats}, "
        f"viewpoint {args.viewpoint}, reference {'yes' if reference else 'no'}; data {args.data}; "
        f"load {os.getloadavg()[0]:.1f}",
        flush=True,
    )
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="kissm-map-") as tmp:
        for t in args.threads:
            out = Path(tmp) / f"worker_{t}.json"
            code = run_worker(argv, t, out)
            part = json.loads(out.read_text()) if out.is_file() else None
            if part is not None:
                for key in ("maps", "prep", "runs", "errors"):
                    results[key] += part[key]
                results["layout"] = part.get("layout") or results["layout"]
            if code != 0 or part is None:
                results["errors"].append({"threads": t, "error": f"the worker exited with status {code}"})
                print(f"map_bench: the {t}-thread worker exited with status {code}", flush=True)
    meta = results["meta"]
    meta["duration_s"] = time.monotonic() - t0
    meta["load_end"] = os.getloadavg()
    meta["finished"] = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    args.raw.parent.mkdir(parents=True, exist_ok=True)
    args.raw.write_text(json.dumps(results, indent=1) + "\n")
    written = write_report(results, args.out) if results["maps"] else []
    print(f"map_bench: wrote {', '.join(str(p) for p in [*written, args.raw])} in {meta['duration_s']:.0f} s")
    if results["errors"]:
        print(f"map_bench: {len(results['errors'])} call(s) raised", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
