# SPDX-License-Identifier: MIT
"""Multiway benchmark (issue 34, section 4): kissm.multiway.align against Open3D 0.20's multiway registration as its
tutorials set it up, on the shared multi-scan sets, end to end from the files, at the same thread count.

    python bench/multiway_bench.py [--sets kitti07 bunny happy] [--threads 1 2] [--repeats 3] [--out FILE]

Every method gets the same scans, the same voxel size v (the sets' own, kissm_bench.data.SCAN_SETS) and the same
candidate pairs (every pair once):

* kissm: ``kissm.multiway.align(files, v, pairs="all", refine="gicp")``, each scan a ``kissm.batch.CloudFile`` read
  by the batch's own jobs; at 1 thread on the calling thread, at 2 on a ``ThreadPoolExecutor(2)`` with one library
  thread per job (what kissm.batch advises: one job per core).
* Open3D, as its "Global registration" and "Multiway registration" tutorials set it up: ``o3d.io.read_point_cloud``
  (a scan it reads as empty, or a raw ``.bin`` it has no reader for, is read with ``kissm.read_points`` and wrapped
  in a ``PointCloud``); ``voxel_down_sample(v)``, normals (radius 2v, 30 neighbours), FPFH (radius 5v, 100
  neighbours); per pair ``registration_ransac_based_on_feature_matching`` (distance 1.5v, mutual filter off unless
  --o3d-mutual, point-to-point, 3 points per sample, the edge-length (0.9) and distance (1.5v) checkers,
  ``RANSACConvergenceCriteria(100000, 0.999)``; the RNG seeded with --seed), point-to-plane ICP from RANSAC's pose
  and ``get_information_matrix_from_point_clouds``; a ``PoseGraph`` whose odometry edges (scan k to k + 1 in
  scans.tsv's order, which also chain the nodes' starting poses) are certain and every other pair an uncertain
  loop edge; ``global_optimization`` with ``GlobalOptimizationLevenbergMarquardt``, the default
  ``GlobalOptimizationConvergenceCriteria`` and ``GlobalOptimizationOption(max_correspondence_distance=d,
  edge_prune_threshold=0.25, reference_node=0)``. Two set-ups of the ICP step: ``open3d`` on the downsampled scans
  with d = 1.5v (the Multiway tutorial's fine distance), ``open3d_full`` on the full-resolution scans (with their
  own normals) with d = 0.4v (the Global registration tutorial's refinement); the information matrices and the
  optimisation use the same d.

Every run is its own process (``multiway_bench.py --worker METHOD``), pinned to the first T CPUs with
OMP_NUM_THREADS=T (Open3D's OpenMP pool) before it imports any library; its clock runs from the first file read to
the last pose (imports are outside it). The methods' runs alternate (kissm, Open3D, Open3D full, then again),
--repeats times per set, so a change of load touches them alike; medians are reported. Scoring: each pose anchored
on scan 0 (``T_world_gt[0] @ pose``) against the ground truth; a scan is placed right within 2 degrees and 2
voxels; a non-finite pose (kissm's unplaced scans) counts as not placed. Prints a Markdown page (tables, per-scan
errors, the machine) and writes it to --out (default bench/results/multiway_latest.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .common import BENCH, RESULTS, add_data_option, cpus_for, machine_info, now, pin, thread_env
from .data import SCAN_SETS, ScanSet, read_scan_set

PLACED_DEG = 2.0  #: issue 34's bar: a scan is placed right within 2 degrees ...
PLACED_VOXELS = 2.0  #: ... and 2 voxels of its ground-truth pose (anchored on the first scan)
#: The methods, as the page names them: kissm, and Open3D with ICP on the downsampled scans (the Multiway tutorial)
#: or on the full-resolution ones (the Global registration tutorial's refinement).
METHODS = {"kissm": "kissm", "open3d": "Open3D", "open3d_full": "Open3D, full-res ICP"}
DEFAULT_OUT = RESULTS / "multiway_latest.md"
SCRIPT = BENCH / "multiway_bench.py"


# ---- the two sides, each run in its own worker process ----------------------------------------------------------


def run_kissm(scan_set: ScanSet, folder: Path, threads: int) -> dict[str, Any]:
    """kissm's multiway alignment of one set, timed from the files to the poses."""
    import concurrent.futures

    import kissm.batch
    import kissm.multiway

    names, files, formats, _ = read_scan_set(folder)
    start = time.perf_counter()
    clouds = {n: kissm.batch.CloudFile(str(f), fmt) for n, f, fmt in zip(names, files, formats, strict=True)}
    # At 2 threads the batch's own parallelism (one job per core) is what docs/batch.md advises for many pairs.
    if threads > 1:
        with concurrent.futures.ThreadPoolExecutor(threads) as pool:
            alignment = kissm.multiway.align(clouds, scan_set.voxel, pairs="all", refine="gicp", executor=pool)
    else:
        alignment = kissm.multiway.align(clouds, scan_set.voxel, pairs="all", refine="gicp")
    seconds = time.perf_counter() - start
    return {
        "seconds": seconds,
        "poses": alignment.poses.tolist(),
        "info": {
            "pairs": alignment.registrations,
            "valid_edges": len(alignment.edges),
            "accepted_edges": sum(e.accepted for e in alignment.edges),
        },
    }


def read_for_open3d(o3d: Any, path: Path, fmt: str) -> tuple[Any, bool]:
    """A scan as an Open3D cloud, and whether Open3D's own reader could not give it.

    Open3D 0.20's PLY reader returns an empty cloud (with a warning only) for the Happy Buddha scans whose headers
    hold stray ``bye`` lines, and it has no reader for raw float32 ``.bin`` files: those are read with
    kissm.read_points, so that Open3D is measured on the same points rather than dropped."""
    if fmt == "ply":
        cloud = o3d.io.read_point_cloud(str(path))
        if len(cloud.points) > 0:
            return cloud, False
    import kissm

    points = kissm.read_points(path, format=fmt)
    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)), True


@dataclasses.dataclass(frozen=True)
class Open3DScan:
    """One scan as Open3D's pipeline holds it."""

    down: Any  #: voxel-downsampled, with normals: RANSAC's points (and ICP's in the "down" variant)
    fpfh: Any  #: FPFH features of ``down``
    icp: Any  #: the cloud ICP and the information matrix use: ``down``, or the full scan with its own normals


def open3d_scan(o3d: Any, cloud: Any, voxel: float, full: bool) -> Open3DScan:
    """The Global registration tutorial's preprocessing (downsample, normals, FPFH, radii scaled with the voxel);
    for the full-resolution variant also the full scan's normals, which point-to-plane ICP needs on it."""
    search = o3d.geometry.KDTreeSearchParamHybrid
    down = cloud.voxel_down_sample(voxel)
    down.estimate_normals(search(radius=2 * voxel, max_nn=30))
    fpfh = o3d.pipelines.registration.compute_fpfh_feature(down, search(radius=5 * voxel, max_nn=100))
    if full:
        cloud.estimate_normals(search(radius=2 * voxel, max_nn=30))
    return Open3DScan(down, fpfh, cloud if full else down)


def open3d_pair(
    o3d: Any, source: Open3DScan, target: Open3DScan, voxel: float, icp_distance: float, mutual: bool
) -> tuple[Any, Any]:
    """One pair as the tutorials chain it: FPFH + RANSAC, then point-to-plane ICP, then the edge's information."""
    reg = o3d.pipelines.registration
    distance = 1.5 * voxel  # the Global registration tutorial's RANSAC distance
    coarse = reg.registration_ransac_based_on_feature_matching(
        source.down,
        target.down,
        source.fpfh,
        target.fpfh,
        mutual,  # off unless --o3d-mutual
        distance,
        reg.TransformationEstimationPointToPoint(False),
        3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(distance)],
        reg.RANSACConvergenceCriteria(100000, 0.999),
    )
    fine = reg.registration_icp(
        source.icp, target.icp, icp_distance, coarse.transformation, reg.TransformationEstimationPointToPlane()
    )
    information = reg.get_information_matrix_from_point_clouds(
        source.icp, target.icp, icp_distance, fine.transformation
    )
    return fine.transformation, information


def open3d_graph(o3d: Any, scans: list[Open3DScan], voxel: float, icp_distance: float, mutual: bool) -> Any:
    """The Multiway tutorial's pose graph over every pair: consecutive scans as certain odometry edges (which also
    chain the nodes' starting poses), every other pair as an uncertain loop edge."""
    import numpy as np

    reg = o3d.pipelines.registration
    graph = reg.PoseGraph()
    odometry = np.eye(4)
    graph.nodes.append(reg.PoseGraphNode(odometry))
    n = len(scans)
    for s in range(n):
        for t in range(s + 1, n):
            transform, information = open3d_pair(o3d, scans[s], scans[t], voxel, icp_distance, mutual)
            loop = t != s + 1
            if not loop:
                odometry = np.asarray(transform) @ odometry
                graph.nodes.append(reg.PoseGraphNode(np.linalg.inv(odometry)))
            graph.edges.append(reg.PoseGraphEdge(s, t, transform, information, uncertain=loop))
    return graph


def run_open3d(scan_set: ScanSet, folder: Path, seed: int, mutual: bool, full: bool) -> dict[str, Any]:
    """Open3D's multiway registration of one set, timed from the files to the poses (its thread count is OpenMP's,
    set in the environment before the import). ``full``: ICP on the full-resolution scans at 0.4 voxel (the Global
    registration tutorial's refinement) instead of on the downsampled ones at 1.5 voxel (the Multiway tutorial's
    fine distance); the information matrices and the optimisation's correspondence distance follow ICP's."""
    import numpy as np
    import open3d as o3d

    reg = o3d.pipelines.registration
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    o3d.utility.random.seed(seed)  # RANSAC's samples: the same every run
    names, files, formats, _ = read_scan_set(folder)
    voxel = scan_set.voxel
    icp_distance = (0.4 if full else 1.5) * voxel
    start = time.perf_counter()
    read = [read_for_open3d(o3d, f, fmt) for f, fmt in zip(files, formats, strict=True)]
    scans = [open3d_scan(o3d, cloud, voxel, full) for cloud, _ in read]
    graph = open3d_graph(o3d, scans, voxel, icp_distance, mutual)
    edges_before = len(graph.edges)
    option = reg.GlobalOptimizationOption(
        max_correspondence_distance=icp_distance, edge_prune_threshold=0.25, reference_node=0
    )
    reg.global_optimization(
        graph, reg.GlobalOptimizationLevenbergMarquardt(), reg.GlobalOptimizationConvergenceCriteria(), option
    )
    poses = np.array([np.asarray(node.pose) for node in graph.nodes])
    seconds = time.perf_counter() - start
    return {
        "seconds": seconds,
        "poses": poses.tolist(),
        "info": {
            "pairs": edges_before,
            "edges_pruned": edges_before - len(graph.edges),
            "read_by_kissm": [n for n, (_, fallback) in zip(names, read, strict=True) if fallback],
            "downsampled_points": [len(scan.down.points) for scan in scans],
        },
    }


def worker(args: argparse.Namespace) -> int:
    """One timed run in this process: pinned before any library is imported, its reply as one JSON line on the
    original stdout (what a library prints goes to stderr)."""
    threads = args.threads[0]
    pin(cpus_for(threads))
    reply = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    scan_set = set_by_label(args.set)
    folder = args.data / scan_set.folder
    if args.worker == "kissm":
        result = run_kissm(scan_set, folder, threads)
    else:
        result = run_open3d(scan_set, folder, args.seed, args.o3d_mutual, full=args.worker == "open3d_full")
    reply.write(json.dumps(result) + "\n")
    reply.close()
    return 0


def timed_run(side: str, label: str, threads: int, args: argparse.Namespace) -> dict[str, Any]:
    """One run of ``side`` on a set, in a fresh worker process with the thread count's environment."""
    command = [sys.executable, str(SCRIPT), "--worker", side, "--set", label, "--threads", str(threads)]
    command += ["--data", str(args.data), "--seed", str(args.seed)] + (["--o3d-mutual"] if args.o3d_mutual else [])
    done = subprocess.run(command, env=thread_env(threads), stdout=subprocess.PIPE, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"multiway_bench: {side} on {label} at {threads} threads exited with {done.returncode}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


# ---- scoring ---------------------------------------------------------------------------------------------------


def angle_deg(rotation: Any) -> float:
    import numpy as np

    return math.degrees(math.acos(max(-1.0, min(1.0, (float(np.trace(rotation)) - 1.0) / 2.0))))


def score(poses: list[Any], names: list[str], truth: dict[str, Any], voxel: float) -> dict[str, Any]:
    """Per scan its rotation error (deg) and translation error (voxels) with the first scan as the anchor; counts
    of scans placed right, placed wrong and not placed (non-finite pose)."""
    import numpy as np

    anchor = truth[names[0]]
    errors: list[tuple[float, float] | None] = []
    for name, pose in zip(names, poses, strict=True):
        pose = np.array(pose, dtype=np.float64)
        if not np.all(np.isfinite(pose)):
            errors.append(None)
            continue
        error = np.linalg.inv(truth[name]) @ anchor @ pose
        errors.append((angle_deg(error[:3, :3]), float(np.linalg.norm(error[:3, 3])) / voxel))
    placed = [e for e in errors if e is not None]
    right = sum(r <= PLACED_DEG and t <= PLACED_VOXELS for r, t in placed)
    return {
        "errors": errors,
        "right": right,
        "wrong": len(placed) - right,
        "not_placed": len(errors) - len(placed),
        "worst_deg": max((r for r, _ in placed), default=math.nan),
        "worst_voxels": max((t for _, t in placed), default=math.nan),
    }


def measure_set(scan_set: ScanSet, threads: int, args: argparse.Namespace) -> dict[str, Any]:
    """Every method's runs on one set, interleaved (kissm, Open3D, ..., then again), each scored."""
    names, _, _, truth = read_scan_set(args.data / scan_set.folder)
    runs: dict[str, list[dict[str, Any]]] = {side: [] for side in args.methods}
    for repeat in range(args.repeats):
        for side in args.methods:
            result = timed_run(side, scan_set.label, threads, args)
            result["score"] = score(result["poses"], names, truth, scan_set.voxel)
            runs[side].append(result)
            s = result["score"]
            print(
                f"  {scan_set.label} {threads}T run {repeat + 1}/{args.repeats} {side}: {result['seconds']:.2f} s, "
                f"right {s['right']}, wrong {s['wrong']}, not placed {s['not_placed']}",
                file=sys.stderr,
                flush=True,
            )
    return {"set": scan_set, "names": names, "runs": runs}


# ---- the page --------------------------------------------------------------------------------------------------


def span(values: Sequence[float | int], spec: str = "d") -> str:
    """A count or value over the repeats: one number when they agree as printed, else the range."""
    low, high = format(min(values), spec), format(max(values), spec)
    return low if low == high else f"{low}–{high}"


def median_seconds(runs: list[dict[str, Any]]) -> float:
    return float(statistics.median(r["seconds"] for r in runs))


def method_row(label: str, n: int, side: str, runs: dict[str, list[dict[str, Any]]]) -> str:
    scores = [r["score"] for r in runs[side]]
    seconds = median_seconds(runs[side])
    # The target compares each Open3D set-up with kissm at the same thread count: its median over kissm's.
    ratio = f"{seconds / median_seconds(runs['kissm']):.1f}x" if side != "kissm" and "kissm" in runs else ""
    cells = [
        label,
        str(n),
        METHODS[side],
        span([s["right"] for s in scores]),
        span([s["wrong"] for s in scores]),
        span([s["not_placed"] for s in scores]),
        span([s["worst_deg"] for s in scores], ".2f"),
        span([s["worst_voxels"] for s in scores], ".2f"),
        f"{seconds:.2f}",
        ratio,
    ]
    return "| " + " | ".join(cells) + " |"


def plural(threads: int) -> str:
    return f"{threads} thread{'s' if threads > 1 else ''}"


def table(measured: list[dict[str, Any]], threads: int) -> list[str]:
    lines = [
        f"### {plural(threads)}",
        "",
        "| set | scans | method | placed right | placed wrong | not placed | worst rotation (deg) "
        "| worst translation (voxels) | seconds (median) | time / kissm's |",
        "|---|--:|---|--:|--:|--:|--:|--:|--:|--:|",
    ]
    for entry in measured:
        for side in entry["runs"]:
            lines.append(method_row(entry["set"].label, len(entry["names"]), side, entry["runs"]))
    return lines + [""]


def cell(error: tuple[float, float] | None) -> str:
    return "not placed" if error is None else f"{error[0]:.2f} / {error[1]:.2f}"


def run_notes(runs: dict[str, list[dict[str, Any]]]) -> str:
    """What each method did in its first run: kissm's edges, Open3D's pruned edges, points and read fallbacks."""
    notes = []
    if "kissm" in runs:
        info = runs["kissm"][0]["info"]
        notes.append(
            f"kissm: {info['pairs']} pairs registered, {info['valid_edges']} valid, {info['accepted_edges']} "
            "accepted by the pose graph."
        )
    for side in runs:
        if side == "kissm":
            continue
        info = runs[side][0]["info"]
        points = info["downsampled_points"]
        notes.append(
            f"{METHODS[side]}: {info['pairs']} edges, {info['edges_pruned']} pruned by the line process; "
            f"downsampled scans of {min(points)}–{max(points)} points"
            + (f"; read with kissm.read_points: {', '.join(info['read_by_kissm'])}" if info["read_by_kissm"] else "")
            + "."
        )
    return " ".join(notes)


def details(measured: list[dict[str, Any]], threads: int) -> list[str]:
    """Per scan, each method's errors in its first run, and what each method did."""
    lines = [f"### Per scan at {plural(threads)}, first run (rotation error deg / translation error voxels)", ""]
    for entry in measured:
        runs = entry["runs"]
        lines += [
            f"**{entry['set'].label}** (voxel {entry['set'].voxel:g})",
            "",
            "| scan | " + " | ".join(METHODS[side] for side in runs) + " |",
            "|---|" + "---|" * len(runs),
        ]
        for k, name in enumerate(entry["names"]):
            lines.append(f"| {name} | " + " | ".join(cell(runs[side][0]["score"]["errors"][k]) for side in runs) + " |")
        lines += ["", run_notes(runs), ""]
    return lines


def machine_lines(load_start: Sequence[float], load_end: Sequence[float]) -> list[str]:
    info = machine_info()
    packages = ", ".join(f"{k} {v}" for k, v in info.get("packages", {}).items())
    return [
        f"Machine: {info.get('cpu', '?')}, {info.get('cpus_online', '?')} CPUs online (allowed "
        f"{info.get('cpus_allowed', '?')}), {info.get('mem_total_gb', '?')} GB; {info.get('platform', '?')}, "
        f"Python {info.get('python', '?')}; {packages}; checkout {info.get('git', '?')}. Load average (1 min) "
        f"{load_start[0]:.1f} at the start, {load_end[0]:.1f} at the end (the machine is shared).",
        "",
    ]


def page(
    all_measured: dict[int, list[dict[str, Any]]],
    command: str,
    times: tuple[str, str],
    load: tuple[Any, Any],
    args: argparse.Namespace,
) -> str:
    lines = [
        "## Multiway registration: kissm against Open3D 0.20 (issue 34)",
        "",
        "<!-- Written by bench/multiway_bench.py (kissm_bench/multiway.py); rerun the command, do not edit. -->",
        "",
        f"Command: `{command}`. Started {times[0]}, finished {times[1]}. Median of {args.repeats} runs per method, "
        "interleaved, each in a fresh process pinned to the first T CPUs with OMP_NUM_THREADS=T; time from "
        f"reading the files to the poses. Placed right: within {PLACED_DEG:g} degrees and {PLACED_VOXELS:g} voxels "
        "of the ground truth, anchored on the first scan; worst errors over the placed scans; a range where the "
        f"runs differ. Every pair of each set on both sides; Open3D's RNG seed {args.seed}, RANSAC's mutual filter "
        f"{'on' if args.o3d_mutual else 'off'}.",
        "",
        *machine_lines(*load),
    ]
    for threads, measured in all_measured.items():
        lines += table(measured, threads)
    for threads, measured in all_measured.items():
        lines += details(measured, threads)
    return "\n".join(lines).rstrip() + "\n"


# ---- the command -----------------------------------------------------------------------------------------------


def set_by_label(label: str) -> ScanSet:
    for scan_set in SCAN_SETS:
        if label in (scan_set.label, scan_set.folder, scan_set.folder.split("/")[0]):
            return scan_set
    raise SystemExit(f"multiway_bench: unknown set {label!r}; one of {', '.join(s.label for s in SCAN_SETS)}")


def parse(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    parser.add_argument("--sets", nargs="+", default=[s.label for s in SCAN_SETS], help="labels or folders")
    parser.add_argument("--threads", nargs="+", type=int, choices=(1, 2), default=[1], help="each measured apart")
    parser.add_argument(
        "--methods", nargs="+", choices=list(METHODS), default=list(METHODS), help="default: all (kissm first)"
    )
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per side and set (median reported)")
    parser.add_argument("--seed", type=int, default=1, help="Open3D's RNG seed (o3d.utility.random.seed)")
    parser.add_argument(
        "--o3d-mutual", action="store_true", help="Open3D's RANSAC with its mutual filter on (default off)"
    )
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="the Markdown page (default %(default)s)")
    add_data_option(parser)
    parser.add_argument("--worker", choices=list(METHODS), help=argparse.SUPPRESS)
    parser.add_argument("--set", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    return args


def main(argv: Sequence[str] | None = None) -> int:
    args = parse(argv)
    if args.worker:
        return worker(args)
    scan_sets = [set_by_label(label) for label in args.sets]
    missing = [s.folder for s in scan_sets if not (args.data / s.folder / "scans.tsv").is_file()]
    if missing:
        print(f"multiway_bench: skipped: no {', '.join(missing)} in {args.data} (set --data)", flush=True)
        return 0
    started, load_start = now(), os.getloadavg()
    measured = {threads: [measure_set(s, threads, args) for s in scan_sets] for threads in args.threads}
    given = sys.argv[1:] if argv is None else list(argv)
    command = "bench/.venv/bin/python bench/multiway_bench.py " + " ".join(given)
    text = page(measured, command.strip(), (started, now()), (load_start, os.getloadavg()), args)
    print(text, end="")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    return 0
