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
* how much of the CPUs the run left unused (CPUs x wall - CPU time);

and, after the runs, the CPU time all those processes take per second while nothing runs (``--idle`` seconds).

Dask runs three times: as it comes, with its nannies' ``MALLOC_TRIM_THRESHOLD_`` unset, and with all the settings
docs/batch.md suggests for kissm clusters (kissm_bench.batch.DASK_FOR_KISSM); then Ray (``ray.init(num_cpus=2)``) when
installed, with the CPU of all the processes it starts. With ``--blocks B`` every method is started afresh B times,
the methods taking turns, and the medians are over all B x --runs runs (the machine's speed drifts by 10% within
minutes; blocks spread that over all rows).

    python bench/batch_accounting.py [--runs 5] [--blocks 1] [--idle 3] [--pair-repeats 1] [--refine gicp|none]
                                     [--data DIR] [--out DIR]
    python bench/batch_accounting.py --smoke      # three keyframes, one run each: keeps the script working

Prints a Markdown table (the one in docs/batch.md, "Where Dask's time goes on this machine"). The process is
pinned to the first two CPUs. Needs numpy, kissm (with kissm.batch), psutil and Dask (``distributed``); exits 0
without running when the data or Dask is absent, 1 when a method's poses differ from the thread pool's.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import os
import statistics
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from .batch import (
    DASK_FOR_KISSM,
    DASK_UNTRIMMED,
    DATASET,
    KEYFRAMES,
    SMOKE_KEYFRAMES,
    all_pairs,
    dask_client,
    load_clouds,
    same_poses,
)
from .common import cpus_for, default_data, pin
from .reports.batch import WORKERS


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


def account(
    executor: Any,
    workers: Callable[[], list[int]],
    pairs: list[tuple[int, int]],
    clouds: Any,
    settings: dict[str, Any],
    runs: int,
    idle_s: float,
) -> tuple[list[dict[str, Any]], list[Any], float]:
    """``runs`` timed runs after a warm-up, each its wall time, CPU per process (this one first) and page faults;
    the warm-up's poses; and the CPU seconds per second all the processes took while nothing ran, over ``idle_s``
    seconds after the runs. ``workers`` names the engine's processes once the warm-up has started them."""
    import kissm.batch

    def run() -> list[Any]:
        done = kissm.batch.register_many(pairs, clouds, executor, progress=False, **settings)
        return [None if p.result is None else p.result.transform for p in done]

    poses = run()  # warm-up: the workers' imports and first calls
    pids = [os.getpid(), *workers()]
    samples = []
    for _ in range(runs):
        cpu0, faults0 = _cpu_and_faults(pids)
        t0 = time.perf_counter()
        run()
        wall = time.perf_counter() - t0
        cpu1, faults1 = _cpu_and_faults(pids)
        cpu = [b - a for a, b in zip(cpu0, cpu1, strict=True)]
        samples.append({"wall_s": wall, "cpu_s": cpu, "page_faults": faults1 - faults0})
    time.sleep(min(1.0, idle_s))  # the last run's messages settle
    cpu0, _ = _cpu_and_faults(pids)
    t0 = time.perf_counter()
    time.sleep(idle_s)
    cpu1, _ = _cpu_and_faults(pids)
    idle = (sum(cpu1) - sum(cpu0)) / (time.perf_counter() - t0)
    return samples, poses, idle


def summary(name: str, samples: list[dict[str, Any]], idle: list[float]) -> dict[str, Any]:
    """The medians over all runs of a method (of every block): wall, CPU of the calling process, of each engine
    process (when every block had the same number of them) and in all, page faults, CPUs left unused."""
    wall = statistics.median(s["wall_s"] for s in samples)
    total = statistics.median(sum(s["cpu_s"]) for s in samples)
    counts = {len(s["cpu_s"]) for s in samples}
    per_process = [statistics.median(s["cpu_s"][i] for s in samples) for i in range(1, min(counts))]
    return {
        "method": name,
        "wall_s": wall,
        "cpu_caller_s": statistics.median(s["cpu_s"][0] for s in samples),
        "cpu_workers_s": per_process if len(counts) == 1 else [],
        "cpu_engine_s": statistics.median(sum(s["cpu_s"][1:]) for s in samples),
        "engine_processes": max(counts) - 1,
        "cpu_total_s": total,
        "page_faults": statistics.median(s["page_faults"] for s in samples),
        "unused_cpu_fraction": max(0.0, 1.0 - total / (WORKERS * wall)),
        "idle_cpu_per_s": statistics.median(idle),
    }


@contextlib.contextmanager
def started(method: str) -> Iterator[tuple[Any, Callable[[], list[int]]]]:
    """The executor of ``method`` (a key of METHODS) and what names its processes, for the block's runs."""
    if method == "threads":
        with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
            yield pool, list
    elif method == "ray":
        import ray

        # Every process Ray starts (GCS, raylet, workers...) descends from this one.
        ray.init(num_cpus=WORKERS, include_dashboard=False, log_to_driver=False)
        try:
            yield "ray", _descendants
        finally:
            ray.shutdown()
    else:
        with dask_client(METHODS[method][1]) as client:
            yield client, lambda: sorted(_worker_pids(client))


#: The rows: label and, for Dask, the cluster's settings (bench/batch_bench.py; docs/batch.md).
METHODS: dict[str, tuple[str, dict[str, Any]]] = {
    "threads": (f"`ThreadPoolExecutor({WORKERS})`", {}),
    "dask": (f"Dask `LocalCluster({WORKERS} x 1)`", {}),
    "dask_untrimmed": (f"Dask `LocalCluster({WORKERS} x 1)`, `MALLOC_TRIM_THRESHOLD_` unset", DASK_UNTRIMMED),
    "dask_kissm": (f"Dask `LocalCluster({WORKERS} x 1)`, settings for kissm", DASK_FOR_KISSM),
    "ray": (f"Ray (`num_cpus={WORKERS}`), all its processes", {}),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--data", type=Path, default=default_data(), help="the shared data folder")
    parser.add_argument("--runs", type=int, default=5, help="timed runs per method and block")
    parser.add_argument("--blocks", type=int, default=1, help="start every method afresh B times, in turns")
    parser.add_argument("--idle", type=float, default=3.0, help="seconds of idle CPU measured after the runs")
    parser.add_argument("--pair-repeats", type=int, default=1, help="list every pair K times in one batch")
    parser.add_argument("--refine", choices=["gicp", "none"], default="gicp")
    parser.add_argument("--voxel", type=float, default=0.5)
    parser.add_argument("--smoke", action="store_true", help="three keyframes, one run each")
    parser.add_argument("--out", type=Path, default=None, help="also write the table to OUT/batch-accounting.md")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.blocks < 1 or args.pair_repeats < 1:
        parser.error("--runs, --blocks and --pair-repeats must be at least 1")
    if not args.idle > 0:
        parser.error("--idle must be positive")
    if not (args.data / DATASET).is_dir():
        print(f"batch_accounting: {args.data / DATASET} is absent: nothing measured", file=sys.stderr)
        return 0
    try:
        import distributed  # noqa: F401
    except ImportError:
        print("batch_accounting: Dask is not installed (pip install 'dask[distributed]'): nothing measured")
        return 0
    pin(cpus_for(WORKERS))
    count = SMOKE_KEYFRAMES if args.smoke else KEYFRAMES
    runs, blocks, idle_s = (1, 1, 0.5) if args.smoke else (args.runs, args.blocks, args.idle)
    clouds = load_clouds(args.data, count)
    pairs = all_pairs(list(range(count))) * args.pair_repeats
    settings = {"voxel_size": args.voxel, "refine": args.refine}
    methods = list(METHODS)
    try:
        import ray  # noqa: F401
    except ImportError:
        methods.remove("ray")
    # Every block starts each method afresh and times it --runs times, kept running; the methods take turns
    # block by block, so that the machine's own drift touches all of them alike.
    samples: dict[str, list[dict[str, Any]]] = {m: [] for m in methods}
    idle: dict[str, list[float]] = {m: [] for m in methods}
    reference: list[Any] | None = None
    same = True
    for _ in range(blocks):
        for method in methods:
            with started(method) as (executor, workers):
                runs_of_block, poses, idle_rate = account(executor, workers, pairs, clouds, settings, runs, idle_s)
            samples[method] += runs_of_block
            idle[method].append(idle_rate)
            reference = poses if reference is None else reference
            same = same and same_poses(poses, reference)
    rows = [summary(METHODS[m][0], samples[m], idle[m]) for m in methods]
    lines = [
        f"{len(pairs)} pairs of {count} keyframes, refine {args.refine}, {blocks} block(s) of {runs} timed run(s) "
        "per method (medians), CPUs pinned:",
        "",
        "| | wall per run | CPU, calling process | CPU, engine's processes | CPU, total | CPUs unused | page faults "
        "| idle, CPU-s per s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        w = r["cpu_workers_s"]
        if r["engine_processes"] == 0:
            workers_cpu = "(threads)"
        elif w and len(w) <= WORKERS:
            workers_cpu = " + ".join(f"{c:.2f}" for c in w) + " s"
        else:
            workers_cpu = f"{r['cpu_engine_s']:.2f} s in {r['engine_processes']}"
        lines.append(
            f"| {r['method']} | {r['wall_s']:.2f} s | {r['cpu_caller_s']:.2f} s | {workers_cpu} | "
            f"{r['cpu_total_s']:.2f} s | {100 * r['unused_cpu_fraction']:.0f}% | {r['page_faults'] / 1000:.1f}K | "
            f"{r['idle_cpu_per_s']:.3f} |"
        )
    print("\n".join(lines))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "batch-accounting.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    if not same:
        print("batch_accounting: an engine's poses differ from the thread pool's", file=sys.stderr)
        return 1
    return 0


def _descendants() -> list[int]:
    import psutil

    return sorted(p.pid for p in psutil.Process().children(recursive=True))


def _worker_pids(client: Any) -> set[int]:
    """The process ids of the cluster's workers (asked of the workers themselves)."""
    return set(client.run(os.getpid).values())
