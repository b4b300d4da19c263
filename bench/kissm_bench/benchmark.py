# SPDX-License-Identifier: MIT
"""kissm benchmark: kissm against the reference KISS-Matcher and Open3D, on real pairs and synthetic scenes.

Full run (normally through ``bash bench/run.sh``, which makes the venv with every peer installed)::

    python bench/bench.py --threads 1 2 --rotations 2 --repeats 3 --out docs/reports

Smoke run (seconds; needs only numpy and kissm; any peer that happens to be importable is skipped unless
it is the reference)::

    python bench/bench.py --smoke --out /tmp/kissm-bench-smoke

How it measures (also written into the report):

* Every case (a pair of ``../shared/data``, raw or with its source turned by a large rotation with a fixed
  seed, ground truth composed accordingly) is loaded once, as float64 (N, 3) arrays, and saved to a
  temporary ``.npy``. Each method then runs in its **own fresh worker process** per (thread count, case):
  the worker pins itself to the first T CPUs (``sched_setaffinity``, like ``taskset``) before any library
  is imported, with ``OMP_NUM_THREADS=T``; kissm also gets ``num_threads=T``.
* The worker loads the arrays, returns freed heap to the OS (``malloc_trim``), resets its peak-RSS counter
  (``/proc/self/clear_refs``) and records the resident size as the baseline. Peak memory of a method is
  ``VmHWM - baseline`` after the warm-up and all timed runs: what the call adds on top of the input
  arrays and the imported libraries, including one-time initialisation in the first call.
* One warm-up call per method, then the timed calls interleaved method by method (A B C D, A B C D, ...).
  Every timed call starts from the raw numpy arrays: matcher construction, conversion, voxelisation,
  features, matching and solving are all inside the wall time. The median over the repeats is reported.
* Stage times: kissm's ``Result.time_*_ms``; the reference's own C++ getters (its matching time includes
  its pruning, which is shown separately); Open3D's stages timed around each call.

The code is kissm_bench's: this module (the cases, the runs, the options), kissm_bench.workers (the worker
processes), kissm_bench.methods (each method's call) and kissm_bench.reports.benchmarks (the page).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import math
import os
import shutil
import sys
import tempfile
import time
import zlib
from pathlib import Path
from typing import IO, Any

from . import common
from . import results as results_io
from .common import (
    BENCH,
    REPORTS,
    RESULTS,
    cpus_for,
    default_data,
    is_committed,
    med,
)
from .data import THRESHOLDS, Pair, has_index, load_pairs
from .geometry import pose_errors, rotation_about
from .methods import (
    COARSE_METHODS,
    FROM_KISSM_START,
    KISSM_REFINE_MODE,
    METHOD_MODULES,
    METHODS,
    REFINE_METHODS,
    UPSTREAM_CHAIN,
)
from .reports import benchmarks as page
from .reports.common import METHOD_LABEL
from .reports.common import STAGE_ORDER as STAGES
from .scenes import SYN_DENSITY, make_synthetic
from .workers import Worker, WorkerError, WorkerTimeout, worker_main

SCRIPT = BENCH / "bench.py"  # what the worker processes run
COMMITTED = RESULTS / "latest.json.gz"  # what docs/reports/benchmarks.md is rendered from


def pair_label(p: Pair) -> str:
    """A pair as the page names it (and --pairs matches it): dataset/pair."""
    return f"{p.dataset}/{p.pair}"


def make_cases(pairs: list[Pair], rotations: int, tmp: Path) -> list[dict[str, Any]]:
    """Loads each pair once and writes its raw and rotated variants as .npy files."""
    import numpy as np

    cases: list[dict[str, Any]] = []
    for p in pairs:
        src, tgt = p.read()
        gt = p.gt
        name = pair_label(p)
        row = {
            "dataset": p.dataset,
            "pair": p.pair,
            "pair_dir": p.name,
            "kind": p.kind_name,
            "category": p.kind.category,
            "voxel": p.kind.voxel,
        }
        tgt_path = tmp / f"case{len(cases):03d}_tgt.npy"
        np.save(tgt_path, tgt)
        for r in range(rotations + 1):
            case = dict(row, name=name, index=len(cases), n_src=len(src), n_tgt=len(tgt), tgt_path=str(tgt_path))
            if r == 0:
                rot = np.eye(3)
                case.update(variant="raw", rot_deg=0.0)
            else:
                rng = np.random.default_rng(zlib.crc32(f"{name}#{r}".encode()))
                axis = rng.normal(size=3)
                angle = rng.uniform(0.3 * math.pi, math.pi)  # 54°..180° about a random axis
                rot = rotation_about(axis, angle)
                case.update(variant=f"rot{r}", rot_deg=math.degrees(angle))
            src_r = np.ascontiguousarray(src @ rot.T)
            truth = gt.copy()
            truth[:3, :3] = gt[:3, :3] @ rot.T  # p_t = R_gt p_s + t = (R_gt R^T)(R p_s) + t
            src_path = tmp / f"case{len(cases):03d}_src.npy"
            np.save(src_path, src_r)
            seed = zlib.crc32(f"{name}#{r}#ransac".encode()) & 0x7FFFFFFF  # Open3D takes an int32 seed
            case.update(src_path=str(src_path), gt=truth.tolist(), seed=seed)
            cases.append(case)
    return cases


# ---- running ---------------------------------------------------------------------------------------------


def within(rre: float | None, rte: float | None, category: str) -> bool:
    max_rre, max_rte = THRESHOLDS[category]
    return rre is not None and rte is not None and rre < max_rre and rte < max_rte


def judge(record: dict[str, Any], gt: Any, category: str) -> None:
    import numpy as np

    rre, rte = pose_errors(record["transform"], np.asarray(gt))
    record["rre_deg"], record["rte_m"] = rre, rte
    record["success"] = bool(record["valid"] and within(rre, rte, category))
    if "coarse_transform" in record:  # a refining method: the errors of the pose it started from
        c_rre, c_rte = pose_errors(record["coarse_transform"], np.asarray(gt))
        record["coarse_rre_deg"], record["coarse_rte_m"] = c_rre, c_rte
        record["start_within"] = within(c_rre, c_rte, category)
        record["within"] = within(rre, rte, category)


def refine_settings() -> dict[str, Any]:
    """What the refinement peers share with kissm's refinement: its correspondence distance (as a gain on the
    voxel size) and its iteration cap, both kissm's defaults, read from the library."""
    import kissm

    config = kissm.Config()
    return {"max_distance_gain": config.refine_max_distance_gain, "max_iterations": config.refine_max_iterations}


def add_coarse_starts(cases: list[dict[str, Any]], threads: int) -> None:
    """kissm's coarse pose for each case (one untimed call in this process; kissm's result does not depend on
    the thread count): the start of the refinement peers, the same start kissm's own refinement has."""
    import kissm
    import numpy as np

    for case in cases:
        src, tgt = np.load(case["src_path"]), np.load(case["tgt_path"])
        with kissm.Matcher(voxel_size=case["voxel"], num_threads=threads) as matcher:
            r = matcher.register(src, tgt)
        rre, rte = pose_errors(r.transform, np.asarray(case["gt"]))
        case["coarse"] = {
            "transform": r.transform.tolist(),
            "valid": bool(r.valid),
            "rre_deg": rre,
            "rte_m": rte,
            "within": within(rre, rte, case["category"]),
        }


def slim(record: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in record.items() if k not in ("ok",)}


def run_real(
    args: argparse.Namespace,
    cases: list[dict[str, Any]],
    methods: list[str],
    threads_list: list[int],
    log: IO[str],
    results: dict[str, Any],
) -> None:
    total = len(threads_list) * len(cases)
    done = 0
    refine: dict[str, Any] = {}
    if any(m in REFINE_METHODS for m in methods):
        refine = refine_settings()
        results["meta"]["refine_settings"] = dict(refine, upstream_chain=UPSTREAM_CHAIN)
    if any(m in FROM_KISSM_START for m in methods):
        t0 = time.monotonic()
        add_coarse_starts(cases, max(threads_list))
        print(f"bench: kissm's coarse poses for {len(cases)} cases in {time.monotonic() - t0:.0f} s", flush=True)
        by_index = {c["index"]: c for c in cases}
        for c in results["cases"]:
            c["coarse"] = by_index[c["index"]]["coarse"]
    for threads in threads_list:
        cpus = cpus_for(threads)
        for case in cases:
            done += 1
            t_case = time.monotonic()
            workers: dict[str, Worker] = {}
            failed: dict[str, str] = {}
            for m in methods:
                try:
                    w = Worker(SCRIPT, m, threads, cpus, log, args.python)
                    results["versions"].setdefault(m, w.hello.get("version"))
                    msg: dict[str, Any] = {
                        "cmd": "load",
                        "src": case["src_path"],
                        "tgt": case["tgt_path"],
                        "voxel": case["voxel"],
                        "seed": case["seed"],
                    }
                    if m in REFINE_METHODS:
                        msg["init"] = case.get("coarse")
                        msg["refine"] = {
                            "max_distance": refine["max_distance_gain"] * case["voxel"],
                            "max_iterations": refine["max_iterations"],
                        }
                    load = w.call(msg, timeout=300)
                    w.baseline_kb = load["baseline_kb"]
                    workers[m] = w
                except (WorkerError, WorkerTimeout) as exc:
                    failed[m] = str(exc)
            base = {"threads": threads, "case": case["index"]}
            for rep in range(args.repeats + 1):  # rep 0 is the warm-up
                for m in methods:
                    if m in failed:
                        continue
                    try:
                        rec = workers[m].call({"cmd": "run"}, timeout=args.timeout)
                        judge(rec, case["gt"], case["category"])
                        if m in KISSM_REFINE_MODE and "coarse" in case:  # the peers' start, bit for bit?
                            rec["same_start"] = rec["coarse_transform"] == case["coarse"]["transform"]
                        rec["status"] = "ok"
                    except WorkerTimeout as exc:
                        failed[m] = "timeout"
                        rec = {"status": "timeout", "error": str(exc)}
                    except WorkerError as exc:
                        failed[m] = str(exc)
                        rec = {"status": "error", "error": str(exc)}
                    rec.update(base, method=m, rep=rep, warmup=rep == 0)
                    results["runs"].append(slim(rec))
            for m in methods:
                mem: dict[str, Any] = {"threads": threads, "case": case["index"], "method": m}
                if m in workers and m not in failed:
                    st = workers[m].call({"cmd": "mem"}, timeout=30)
                    mem.update(
                        baseline_kb=workers[m].baseline_kb,
                        hwm_kb=st["VmHWM"],
                        peak_kb=max(0, st["VmHWM"] - workers[m].baseline_kb),
                    )
                else:
                    mem.update(error=failed.get(m, "not run"))
                    if m in failed and (failed[m] != "timeout" or args.smoke):
                        results["errors"].append(
                            f"{METHOD_LABEL[m]} on {case['name']} {case['variant']} ({threads}t): {failed[m]}"
                        )
                results["memory"].append(mem)
                if m in workers:
                    workers[m].close()
            line = []
            for m in methods:
                runs = [
                    r
                    for r in results["runs"]
                    if r["threads"] == threads
                    and r["case"] == case["index"]
                    and r["method"] == m
                    and not r["warmup"]
                    and r["status"] == "ok"
                ]
                if runs:
                    ok = sum(r["success"] for r in runs)
                    line.append(f"{m} {med([r['wall_ms'] for r in runs]):.0f}ms {ok}/{len(runs)}")
                else:
                    line.append(f"{m} {failed.get(m, '-')[:40]}")
            print(
                f"[{done}/{total}] {threads}t {case['name']} {case['variant']}: "
                + ", ".join(line)
                + f"  ({time.monotonic() - t_case:.0f} s, load {os.getloadavg()[0]:.1f})",
                flush=True,
            )


def _mem_available_kb() -> int | None:
    with contextlib.suppress(OSError, ValueError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1])
    return None


def projected_too_big(
    runs: list[dict[str, Any]], sizes: list[dict[str, Any]], method: str, target: int, timeout: float
) -> str | None:
    """Why the next size should not be tried (projected memory or time from the smaller sizes), or None."""
    done = [r for r in runs if r["method"] == method and r["status"] == "ok"]
    if not done:
        return None
    last = done[-1]
    x_last = sizes[last["size"]]["voxels_numpy"]
    ratio = target / x_last
    exponent = 1.0
    if len(done) >= 2:
        prev = done[-2]
        x_prev = sizes[prev["size"]]["voxels_numpy"]
        if x_last > x_prev and prev["wall_ms"] > 0:
            exponent = max(1.0, math.log(last["wall_ms"] / prev["wall_ms"]) / math.log(x_last / x_prev))
    time_s = last["wall_ms"] / 1e3 * ratio**exponent
    if time_s > 2 * timeout:
        return f"projected {time_s:.0f} s per call from the smaller sizes, over twice the {timeout:.0f} s timeout"
    avail = _mem_available_kb()
    mem_kb = (last["peak_kb"] + last["baseline_kb"]) * ratio * 1.25
    if avail and mem_kb > 0.7 * avail:
        return (
            f"projected {mem_kb / 2**20:.1f} GB from the smaller sizes, over 70% of the "
            f"{avail / 2**20:.1f} GB available"
        )
    return None


def run_scaling(
    args: argparse.Namespace, methods: list[str], threads: int, tmp: Path, log: IO[str], results: dict[str, Any]
) -> None:
    import numpy as np

    cpus = cpus_for(threads)
    voxel = args.scaling_voxel
    warm = make_synthetic(1000, voxel, 99, tmp, "warm")
    scaling: dict[str, Any] = {
        "voxel": voxel,
        "threads": threads,
        "density": SYN_DENSITY,
        "timeout_s": args.scaling_timeout,
        "sizes": [],
        "runs": [],
    }
    results["scaling"] = scaling
    stopped: dict[str, str] = {}
    for i, target in enumerate(args.scaling_sizes):
        t_gen = time.monotonic()
        scene = make_synthetic(target, voxel, 1234, tmp, f"{i}")
        scene["gen_s"] = time.monotonic() - t_gen
        scene["index"] = i
        scaling["sizes"].append({k: v for k, v in scene.items() if not k.endswith("_path")})
        gt = np.asarray(scene["gt"])
        for m in methods:
            rec: dict[str, Any] = {"size": i, "method": m}
            if m in stopped:
                rec.update(status="skipped", error=stopped[m])
                scaling["runs"].append(rec)
                continue
            why = projected_too_big(scaling["runs"], scaling["sizes"], m, target, args.scaling_timeout)
            if why:
                rec.update(status="skipped", error=why)
                stopped[m] = why
                scaling["runs"].append(rec)
                print(f"[scaling {threads}t] {target:>9} voxels {m}: skipped ({why})", flush=True)
                continue
            w: Worker | None = None
            try:
                w = Worker(SCRIPT, m, threads, cpus, log, args.python)
                results["versions"].setdefault(m, w.hello.get("version"))
                w.call(
                    {"cmd": "load", "src": warm["src_path"], "tgt": warm["tgt_path"], "voxel": voxel, "seed": 7},
                    timeout=120,
                )
                w.call({"cmd": "run"}, timeout=args.scaling_timeout)  # warm-up on a small scene
                load = w.call(
                    {"cmd": "load", "src": scene["src_path"], "tgt": scene["tgt_path"], "voxel": voxel, "seed": 7},
                    timeout=600,
                )
                # The first call at a size is untimed: it is the first to touch that much memory in this
                # process, and on a VM whose balloon driver hands freed pages back to the host (this machine)
                # a first touch costs about 2.5 s per GB, which only the largest sizes, measured once, would
                # pay. Its time is kept as first_wall_ms.
                calls: list[dict[str, Any]] = []
                t_start = time.monotonic()
                while True:
                    r = w.call({"cmd": "run"}, timeout=args.scaling_timeout)
                    judge(r, gt, "synthetic")
                    calls.append(r)
                    runs = calls[1:]
                    if runs and (len(runs) >= args.scaling_repeats or time.monotonic() - t_start > 20.0):
                        break
                st = w.call({"cmd": "mem"}, timeout=30)
                rec.update(
                    status="ok",
                    n=len(runs),
                    walls_ms=[r["wall_ms"] for r in runs],
                    first_wall_ms=calls[0]["wall_ms"],
                    cpu={k: med([r["cpu"][k] for r in runs]) for k in ("user_ms", "sys_ms", "minflt")},
                    wall_ms=med([r["wall_ms"] for r in runs]),
                    engine_ms=med([r["engine_ms"] for r in runs]),
                    stages={
                        s: med([r["stages"].get(s) for r in runs])
                        for s in STAGES
                        if any(s in r["stages"] for r in runs)
                    },
                    success=runs[0]["success"],
                    valid=runs[0]["valid"],
                    rre_deg=runs[0]["rre_deg"],
                    rte_m=runs[0]["rte_m"],
                    info=runs[0].get("info", {}),
                    baseline_kb=load["baseline_kb"],
                    hwm_kb=st["VmHWM"],
                    peak_kb=max(0, st["VmHWM"] - load["baseline_kb"]),
                )
            except WorkerTimeout as exc:
                rec.update(status="timeout", error=str(exc))
                stopped[m] = f"timed out at {target} voxels"
            except WorkerError as exc:
                rec.update(status="error", error=str(exc))
                stopped[m] = f"failed at {target} voxels"
                results["errors"].append(f"scaling {METHOD_LABEL[m]} at {target} voxels: {exc}")
            finally:
                if w is not None:
                    w.close()
            scaling["runs"].append(rec)
            extra = (
                (f"{rec['wall_ms']:.0f} ms, +{rec['peak_kb'] / 1024:.0f} MB, {'ok' if rec['success'] else 'FAIL'}")
                if rec["status"] == "ok"
                else rec["status"]
            )
            print(
                f"[scaling {threads}t] {target:>9} voxels ({scene['n_src']} points) {m}: {extra}  "
                f"(load {os.getloadavg()[0]:.1f})",
                flush=True,
            )
        for path in (scene["src_path"], scene["tgt_path"]):
            with contextlib.suppress(OSError):
                os.unlink(path)


def available_methods(methods: list[str]) -> tuple[list[str], dict[str, str]]:
    ok, missing = [], {}
    for m in methods:
        absent = [mod for mod in METHOD_MODULES[m] if importlib.util.find_spec(mod) is None]
        if absent:
            missing[m] = "Python module " + " and ".join(repr(mod) for mod in absent) + " not installed"
        else:
            ok.append(m)
    return ok, missing


def parse_args(argv: list[str]) -> argparse.Namespace:
    p = common.script_parser(__doc__)
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="thread counts (default: 1 2)")
    p.add_argument("--rotations", type=int, default=2, help="rotated variants per pair besides the raw one (2)")
    p.add_argument("--repeats", type=int, default=3, help="timed calls per method and case after the warm-up (3)")
    p.add_argument(
        "--methods",
        nargs="+",
        choices=METHODS,
        default=list(METHODS),
        help="coarse: " + " ".join(COARSE_METHODS) + "; refinement: " + " ".join(REFINE_METHODS),
    )
    p.add_argument(
        "--refine-only",
        action="store_true",
        help="only the refinement comparison: kissm coarse and "
        "refined, small_gicp, Open3D GICP / point-to-plane, reference + small_gicp; no scaling",
    )
    p.add_argument("--pairs", nargs="*", default=None, help="only pairs whose dataset/pair contains one of these")
    p.add_argument("--data", type=Path, default=default_data())
    p.add_argument("--out", type=Path, default=REPORTS, help="writes OUT/benchmarks.md and OUT/img/*.png")
    p.add_argument(
        "--raw",
        type=Path,
        default=None,
        help="also write the full raw results JSON here (default: OUT/raw.json, except with the default --out, "
        "whose page's reduced results go to bench/results/latest.json.gz)",
    )
    p.add_argument("--timeout", type=float, default=600.0, help="seconds per call on real pairs (600)")
    p.add_argument("--no-real", action="store_true", help="skip the real pairs")
    p.add_argument("--no-scaling", action="store_true", help="skip the synthetic scaling runs")
    p.add_argument(
        "--scaling-sizes",
        type=int,
        nargs="+",
        default=[10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000],
        help="target voxels per cloud",
    )
    p.add_argument(
        "--scaling-methods",
        nargs="+",
        choices=COARSE_METHODS,
        default=None,
        help="default: the coarse ones of --methods",
    )
    p.add_argument("--scaling-threads", type=int, default=None, help="default: the largest of --threads")
    p.add_argument("--scaling-voxel", type=float, default=0.5)
    p.add_argument(
        "--scaling-repeats",
        type=int,
        default=3,
        help="timed calls per size after one untimed call (fewer past 20 s) (3)",
    )
    p.add_argument(
        "--scaling-timeout",
        type=float,
        default=300.0,
        help="seconds per call; larger sizes are skipped for a method after a timeout (300)",
    )
    p.add_argument("--quick", action="store_true", help="1 rotation, 1 repeat, scaling up to 100K voxels")
    p.add_argument(
        "--smoke",
        action="store_true",
        help="seconds-long check of the harness: kissm (+ the reference "
        "if installed), one small real pair (or a synthetic one), tiny scaling, results in --out",
    )
    p.add_argument("--python", default=sys.executable, help=argparse.SUPPRESS)
    p.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    p.add_argument("--cpus", default="", help=argparse.SUPPRESS)
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.worker:
        return worker_main(args.worker, args.threads[0], [int(c) for c in args.cpus.split(",") if c])

    explicit = common.explicit_options(argv)
    if args.quick:
        if "--rotations" not in explicit:
            args.rotations = 1
        if "--repeats" not in explicit:
            args.repeats = 1
        if "--scaling-sizes" not in explicit:
            args.scaling_sizes = [10_000, 30_000, 100_000]
    if args.refine_only:
        if "--methods" not in explicit:  # the coarse ones for the coarse errors, times and success to compare
            args.methods = ["kissm", "reference", *REFINE_METHODS]
        args.no_scaling = True
    if args.smoke:
        if "--out" not in explicit:
            args.out = Path(tempfile.mkdtemp(prefix="kissm-bench-smoke-"))
        if "--methods" not in explicit:  # the fast methods; the peers among them only when installed
            args.methods = ["kissm", "reference", *REFINE_METHODS]
        if "--threads" not in explicit:
            args.threads = [1]
        if "--rotations" not in explicit:
            args.rotations = 1
        if "--repeats" not in explicit:
            args.repeats = 1
        if "--scaling-sizes" not in explicit:
            args.scaling_sizes = [10_000, 30_000]
        if "--scaling-methods" not in explicit:
            args.scaling_methods = ["kissm"]
        if "--pairs" not in explicit:
            args.pairs = ["kitti07_keyframes_gtsam_points/000002__000003"]
    # The committed page's results (reduced) only with the committed page; the raw ones elsewhere or when asked.
    committed = COMMITTED if is_committed(args.out, args.smoke) else None
    if args.raw is None and committed is None:
        args.raw = args.out / "raw.json"

    methods, missing = available_methods(args.methods)
    if importlib.util.find_spec("kissm") is None:  # it reads the data and gives the refinement peers their start
        print("bench: the kissm Python package is not importable (pip install ./bindings/python)", file=sys.stderr)
        return 2
    if missing and not args.smoke:
        for m, why in missing.items():
            print(f"bench: {METHOD_LABEL[m]}: {why} (use bench/run.sh, or pass --methods)", file=sys.stderr)
        return 2
    if missing:
        print("bench: smoke run without " + ", ".join(METHOD_LABEL[m] for m in missing) + " (not installed)")
    scaling_methods = [m for m in (args.scaling_methods or methods) if m in methods and m in COARSE_METHODS]
    scaling_threads = args.scaling_threads or max(args.threads)
    for t in set(args.threads) | {scaling_threads}:
        cpus_for(t)

    results: dict[str, Any] = {
        "meta": common.run_meta(
            "bench.py", argv, args, ("worker", "cpus", "python"), methods=methods, missing_methods=missing
        ),
        "versions": {},
        "cases": [],
        "runs": [],
        "memory": [],
        "scaling": None,
        "errors": [],
        "load_samples": [],
    }
    t0 = time.monotonic()
    args.out.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="kissm-bench-"))
    log_path = args.out / "bench_workers.log" if args.smoke else tmp / "workers.log"
    print(
        f"bench: methods {', '.join(methods)}; threads {args.threads}; data {args.data}; "
        f"load {os.getloadavg()[0]:.1f}; worker log {log_path}",
        flush=True,
    )
    try:
        with open(log_path, "w") as log:
            if not args.no_real:
                if has_index(args.data):
                    pairs = load_pairs(args.data)
                    if args.pairs is not None:
                        pairs = [p for p in pairs if any(s in pair_label(p) for s in args.pairs)]
                    cases = make_cases(pairs, args.rotations, tmp)
                    results["cases"] = [{k: v for k, v in c.items() if not k.endswith("_path")} for c in cases]
                    run_real(args, cases, methods, args.threads, log, results)
                elif args.smoke:
                    print(f"bench: no data at {args.data}; the smoke run uses a synthetic pair instead")
                    scene = make_synthetic(5000, 0.5, 4321, tmp, "smoke")
                    case: dict[str, Any] = {
                        "dataset": "synthetic",
                        "pair": "smoke",
                        "name": "synthetic/smoke",
                        "kind": "synthetic",
                        "category": "synthetic",
                        "voxel": 0.5,
                        "variant": "raw",
                        "rot_deg": 0.0,
                        "index": 0,
                        "n_src": scene["n_src"],
                        "n_tgt": scene["n_tgt"],
                        "src_path": scene["src_path"],
                        "tgt_path": scene["tgt_path"],
                        "gt": scene["gt"],
                        "seed": 1,
                    }
                    results["cases"] = [{k: v for k, v in case.items() if not k.endswith("_path")}]
                    run_real(args, [case], methods, args.threads, log, results)
                else:
                    print(f"bench: no data at {args.data} (set --data or KISSM_DATA_DIR)", file=sys.stderr)
                    return 2
            results["load_samples"].append(os.getloadavg())
            if not args.no_scaling:
                run_scaling(args, scaling_methods, scaling_threads, tmp, log, results)
    finally:
        common.finish_meta(results["meta"], t0)
        results_io.save(results, page.reduce(results), committed, args.raw)
        shutil.rmtree(tmp, ignore_errors=True)

    written = page.write_all(results, args.out, smoke=args.smoke)
    saved = " and ".join(str(p) for p in (committed, args.raw) if p is not None)
    print(
        f"bench: wrote {', '.join(str(p) for p in written)} and {saved} in {results['meta']['duration_s']:.0f} s",
        flush=True,
    )
    if results["errors"]:
        print("bench: errors:\n  " + "\n  ".join(results["errors"]), file=sys.stderr)
        return 1
    return 0
