#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Where a batch's CPU goes (issue 17): the same all-pairs batch of the KITTI 07 keyframes registered by
``kissm.batch.register_many`` with a ``ThreadPoolExecutor(2)`` and with a Dask ``LocalCluster`` of 2 worker
processes of 1 thread, each kept running between its runs (the steady state, unlike bench/batch_bench.py, which
starts every engine afresh per timed run), and per run:

* the wall time;
* the CPU time of every process involved (``psutil``'s ``cpu_times``: user + system): the calling process (for
  Dask it also holds the client, the scheduler and the nannies) and each worker process;
* the page faults of all of them (``minflt``: Dask's nannies start workers with ``MALLOC_TRIM_THRESHOLD_=65536``,
  so every large array of a call is fresh pages);
* how much of the CPUs the run left unused (CPUs x wall - CPU time).

Dask runs twice: as it comes, and with its nannies' ``MALLOC_TRIM_THRESHOLD_`` unset; then Ray
(``ray.init(num_cpus=2)``) when installed, with the CPU of all the processes it starts.

    python bench/batch_accounting.py [--runs 5] [--pair-repeats 1] [--refine gicp|none] [--data DIR] [--out DIR]
    python bench/batch_accounting.py --smoke      # three keyframes, one run each: keeps the script working

Prints a Markdown table (the one in docs/batch.md, "Where Dask's time goes on this machine"). The process is
pinned to the first two CPUs. Needs numpy, kissm (with kissm.batch), psutil and Dask (``distributed``); exits 0
without running when the data or Dask is absent, 1 when a method's poses differ from the thread pool's.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import os
import statistics
import sys
import time
from pathlib import Path
from collections.abc import Callable
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from batch_bench import DATASET, KEYFRAMES, SMOKE_KEYFRAMES, WORKERS, all_pairs, load_clouds  # noqa: E402
from bench import cpus_for  # noqa: E402


_TRIM = "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"


def _cpu_and_faults(pids: list[int]) -> tuple[list[float], int]:
    """Per process, user + system CPU seconds so far; and the minor page faults of all of them."""
    import psutil

    cpu, faults = [], 0
    for pid in pids:
        try:
            t = psutil.Process(pid).cpu_times()
            with open(f"/proc/{pid}/stat", encoding="ascii") as f:
                faults += int(f.read().rsplit(")", 1)[1].split()[7])  # field 10, minflt
        except (psutil.NoSuchProcess, FileNotFoundError):  # a process of the engine that ended: counted as idle
            cpu.append(0.0)
            continue
        cpu.append(t.user + t.system)
    return cpu, faults


def account(name: str, executor: Any, workers: Callable[[], list[int]], pairs: list[tuple[int, int]], clouds: Any,
            settings: dict[str, Any], runs: int) -> tuple[dict[str, Any], list[Any]]:
    """``runs`` timed runs after a warm-up; the medians of wall, CPU per process and page faults. ``workers``
    names the engine's processes once the warm-up has started them."""
    import kissm.batch

    def run() -> list[Any]:
        done = kissm.batch.register_many(pairs, clouds, executor, progress=False, **settings)
        return [None if p.result is None else p.result.transform for p in done]

    poses = run()  # warm-up: the workers' imports and first calls
    pids = [os.getpid(), *workers()]
    walls, cpus, faults = [], [], []
    for _ in range(runs):
        cpu0, faults0 = _cpu_and_faults(pids)
        t0 = time.perf_counter()
        run()
        walls.append(time.perf_counter() - t0)
        cpu1, faults1 = _cpu_and_faults(pids)
        cpus.append([b - a for a, b in zip(cpu0, cpu1, strict=True)])
        faults.append(faults1 - faults0)
    per_process = [statistics.median(c[i] for c in cpus) for i in range(len(pids))]
    wall = statistics.median(walls)
    total = statistics.median(sum(c) for c in cpus)
    return {
        "method": name,
        "wall_s": wall,
        "cpu_caller_s": per_process[0],
        "cpu_workers_s": per_process[1:],
        "cpu_total_s": total,
        "page_faults": statistics.median(faults),
        "unused_cpu_fraction": max(0.0, 1.0 - total / (WORKERS * wall)),
    }, poses


def main(argv: list[str] | None = None) -> int:
    default_data = Path(os.environ.get("KISSM_DATA_DIR", HERE.parent.parent / "shared" / "data"))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--data", type=Path, default=default_data, help="the shared data folder")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--pair-repeats", type=int, default=1, help="list every pair K times in one batch")
    parser.add_argument("--refine", choices=["gicp", "none"], default="gicp")
    parser.add_argument("--voxel", type=float, default=0.5)
    parser.add_argument("--smoke", action="store_true", help="three keyframes, one run each")
    parser.add_argument("--out", type=Path, default=None, help="also write the table to OUT/batch-accounting.md")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.pair_repeats < 1:
        parser.error("--runs and --pair-repeats must be at least 1")
    if not (args.data / DATASET).is_dir():
        print(f"batch_accounting: {args.data / DATASET} is absent: nothing measured", file=sys.stderr)
        return 0
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        print("batch_accounting: Dask is not installed (pip install 'dask[distributed]'): nothing measured")
        return 0
    os.sched_setaffinity(0, cpus_for(WORKERS))
    count = SMOKE_KEYFRAMES if args.smoke else KEYFRAMES
    runs = 1 if args.smoke else args.runs
    clouds = load_clouds(args.data, count)
    pairs = all_pairs(list(range(count))) * args.pair_repeats
    settings = {"voxel_size": args.voxel, "refine": args.refine}
    rows = []
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        row, reference = account(f"`ThreadPoolExecutor({WORKERS})`", pool, list, pairs, clouds, settings, runs)
        rows.append(row)
    same = True
    # Dask as it comes, then with its nannies' MALLOC_TRIM_THRESHOLD_ unset (a cluster's own setting, in its
    # Dask configuration; docs/batch.md). A nanny also sets the variable in the process that runs it, whose
    # next workers would inherit it: it goes from there too while the second cluster starts.
    inherited = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    for label, trim in (("", {}), (", `MALLOC_TRIM_THRESHOLD_` unset", {_TRIM: None})):
        if trim:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        with (
            dask.config.set(trim),
            LocalCluster(
                n_workers=WORKERS, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
            ) as cluster,
            Client(cluster) as client,
        ):
            trims = set(client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_")).values())
            if trim and trims != {None}:
                raise SystemExit(f"batch_accounting: the workers still have MALLOC_TRIM_THRESHOLD_={trims}")
            name = f"Dask `LocalCluster({WORKERS} x 1)`{label}"
            row, poses = account(name, client, lambda: sorted(_worker_pids(client)), pairs, clouds, settings, runs)
            rows.append(row)
        if inherited is None:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        else:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = inherited
        same = same and _same(poses, reference)
    try:
        import ray
    except ImportError:
        ray = None
    if ray is not None:
        # Every process Ray starts (GCS, raylet, workers...) descends from this one.
        ray.init(num_cpus=WORKERS, include_dashboard=False, log_to_driver=False)
        try:
            name = f"Ray (`num_cpus={WORKERS}`), all its processes"
            row, poses = account(name, "ray", _descendants, pairs, clouds, settings, runs)
            rows.append(row)
        finally:
            ray.shutdown()
        same = same and _same(poses, reference)
    lines = [
        f"{len(pairs)} pairs of {count} keyframes, refine {args.refine}, {runs} timed run(s) (medians), CPUs pinned:",
        "",
        "| | wall per run | CPU, calling process | CPU, engine's processes | CPU, total | CPUs unused | page faults |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        w = r["cpu_workers_s"]
        if not w:
            workers_cpu = "(threads)"
        elif len(w) <= WORKERS:
            workers_cpu = " + ".join(f"{c:.2f}" for c in w) + " s"
        else:
            workers_cpu = f"{sum(w):.2f} s in {len(w)}"
        lines.append(
            f"| {r['method']} | {r['wall_s']:.2f} s | {r['cpu_caller_s']:.2f} s | {workers_cpu} | "
            f"{r['cpu_total_s']:.2f} s | {100 * r['unused_cpu_fraction']:.0f}% | {r['page_faults'] / 1000:.1f}K |"
        )
    print("\n".join(lines))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "batch-accounting.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    if not same:
        print("batch_accounting: an engine's poses differ from the thread pool's", file=sys.stderr)
        return 1
    return 0


def _same(poses: list[Any], reference: list[Any]) -> bool:
    return all(
        (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))
        for a, b in zip(poses, reference, strict=True)
    )


def _descendants() -> list[int]:
    import psutil

    return sorted(p.pid for p in psutil.Process().children(recursive=True))


def _worker_pids(client: Any) -> set[int]:
    """The process ids of the cluster's workers (asked of the workers themselves)."""
    return set(client.run(os.getpid).values())


if __name__ == "__main__":
    sys.exit(main())
