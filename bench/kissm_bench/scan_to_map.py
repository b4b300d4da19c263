# SPDX-License-Identifier: MIT
"""Scan-to-map benchmark (issue 15): the time to register one LiDAR scan against maps of growing size, for
kissm with the map described once and reused, kissm's full register per call, and the reference
KISS-Matcher, which has no reusable map side. Writes docs/reports/scan_to_map.md,
docs/reports/img/scan_to_map_time.png and bench/results/map_latest.json.gz (the results the page is rendered
from; the page itself is kissm_bench.reports.scan_to_map's).

    python bench/map_bench.py [--threads 1 2] [--sizes 100000 330000 1300000 5300000] [--repeats 3] [--out DIR]
    python bench/map_bench.py --smoke           # well under a minute: one keyframe, 100K and 330K, a temp dir
    python bench/map_bench.py --report-from bench/results/map_latest.json.gz   # rewrite the page
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
import importlib
import importlib.util
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import common
from .common import (
    BENCH,
    RESULTS,
    allowed_cpus,
    cpus_for,
    package_versions,
    pin,
    proc_status,
    thread_env,
    trim_heap,
)
from .data import KEYFRAMES_DIR, keyframes
from .geometry import apply, pose_errors, rot_about
from .reference import estimate
from .reports import scan_to_map as page
from .reports.scan_to_map import reduce, write_report
from .results import destinations, rewrite_page, save, shown

SCRIPT = BENCH / "map_bench.py"  # what the worker processes run
COMMITTED = RESULTS / "map_latest.json.gz"  # what docs/reports/scan_to_map.md is rendered from
RAW_NAME = "map_raw.json"  # the raw results' name in any other --out
DEFAULT_SIZES = [100_000, 330_000, 1_300_000, 5_300_000]
SMOKE_SIZES = [100_000, 330_000]
SMOKE_KEYFRAMES = [1]


# ---- data and maps --------------------------------------------------------------------------------------


def data_missing(data: Path) -> str | None:
    """Why the benchmark cannot run on ``data``, or None."""
    root = data / KEYFRAMES_DIR
    needed = [root / f"{k:06d}" / "points.bin" for k in range(5)]
    needed += [root / "pairs" / f"{k - 1:06d}__{k:06d}" / "gt_T_target_source.txt" for k in range(1, 5)]
    absent = [p for p in needed if not p.is_file()]
    if absent:
        return f"no KITTI 07 keyframes at {root} ({absent[0].relative_to(root)} missing)"
    if not any((data / rel).is_file() for rel, _ in page.TILE_SOURCES):
        return "none of the distractor clouds " + ", ".join(rel for rel, _ in page.TILE_SOURCES) + f" under {data}"
    return None


def load_keyframes(data: Path) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """World pose of each keyframe (chained ground truth, keyframe 0 at the identity) and its points."""
    kf = keyframes(data)  # the same chain as docs/design/frames.md's scan-to-map runs (frame_study.py)
    if kf is None:
        raise FileNotFoundError(f"no KITTI 07 keyframes under {data}")
    return kf


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
        reach = self.tile_radius + page.TILE_SHIFT_M * math.sqrt(2.0) + 6.0 * page.TILE_JITTER_M
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
        keep = rng.permutation(len(cloud))[: int(round(page.TILE_KEEP * len(cloud)))]
        yaw = float(rng.uniform(0.0, 360.0))
        shift = rng.uniform(-page.TILE_SHIFT_M, page.TILE_SHIFT_M, size=2)
        dz = float(rng.uniform(-page.TILE_Z_SHIFT_M, page.TILE_Z_SHIFT_M))
        local = cloud[keep] - np.array([*cloud[:, :2].mean(axis=0), np.median(cloud[:, 2])])
        pts = local @ rot_about("z", yaw).T + rng.normal(0.0, page.TILE_JITTER_M, size=local.shape)
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
    for rel, fmt in page.TILE_SOURCES:
        if (data / rel).is_file():
            out.append((rel, np.ascontiguousarray(kissm.read_points(data / rel, format=fmt), dtype=np.float64)))
    return out


# ---- calls ----------------------------------------------------------------------------------------------


def judged(rec: dict[str, Any], transform: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    rot, trans = pose_errors(transform, gt)  # the translation error at the scan's sensor
    rec["rot_err_deg"], rec["trans_err_m"] = rot, trans
    rec["success"] = bool(
        rec["valid"] and rot is not None and trans is not None and rot < page.MAX_ROT_DEG and trans < page.MAX_TRANS_M
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
    rec: dict[str, Any] = {"wall_ms": (t2 - t0) * 1e3, "features_ms": (t1 - t0) * 1e3, "register_ms": (t2 - t1) * 1e3}
    rec["matching_ms"] = float(r.time_matching_ms)  # the registration stage that reads the map's descriptors
    rec.update(kissm_fields(r))
    return judged(rec, r.transform, gt)


def call_full(matcher: Any, scan: np.ndarray, world_map: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    t0 = time.perf_counter()
    r = matcher.register(scan, world_map)
    rec: dict[str, Any] = {"wall_ms": (time.perf_counter() - t0) * 1e3}
    rec.update(kissm_fields(r))
    return judged(rec, r.transform, gt)


def call_reference(km: Any, voxel: float, scan: np.ndarray, world_map: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    """The reference as bench/bench.py calls it: a fresh matcher per call, its own C++ stage times."""
    e = estimate(km, voxel, scan, world_map)
    stages = {
        "voxelize": e.processing_ms,
        "features": e.extraction_ms,
        "matching": e.matching_ms,  # its pruning (ROBIN) included
        "pruning": e.rejection_ms,
        "solver": e.solver_ms,
        "total": e.cxx_ms,
    }
    rec = {
        "wall_ms": e.wall_ms,
        "cxx_ms": e.cxx_ms,
        "valid": e.valid,
        "reason": "solution.valid" if e.solution_valid else "solution not valid",
        "inliers": e.inliers,
        "stages": stages,
    }
    return judged(rec, e.transform, gt)


# ---- the worker: one thread count, every size and scan ------------------------------------------------


def worker(args: argparse.Namespace, threads: int, out: Path) -> int:
    pin(cpus_for(threads))  # before the reference's TBB and OpenMP size their pools
    import kissm

    km: Any = None
    if not args.no_reference and importlib.util.find_spec("kiss_matcher") is not None:
        km = importlib.import_module("kiss_matcher")
    chain, cloud = load_keyframes(args.data)
    base_all = np.concatenate([apply(chain[j], cloud[j]) for j in range(len(cloud))])
    stream = Distractors(load_sources(args.data), base_all, args)
    res: dict[str, Any] = {
        "threads": threads,
        "cpus": allowed_cpus(),
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
    trim_heap()
    rss0 = proc_status().get("VmRSS", 0)
    t0 = time.perf_counter()
    map_features = describe(matcher, world_map)
    prep_ms = (time.perf_counter() - t0) * 1e3
    trim_heap()
    rss1 = proc_status().get("VmRSS", 0)
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
    for m in page.METHODS:
        runs = [r for r in res["runs"] if r["size"] == size and r["keyframe"] == k and r["method"] == m]
        if runs:
            ok = sum(r["success"] for r in runs)
            parts.append(f"{m} {statistics.median(r['wall_ms'] for r in runs):9.1f} ms ({ok}/{len(runs)} ok)")
    return " | ".join(parts)


# ---- the parent ----------------------------------------------------------------------------------------


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = common.script_parser(__doc__)
    common.add_data_option(p)
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
    common.add_output_options(p, "OUT/scan_to_map.md and OUT/img/", COMMITTED, RAW_NAME)
    p.add_argument(
        "--smoke",
        action="store_true",
        help="well under a minute: keyframe 1, sizes 100K and 330K, 1 repeat, 1 thread, results in a temp dir",
    )
    p.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    p.add_argument("--worker-out", type=Path, default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    explicit = common.explicit_options(argv)
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
    cmd = [sys.executable, str(SCRIPT), *argv, "--worker", str(threads), "--worker-out", str(out)]
    return subprocess.run(cmd, env=thread_env(threads), check=False).returncode


def versions() -> dict[str, str | None]:
    return package_versions(("kissm", "kiss-matcher", "numpy", "matplotlib"))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.worker is not None:
        return worker(args, args.worker, args.worker_out)
    if args.report_from is not None:
        return rewrite_page("map_bench", args.report_from, args.out, write_report)

    why = data_missing(args.data)
    if why is not None:
        return common.no_data("map_bench", why)
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

    if args.smoke and "--out" not in common.explicit_options(argv):
        args.out = Path(tempfile.mkdtemp(prefix="kissm-map-smoke-"))
    committed, raw = destinations(COMMITTED, RAW_NAME, args.out, args.smoke, args.raw)
    extra = {"versions": versions(), "reference": reference, "raw": shown(committed, raw)}
    results: dict[str, Any] = {
        "meta": common.run_meta("map_bench.py", argv, args, ("worker", "worker_out"), **extra),
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
    common.finish_meta(meta, t0)
    save(results, reduce(results), committed, raw)
    written = write_report(results, args.out) if results["maps"] else []
    files = [*written, *(path for path in (committed, raw) if path is not None)]
    print(f"map_bench: wrote {', '.join(str(path) for path in files)} in {meta['duration_s']:.0f} s")
    if results["errors"]:
        print(f"map_bench: {len(results['errors'])} call(s) raised", file=sys.stderr)
        return 1
    return 0
