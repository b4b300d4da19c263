#!/usr/bin/env python3
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

Writes bench/results/batch_latest.json and docs/reports/batch-throughput.md (with --refine none:
bench/results/batch_coarse_latest.json and docs/reports/batch-throughput-coarse.md).

    python bench/batch_bench.py [--repeats 5] [--voxel 0.5] [--out docs] [--data DIR]
    python bench/batch_bench.py --smoke         # seconds: three keyframes, one repeat, no Dask or Ray, a temp dir
    python bench/batch_bench.py --report-from bench/results/batch_latest.json   # rewrite the page

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
import datetime as _dt
import itertools
import json
import os
import shlex
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Hashable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
from bench import cpus_for, machine_info, package_versions  # noqa: E402

DATASET = "kitti07_keyframes_gtsam_points"
KEYFRAMES = 5
SMOKE_KEYFRAMES = 3
WORKERS = 2
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
#: Targets of issue 17: Dask and Ray within 15% of the thread pool; clouds described once >= 1.8x the loop.
ENGINE_TOLERANCE = 0.15
BATCH_SPEEDUP = 1.8
LABEL = {
    "per_pair": "`kissm.register` per pair (serial loop)",
    "batch_serial": "`register_many`, calling thread",
    "batch_threads": f"`register_many`, `ThreadPoolExecutor({WORKERS})`",
    "batch_dask": f"`register_many`, Dask `LocalCluster` ({WORKERS} workers x 1 thread)",
    "batch_dask_kissm": f"`register_many`, Dask `LocalCluster` ({WORKERS} x 1), settings for kissm (docs/batch.md)",
    "batch_ray": f"`register_many`, Ray (`num_cpus={WORKERS}`)",
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


# -------------------------------------------------------------------------------------------------- report


def ratio(results: dict[str, Any], a: str, b: str, key: str = "pairs_per_s") -> float | None:
    ma, mb = results["methods"].get(a, {}), results["methods"].get(b, {})
    if key not in ma or key not in mb:
        return None
    return float(ma[key] / mb[key])


def verdicts(results: dict[str, Any], key: str = "pairs_per_s") -> list[tuple[str, float | None, bool | None]]:
    """(target, measured ratio, met) for the three targets, on the medians (or the best runs)."""
    out: list[tuple[str, float | None, bool | None]] = []
    once = ratio(results, "batch_serial", "per_pair", key)
    out.append(
        (
            f"clouds described once >= {BATCH_SPEEDUP}x the per-pair loop",
            once,
            None if once is None else once >= BATCH_SPEEDUP,
        )
    )
    for engine, name in (
        ("batch_dask", "Dask"),
        ("batch_dask_kissm", "Dask (settings for kissm)"),
        ("batch_ray", "Ray"),
    ):
        r = ratio(results, engine, "batch_threads", key)
        met = None if r is None else r >= 1.0 - ENGINE_TOLERANCE
        out.append((f"{name} within {ENGINE_TOLERANCE:.0%} of the thread pool", r, met))
    return out


def yes_no(met: bool | None) -> str:
    return "n/a" if met is None else ("yes" if met else "**no**")


def fmt(value: float | None, spec: str = ".2f", unit: str = "") -> str:
    return "n/a" if value is None else format(value, spec) + unit


def write_report(results: dict[str, Any], path: Path) -> Path:
    meta = results["meta"]
    mach = meta["machine"]
    n_pairs = len(results["pairs"])
    lines = [
        "# Batch registration throughput",
        "",
        "<!-- Generated by bench/batch_bench.py from its raw results; rerun the command below, do not edit. -->",
        "",
        f"Every pair of {len(results['features'])} KITTI 07 keyframes{listed(meta)} ({n_pairs} pairs, each "
        f"keyframe in {2 * n_pairs // max(1, len(results['features']))}), {meta['args']['voxel']:g} m voxels, "
        f"{refine_words(meta)}, one library thread "
        "per job, median of "
        f"{meta['args']['repeats']} timed runs after a warm-up, the methods' runs interleaved; Dask and Ray started "
        "afresh, warmed up and stopped around each of their timed runs, one cluster at a time.",
        "",
        f"Machine: {mach.get('cpu', '?')}, {mach.get('cpus_online', '?')} CPUs online, pinned to CPUs "
        f"{meta['cpus']}; load average {fmt(meta['load_start'][0], '.1f')} at the start, "
        f"{fmt(meta['load_end'][0], '.1f')} at the end (the machine is shared: other jobs' load is in these "
        f"numbers). Started {meta['started']}, {meta['duration_s']:.0f} s. Command: `{meta['command']}`.",
        "",
    ]
    busiest = max(meta["load_start"][0], meta["load_end"][0])
    if busiest > len(meta["cpus"]):
        lines += [
            f"**The load average ({busiest:.1f}) exceeded the {len(meta['cpus'])} CPUs: other processes took "
            "CPU time from every row, most from the parallel ones. The ratios below measure that contention as "
            "much as the engines; judge the targets on an idle machine.**",
            "",
        ]
    lines += [
        "| method | median s | pairs/s | best run, pairs/s | vs thread pool | vs per-pair loop "
        "| poses as the serial batch |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, label in LABEL.items():
        entry = results["methods"].get(name)
        if entry is None:
            continue
        if "skipped" in entry:
            lines.append(f"| {label} | skipped: {entry['skipped']} | | | | | |")
            continue
        vs_pool, vs_loop = ratio(results, name, "batch_threads"), ratio(results, name, "per_pair")
        lines.append(
            f"| {label} | {entry['median_s']:.2f} | {entry['pairs_per_s']:.2f} | {entry['best_pairs_per_s']:.2f} | "
            f"{fmt(vs_pool, unit='x')} | {fmt(vs_loop, unit='x')} | "
            f"{'yes' if entry['same_as_serial_batch'] else '**no**'} |"
        )
    lines += ["", "| target | medians | met | best runs | met |", "|---|---|---|---|---|"]
    for (text, value, met), (_, best, best_met) in zip(
        verdicts(results), verdicts(results, "best_pairs_per_s"), strict=True
    ):
        lines.append(
            f"| {text} | {fmt(value, unit='x')} | {yes_no(met)} | {fmt(best, unit='x')} | {yes_no(best_met)} |"
        )
    split = results["cpu_split"]
    lines += [
        "",
        f"CPU time on one thread (this process only): describing a keyframe {split['describe_cpu_s_per_cloud']:.3f} s, "
        f"matching (and refining) two described keyframes {split['match_refine_cpu_s_per_pair']:.3f} s, a whole "
        f"`kissm.register` {split['register_cpu_s_per_pair']:.3f} s. Describing each keyframe once instead of "
        f"twice per pair can therefore gain {split['predicted_speedup']:.2f}x on these pairs, and no more than "
        f"{split['limit_speedup']:.2f}x however many pairs each cloud is in: the matching and refinement stay.",
    ]
    sizes = results["features"]
    per_kp = [f["bytes_per_keypoint"] for f in sizes]
    lines += [
        "",
        f"`Features.to_bytes()` (what a process pool, Dask or Ray moves per described cloud): "
        f"{statistics.median(per_kp):.0f} bytes per keypoint (median; {min(per_kp):.0f}-{max(per_kp):.0f}), "
        "the voxels and their normals and planes for refinement included.",
        "",
        "| keyframe | points | voxels | keypoints | bytes | bytes/keypoint |",
        "|---|---|---|---|---|---|",
    ]
    for f in sizes:
        lines.append(
            f"| {f['cloud']} | {f['points']} | {f['voxels']} | {f['keypoints']} | {f['bytes']} | "
            f"{f['bytes_per_keypoint']:.0f} |"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
    return path


# ---------------------------------------------------------------------------------------------------- main

COARSE = "coarse"


def page_for(refine: str, pair_repeats: int = 1) -> str:
    """The report's file name: the refined run's page, or the coarse one's beside it; -long with --pair-repeats."""
    return (
        "batch-throughput" + ("" if refine == "gicp" else f"-{COARSE}") + ("-long" if pair_repeats > 1 else "") + ".md"
    )


def listed(meta: dict[str, Any]) -> str:
    k = int(meta["args"].get("pair_repeats", 1))
    return "" if k == 1 else f", each pair listed {k} times in one batch"


def refine_words(meta: dict[str, Any]) -> str:
    return "GICP refinement" if meta["args"].get("refine", "gicp") == "gicp" else "no refinement (coarse poses)"


def parse_args(argv: list[str]) -> argparse.Namespace:
    default_data = Path(os.environ.get("KISSM_DATA_DIR") or REPO.parent / "shared" / "data")
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--data", type=Path, default=default_data, help="the shared data folder")
    parser.add_argument("--voxel", type=float, default=0.5)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "reports", help="where batch-throughput.md goes")
    parser.add_argument("--smoke", action="store_true", help="three keyframes, one repeat, no Dask or Ray")
    parser.add_argument(
        "--refine", choices=["gicp", "none"], default="gicp", help="refinement of every pair (none: coarse poses)"
    )
    parser.add_argument("--pair-repeats", type=int, default=1, help="list every pair K times in one batch")
    parser.add_argument("--report-from", type=Path, default=None, help="rewrite the page from a raw JSON only")
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
        saved = json.loads(args.report_from.read_text())
        page_name = page_for(saved["meta"]["args"].get("refine", "gicp"), saved["meta"]["args"].get("pair_repeats", 1))
        print(f"batch_bench: wrote {write_report(saved, args.out / page_name)}")
        return 0
    if not (args.data / DATASET / "graph.txt").is_file():
        print(f"batch_bench: skipped: no {DATASET} under {args.data} (set --data or KISSM_DATA_DIR)", flush=True)
        return 0
    cpus = cpus_for(WORKERS)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, cpus)  # before any pool starts: its workers inherit it
    os.environ["OMP_NUM_THREADS"] = "1"
    if args.smoke and "--out" not in argv:
        args.out = Path(tempfile.mkdtemp(prefix="kissm-batch-smoke-"))
    committed = not args.smoke and args.out.resolve() == (REPO / "docs" / "reports").resolve()
    stem = "batch" + ("" if args.refine == "gicp" else f"_{COARSE}") + ("_long" if args.pair_repeats > 1 else "")
    stem += "_latest.json"
    raw = HERE / "results" / stem if committed else args.out / "batch_raw.json"
    command = "python bench/batch_bench.py " + " ".join(shlex.quote(a) for a in argv)
    packages = package_versions(("kissm", "numpy", "dask", "distributed", "ray"))
    results: dict[str, Any] = {
        "meta": {
            "command": command.strip(),
            "args": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
            "cpus": cpus,
            "started": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
            "load_start": os.getloadavg(),
            "machine": machine_info(sys.executable),
            "versions": packages,
        },
        "methods": {},
    }
    t0 = time.monotonic()
    measure(args, results)
    results["meta"]["duration_s"] = time.monotonic() - t0
    results["meta"]["load_end"] = os.getloadavg()
    results["verdicts"] = [{"target": t, "ratio": r, "met": m} for t, r, m in verdicts(results)]
    results["verdicts_best_runs"] = [
        {"target": t, "ratio": r, "met": m} for t, r, m in verdicts(results, "best_pairs_per_s")
    ]
    raw.parent.mkdir(parents=True, exist_ok=True)
    raw.write_text(json.dumps(results, indent=1, default=lambda o: o.tolist()) + "\n")
    page = write_report(results, args.out / page_for(args.refine, args.pair_repeats))
    print(page.read_text())
    print(f"batch_bench: wrote {page} and {raw}")
    bad = [n for n, e in results["methods"].items() if "skipped" not in e and not e["same_as_serial_batch"]]
    failed = [n for n, e in results["methods"].items() if e.get("failed_pairs")]
    if bad or failed:
        print(f"batch_bench: poses differ from the serial batch: {bad}; pairs raised: {failed}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
