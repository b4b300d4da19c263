# SPDX-License-Identifier: MIT
"""kissm.batch on a real Ray runtime (ray.init(num_cpus=2), started and shut down by this module): results
bitwise those of the serial loop, each cloud described once, failures as values, num_cpus per task, and a worker
killed mid-run changing no bit of the results."""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Iterator
from typing import Any

import pytest

import kissm
import kissm.batch

import batchcases
from batchcases import Events

ray: Any = pytest.importorskip(
    "ray", reason="Ray (pip install 'kissm[ray]') is not installed: the Ray engine is not tested here"
)

#: Quiet and light: no usage report, no dashboard, no worker logs on the driver, a small object store.
RAY_ENV = {"RAY_USAGE_STATS_ENABLED": "0", "RAY_DISABLE_DOCKER_CPU_WARNING": "1"}


@pytest.fixture(scope="module")
def runtime() -> Iterator[None]:
    if ray.is_initialized():
        pytest.skip("a Ray runtime is already running in this process")
    saved = {name: os.environ.get(name) for name in RAY_ENV}
    os.environ.update(RAY_ENV)
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        logging_level="error",
        object_store_memory=256 * 1024 * 1024,
    )
    try:
        yield
    finally:
        ray.shutdown()
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def test_synthetic_on_ray(runtime, synthetic, synthetic_serial) -> None:
    events = Events()
    got = kissm.batch.register_many(
        synthetic.pairs, synthetic.clouds, "ray", voxel_size=synthetic.voxel_size, progress=events
    )
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    batchcases.assert_each_once(events, synthetic)


def test_two_threads_per_job_on_ray(runtime, synthetic, synthetic_serial) -> None:
    got = kissm.batch.register_many(
        synthetic.pairs, synthetic.clouds, "ray", voxel_size=synthetic.voxel_size, threads_per_job=2
    )
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)


def test_more_threads_per_job_than_cpus_is_refused(runtime, synthetic) -> None:
    """Ray would wait forever for a node with 3 CPUs: refused before any work."""
    with pytest.raises(kissm.InvalidArgumentError, match=r"threads_per_job=3 .* 2 CPUs"):
        kissm.batch.register_many(
            synthetic.pairs, synthetic.clouds, "ray", voxel_size=synthetic.voxel_size, threads_per_job=3
        )


def test_long_batch_in_groups_on_ray(runtime, synthetic, synthetic_serial) -> None:
    """Enough pairs for tasks of several pairs, from points and from features described before (whose pair
    tasks go in at once): each cloud described once, results bitwise the serial loop's, in input order."""
    batch = batchcases.repeated(synthetic, 8)
    events = Events()
    got = kissm.batch.register_many(batch.pairs, batch.clouds, "ray", voxel_size=batch.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, batch, synthetic_serial * 8)
    batchcases.assert_each_once(events, batch)
    described = kissm.batch.describe_many(synthetic.clouds, "ray", voxel_size=batch.voxel_size)
    mixed = dict(batch.clouds, source=described["source"], target1=described["target1"])
    got = kissm.batch.register_many(batch.pairs, mixed, "ray", voxel_size=batch.voxel_size)
    batchcases.assert_same_as_serial(got, batch, synthetic_serial * 8)


def test_describe_many_and_failures_on_ray(runtime, synthetic, tmp_path) -> None:
    batchcases.assert_describe_many_and_failures("ray", synthetic, tmp_path)


def test_kitti_on_ray(runtime, kitti, kitti_serial) -> None:
    events = Events()
    got = kissm.batch.register_many(kitti.pairs, kitti.clouds, "ray", voxel_size=kitti.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)


def running_pair_workers() -> list[int]:
    """The pids of this process's Ray workers running a pair task now (Ray names its worker processes after
    the task they run: ``ray::cached_pairs_job``)."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except OSError:  # gone meanwhile
                continue
            children.setdefault(ppid, []).append(int(entry))
    found, todo = [], list(children.get(os.getpid(), []))
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                if f.read().startswith(b"ray::cached_pairs_job"):
                    found.append(pid)
        except OSError:
            continue
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="finds Ray's worker processes in /proc")
def test_kitti_with_a_worker_killed_mid_run(runtime, kitti, kitti_serial) -> None:
    """SIGKILL, after the first pair, a worker running a pair task: Ray reruns the task on another worker
    (max_retries), which loads the features it needs again (the dead worker's cache is gone); the results must
    not change by a bit and every pair must be reported once."""
    events = Events()
    victims: list[int] = []

    def kill_once(event: kissm.batch.Progress) -> None:
        events(event)
        if event.stage == "register" and not victims:
            busy = running_pair_workers()
            if busy:
                victims.append(busy[0])
                os.kill(busy[0], signal.SIGKILL)

    got = kissm.batch.register_many(kitti.pairs, kitti.clouds, "ray", voxel_size=kitti.voxel_size, progress=kill_once)
    assert len(victims) == 1, "no Ray worker was running a pair task after the first pair"
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)
