# SPDX-License-Identifier: MIT
"""Batch registration throughput (issue 17): pairs per second for every pair of the KITTI 07 keyframes (each
keyframe in four pairs), registered

* per pair: ``kissm.register(source, target, ...)`` in a loop, each call describing both clouds again;
* ``kissm.batch.register_many`` on the calling thread (each cloud described once);
* the same with a ``concurrent.futures.ThreadPoolExecutor(2)``;
* the same on a Dask ``LocalCluster`` of 2 worker processes of 1 thread;
* the same on such a cluster started with the Dask settings docs/batch.md suggests for kissm clusters
  (``DASK_FOR_KISSM`` below: ``MALLOC_TRIM_THRESHOLD_`` unset, the workers' profiler off, slower monitors);
* the same on Ray, ``ray.init(num_cpus=2)``.

Writes docs/reports/batch-throughput.md and bench/results/batch_latest.json.gz, the results it is rendered from
(with --refine none: docs/reports/batch-throughput-coarse.md and bench/results/batch_coarse_latest.json.gz; with
--pair-repeats K > 1, -long and _long); the page itself is kissm_bench.reports.batch's.

    python bench/batch_bench.py [--repeats 5] [--voxel 0.5] [--out docs] [--data DIR]
    python bench/batch_bench.py --smoke         # seconds: three keyframes, one repeat, no Dask or Ray, a temp dir
    python bench/batch_bench.py --report-from bench/results/batch_latest.json.gz   # rewrite the page

Every method gets one warm-up run (it starts Dask's and Ray's workers and loads the library in them), then
the methods' timed runs alternate (method 1, 2, ..., then again) so that a change of load on the machine
touches all of them alike; the median of --repeats is reported. Dask's and Ray's clusters run one at a time:
each is started, warmed up, timed once and stopped for each repeat (idle, a Dask cluster keeps a tenth of a
CPU busy). Settings as in examples/python/pose_graph.py:
0.5 m voxels, GICP refinement, one library thread per job. The process is pinned to the first two CPUs; the
pools get two workers. Every method's poses must equal the serial batch's bit for bit (the library is
deterministic), or the run fails. Also reported: the size of ``Features.to_bytes()`` per keypoint, what a
process pool, Dask or Ray moves per described cloud. Needs numpy and kissm (with kissm.batch); Dask
(``distributed``) and Ray when installed (else their rows say so). Exits 0 without running when the data is
absent, 1 when a method's results differ or a pair raised, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import itertools
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Hashable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from . import common
from .common import (
    RESULTS,
    cpus_for,
    package_versions,
    pin,
)
from .data import KEYFRAMES_DIR
from .reports.batch import COARSE, WORKERS, page_for, reduce, verdicts, write_report
from .results import destinations, save
from .results import read as read_results

DATASET = KEYFRAMES_DIR  # every pair of its five keyframes
KEYFRAMES = 5
SMOKE_KEYFRAMES = 3
RAW_NAME = "batch_raw.json"  # the raw results' name in any other --out (bench/results/ keeps the reduced ones)
#: Dask settings of the configured Dask rows (docs/batch.md, "Dask settings for kissm clusters"). Untrimmed: the
#: nannies leave MALLOC_TRIM_THRESHOLD_ unset (Dask's 65536 makes every large array of a call fresh pages).
DASK_UNTRIMMED: dict[str, Any] = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
#: For kissm: untrimmed, and the periodic work that wakes every Dask process many times a second done less often
#: (the workers' statistical profiler, every 10 ms; the event loops' health ticks, 20 ms; the memory and system
#: monitors, 100 and 500 ms). Idle, such a cluster takes 0.014-0.017 CPU-s per second, not 0.12-0.15.
DASK_FOR_KISSM: dict[str, Any] = {
    **DASK_UNTRIMMED,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
}
Pairs = list[tuple[int, int]]
Clouds = dict[Hashable, np.ndarray]


def load_clouds(data: Path, count: int) -> Clouds:
    import kissm

    root = data / DATASET
    return {k: kissm.read_points(root / f"{k:06d}" / "points.bin", format="bin_xyz_f32") for k in range(count)}


def all_pairs(keys: list[int]) -> Pairs:
    return [(b, a) for a, b in itertools.combinations(keys, 2)]


def same_poses(poses: list[np.ndarray | None], reference: list[np.ndarray | None]) -> bool:
    """Whether two runs' poses are bitwise equal, pair by pair (None: the pair failed in both)."""
    return all(
        (a is None and b is None) or (a is not None and b is not None and np.array_equal(a, b))
        for a, b in zip(poses, reference, strict=True)
    )


@contextlib.contextmanager
def dask_client(settings: dict[str, Any]) -> Iterator[Any]:
    """A client of a Dask ``LocalCluster`` of WORKERS processes of one thread, started under the Dask settings
    ``settings`` (DASK_UNTRIMMED, DASK_FOR_KISSM or none); the cluster stops when the block ends."""
    import dask
    from distributed import Client, LocalCluster

    # A nanny also sets MALLOC_TRIM_THRESHOLD_ in the process that runs it, whence a later cluster's workers would
    # inherit it whatever their settings: it goes from there while an untrimmed cluster starts, and the caller's
    # value comes back afterwards.
    inherited = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    untrimmed = all(k in settings for k in DASK_UNTRIMMED)
    try:
        if untrimmed:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        with (
            dask.config.set(settings),
            LocalCluster(
                n_workers=WORKERS, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
            ) as cluster,
            Client(cluster) as client,
        ):
            if untrimmed:
                trims = set(client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_")).values())
                if trims != {None}:
                    raise RuntimeError(f"the untrimmed cluster's workers have MALLOC_TRIM_THRESHOLD_={trims}")
            yield client
    finally:
        if inherited is None:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        else:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = inherited


# ------------------------------------------------------------------------------------------------- methods


class Method:
    """One way to register the pairs: ``start`` (not timed), ``run`` (timed; the poses in pair order), ``stop``."""

    def __init__(self, name: str, settings: dict[str, Any]) -> None:
        self.name = name
        self.settings = settings
        self.executor: Any = None
        self._close: Callable[[], None] | None = None

    def start(self) -> str | None:
        """None, or why the method cannot run here."""
        if self.name == "batch_threads":
            pool = concurrent.futures.ThreadPoolExecutor(WORKERS)
            self.executor, self._close = pool, pool.shutdown
        elif self.name.startswith("batch_dask"):
            try:
                import distributed  # noqa: F401
            except ImportError:
                return "Dask is not installed (pip install 'dask[distributed]')"
            dask_settings = DASK_FOR_KISSM if self.name == "batch_dask_kissm" else {}
            stack = contextlib.ExitStack()
            self.executor, self._close = stack.enter_context(dask_client(dask_settings)), stack.close
        elif self.name == "batch_ray":
            try:
                import ray
            except ImportError:
                return "Ray is not installed (pip install ray)"
            ray.init(num_cpus=WORKERS, include_dashboard=False, log_to_driver=False)
            self.executor, self._close = "ray", ray.shutdown
        return None

    def run(self, pairs: Pairs, clouds: Clouds) -> list[np.ndarray | None]:
        import kissm
        import kissm.batch

        if self.name == "per_pair":
            return [kissm.register(clouds[s], clouds[t], num_threads=1, **self.settings).transform for s, t in pairs]
        done = kissm.batch.register_many(pairs, clouds, self.executor, progress=False, **self.settings)
        return [None if p.result is None else p.result.transform for p in done]

    @property
    def engine(self) -> bool:
        """Whether the method runs its own processes (started per timed run, see measure)."""
        return self.name.startswith(("batch_dask", "batch_ray"))

    def stop(self) -> None:
        if self._close is not None:
            self._close()
            self._close = None


def features_size(clouds: Clouds, settings: dict[str, Any]) -> list[dict[str, Any]]:
    """Per cloud: the keypoints and the bytes ``Features.to_bytes()`` makes of them (what a pool pickles)."""
    import kissm

    voxel = settings["voxel_size"]
    out = []
    with kissm.Matcher(voxel_size=voxel, refine_mode=settings["refine"], num_threads=1) as matcher:
        for key, points in clouds.items():
            features = matcher.compute_features(points)
            size = len(features.to_bytes())
            out.append(
                {
                    "cloud": key,
                    "points": int(len(points)),
                    "voxels": features.num_voxels,
                    "keypoints": features.num_keypoints,
                    "bytes": size,
                    "bytes_per_keypoint": size / max(1, features.num_keypoints),
                }
            )
    return out


def cpu_split(pairs: Pairs, clouds: Clouds, settings: dict[str, Any]) -> dict[str, float]:
    """Where a pair's time goes, in CPU seconds of this process on one library thread (what other processes'
    load changes least): describing a cloud, matching and refining two described clouds, a whole
    ``register``. The ratio the per-pair loop can lose to describing once follows from them: each cloud is
    described once instead of once per pair it is in, the matching stays."""
    import kissm

    with kissm.Matcher(voxel_size=settings["voxel_size"], refine_mode=settings["refine"], num_threads=1) as m:
        m.register(clouds[pairs[0][0]], clouds[pairs[0][1]])  # warm-up: the library's first-call costs
        t = time.process_time()
        features = {k: m.compute_features(points) for k, points in clouds.items()}
        describe = (time.process_time() - t) / len(clouds)
        t = time.process_time()
        for s, g in pairs:
            m.register_features(features[s], features[g])
        match = (time.process_time() - t) / len(pairs)
        t = time.process_time()
        for s, g in pairs:
            m.register(clouds[s], clouds[g])
        full = (time.process_time() - t) / len(pairs)
    return {
        "describe_cpu_s_per_cloud": describe,
        "match_refine_cpu_s_per_pair": match,
        "register_cpu_s_per_pair": full,
        #: per-pair loop / describe-once batch, for these pairs
        "predicted_speedup": len(pairs) * full / (len(clouds) * describe + len(pairs) * match),
        #: the same with every cloud in infinitely many pairs: only the matching left
        "limit_speedup": full / match,
    }


def measure(args: argparse.Namespace, results: dict[str, Any]) -> None:
    count = SMOKE_KEYFRAMES if args.smoke else KEYFRAMES
    clouds = load_clouds(args.data, count)
    # --pair-repeats K lists every pair K times in one batch: each listing is a real pair job (nothing caches
    # results), so a long batch's throughput shows without the fixed cost of starting one (Dask's and Ray's
    # scheduling, the first transfers) weighing as on 10 pairs.
    pairs = all_pairs(list(range(count))) * args.pair_repeats
    settings = {"voxel_size": args.voxel, "refine": args.refine}  # register_many: threads_per_job=1, its default
    results["pairs"] = [list(p) for p in pairs]
    results["features"] = features_size(clouds, settings)
    results["cpu_split"] = cpu_split(pairs, clouds, settings)
    names = ["per_pair", "batch_serial", "batch_threads"]
    if not args.smoke:
        names += ["batch_dask", "batch_dask_kissm", "batch_ray"]
    methods = [Method(n, settings) for n in names]
    running = []
    for m in methods:
        why = m.start()
        if why is not None:
            results["methods"][m.name] = {"skipped": why}
            print(f"batch_bench: {m.name}: skipped: {why}", flush=True)
            continue
        poses = m.run(pairs, clouds)  # warm-up
        results["methods"][m.name] = {"seconds": [], "failed_pairs": sum(p is None for p in poses), "poses": poses}
        running.append(m)
        if m.engine:
            m.stop()
    # One engine runs at a time, started afresh (and warmed up) for each timed run: an idle Dask cluster keeps
    # about a tenth of a CPU busy (its scheduler's and workers' heartbeats), an idle Ray runtime a few hundredths,
    # and that time would be taken from whichever method runs beside them.
    try:
        for repeat in range(args.repeats):
            for m in running:
                if m.engine:
                    m.start()
                    m.run(pairs, clouds)  # the fresh workers' first imports and first calls
                t0 = time.perf_counter()
                poses = m.run(pairs, clouds)
                seconds = time.perf_counter() - t0
                results["methods"][m.name]["seconds"].append(seconds)
                print(f"batch_bench: repeat {repeat + 1}/{args.repeats} {m.name}: {seconds:.2f} s", flush=True)
                if m.engine:
                    m.stop()
    finally:
        for m in running:
            m.stop()
    reference = results["methods"]["batch_serial"]["poses"]
    for entry in results["methods"].values():
        poses = entry.pop("poses", None)
        if poses is None:
            continue
        entry["same_as_serial_batch"] = same_poses(poses, reference)
        entry["median_s"] = statistics.median(entry["seconds"])
        entry["pairs_per_s"] = len(pairs) / entry["median_s"]
        entry["best_pairs_per_s"] = len(pairs) / min(entry["seconds"])


# ---------------------------------------------------------------------------------------------------- main


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    common.add_data_option(parser, "the shared data folder")
    parser.add_argument("--voxel", type=float, default=0.5)
    parser.add_argument("--repeats", type=int, default=5)
    common.add_output_options(parser, "OUT/batch-throughput*.md", RESULTS / "batch*_latest.json.gz", RAW_NAME)
    parser.add_argument("--smoke", action="store_true", help="three keyframes, one repeat, no Dask or Ray")
    parser.add_argument(
        "--refine", choices=["gicp", "none"], default="gicp", help="refinement of every pair (none: coarse poses)"
    )
    parser.add_argument("--pair-repeats", type=int, default=1, help="list every pair K times in one batch")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    if args.pair_repeats < 1:
        parser.error("--pair-repeats must be at least 1")
    if args.smoke:
        args.repeats = 1
    return args


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    if args.report_from is not None:
        saved = read_results(args.report_from)
        page_name = page_for(saved["meta"]["args"].get("refine", "gicp"), saved["meta"]["args"].get("pair_repeats", 1))
        print(f"batch_bench: wrote {write_report(saved, args.out / page_name)}")
        return 0
    if not (args.data / DATASET / "graph.txt").is_file():
        return common.no_data("batch_bench", f"no {DATASET} under {args.data}")
    cpus = cpus_for(WORKERS)
    pin(cpus)  # before any pool starts: its workers inherit it
    os.environ["OMP_NUM_THREADS"] = "1"
    if args.smoke and "--out" not in common.explicit_options(argv):
        args.out = Path(tempfile.mkdtemp(prefix="kissm-batch-smoke-"))
    stem = "batch" + ("" if args.refine == "gicp" else f"_{COARSE}") + ("_long" if args.pair_repeats > 1 else "")
    committed, raw = destinations(RESULTS / f"{stem}_latest.json.gz", RAW_NAME, args.out, args.smoke, args.raw)
    packages = package_versions(("kissm", "numpy", "dask", "distributed", "ray"))
    results: dict[str, Any] = {
        "meta": common.run_meta("batch_bench.py", argv, args, cpus=cpus, versions=packages),
        "methods": {},
    }
    t0 = time.monotonic()
    measure(args, results)
    common.finish_meta(results["meta"], t0)
    results["verdicts"] = [{"target": t, "ratio": r, "met": m} for t, r, m in verdicts(results)]
    results["verdicts_best_runs"] = [
        {"target": t, "ratio": r, "met": m} for t, r, m in verdicts(results, "best_pairs_per_s")
    ]
    save(results, reduce(results), committed, raw)
    page = write_report(results, args.out / page_for(args.refine, args.pair_repeats))
    print(page.read_text())
    print(f"batch_bench: wrote {page} and {' and '.join(str(p) for p in (committed, raw) if p is not None)}")
    bad = [n for n, e in results["methods"].items() if "skipped" not in e and not e["same_as_serial_batch"]]
    failed = [n for n, e in results["methods"].items() if e.get("failed_pairs")]
    if bad or failed:
        print(f"batch_bench: poses differ from the serial batch: {bad}; pairs raised: {failed}", file=sys.stderr)
        return 1
    return 0
