# SPDX-License-Identifier: MIT
"""kissm.batch on a real Dask cluster (a LocalCluster of two single-threaded worker processes, shared by the
module): results bitwise those of the serial loop, one describe task per cloud in the scheduler's task stream,
failures as values, and a worker killed mid-run changing no bit of the results."""

from __future__ import annotations

import collections
import logging
import os
import signal
from collections.abc import Iterator
from typing import Any

import pytest

import kissm
import kissm.batch

import batchcases
from batchcases import Batch, Events

distributed: Any = pytest.importorskip(
    "distributed", reason="Dask (pip install 'kissm[dask]') is not installed: the Dask engine is not tested here"
)


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.CRITICAL
    )
    with cluster, distributed.Client(cluster) as client:
        yield client


def run_recorded(client: Any, batch: Batch) -> tuple[list[kissm.batch.PairResult], Events, collections.Counter[str]]:
    """The batch on the cluster, with its progress events and the describe tasks the workers ran (from the
    scheduler's task stream: what the workers report, not what the driver believes)."""
    events = Events()
    with distributed.get_task_stream(client) as stream:
        got = kissm.batch.register_many(batch.pairs, batch.clouds, client, voxel_size=batch.voxel_size, progress=events)
    describes = collections.Counter(str(task["key"]) for task in stream.data if "-describe-" in str(task["key"]))
    return got, events, describes


def assert_each_described_once(describes: collections.Counter[str], batch: Batch) -> None:
    used = {key for pair in batch.pairs for key in pair}
    assert len(describes) == len(used), describes
    assert set(describes.values()) == {1}, describes


def test_synthetic_on_dask(client, synthetic, synthetic_serial) -> None:
    got, events, describes = run_recorded(client, synthetic)
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    batchcases.assert_each_once(events, synthetic)
    assert_each_described_once(describes, synthetic)


def test_long_batch_in_groups_on_dask(client, synthetic, synthetic_serial) -> None:
    """Enough pairs for tasks of several pairs: still each cloud described once, the results bitwise the serial
    loop's, in input order; fewer register tasks than pairs in the task stream."""
    batch = batchcases.repeated(synthetic, 8)
    events = Events()
    with distributed.get_task_stream(client) as stream:
        got = kissm.batch.register_many(batch.pairs, batch.clouds, client, voxel_size=batch.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, batch, synthetic_serial * 8)
    batchcases.assert_each_once(events, batch)
    keys = [str(task["key"]) for task in stream.data]
    assert_each_described_once(collections.Counter(k for k in keys if "-describe-" in k), batch)
    registers = sum("-register-" in k for k in keys)
    assert 0 < registers < len(batch.pairs), registers


def test_few_tasks_in_flight_on_dask(client, synthetic, synthetic_serial, monkeypatch) -> None:
    """With at most 2 pair tasks in flight the rest go in as those finish: the same results, every pair once."""
    import kissm._batch_dask

    monkeypatch.setattr(kissm._batch_dask, "_IN_FLIGHT", 2)
    batch = batchcases.repeated(synthetic, 4)
    events = Events()
    got = kissm.batch.register_many(batch.pairs, batch.clouds, client, voxel_size=batch.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, batch, synthetic_serial * 4)
    batchcases.assert_each_once(events, batch)


def test_describe_many_and_failures_on_dask(client, synthetic, tmp_path) -> None:
    batchcases.assert_describe_many_and_failures(client, synthetic, tmp_path)


def test_kitti_on_dask(client, kitti, kitti_serial) -> None:
    got, events, describes = run_recorded(client, kitti)
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)
    assert_each_described_once(describes, kitti)


def holder_of_most_features(client: Any) -> int:
    """The pid of the worker holding the most features (describe results) right now."""
    held: collections.Counter[str] = collections.Counter()
    for key, workers in client.who_has().items():
        if "-describe-" in str(key):
            held.update(workers)
    address = held.most_common(1)[0][0]
    return int(client.run(os.getpid, workers=[address])[address])


def test_kitti_with_a_worker_killed_mid_run(client, kitti, kitti_serial) -> None:
    """SIGKILL, after the first pair, the worker holding the most features: what it held and ran is lost; Dask
    reruns and recomputes, the driver scatters and describes again what Dask cannot (scattered points held by
    that worker alone: whether any were depends on where the pairs ran); the results must not change by a bit."""
    events = Events()
    victims: list[int] = []

    def kill_once(event: kissm.batch.Progress) -> None:
        events(event)
        if event.stage == "register" and not victims:
            victims.append(holder_of_most_features(client))
            os.kill(victims[0], signal.SIGKILL)

    with distributed.get_task_stream(client) as stream:
        got = kissm.batch.register_many(
            kitti.pairs, kitti.clouds, client, voxel_size=kitti.voxel_size, progress=kill_once
        )
    assert len(victims) == 1
    assert [e.done for e in events.seen if e.stage == "register"][-1] == len(kitti.pairs)
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)  # progress reports each cloud once, even when described again
    client.wait_for_workers(2, timeout=120)
    assert victims[0] not in client.run(os.getpid).values()  # the nanny started a new worker
    assert len([t for t in stream.data if "-describe-" in str(t["key"])]) >= len(kitti.clouds)


def test_every_worker_killed_after_the_first_description(client, synthetic, synthetic_serial) -> None:
    """Both workers SIGKILLed once the first cloud is described: its features and every scattered point are
    gone, which Dask cannot recompute; the driver scatters and describes again, and nothing changes by a bit."""
    events = Events()
    victims: list[int] = []

    def kill_all_once(event: kissm.batch.Progress) -> None:
        events(event)
        if not victims:
            victims.extend(client.run(os.getpid).values())
            for pid in victims:
                os.kill(pid, signal.SIGKILL)

    with distributed.get_task_stream(client) as stream:
        got = kissm.batch.register_many(
            synthetic.pairs, synthetic.clouds, client, voxel_size=synthetic.voxel_size, progress=kill_all_once
        )
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    batchcases.assert_each_once(events, synthetic)
    client.wait_for_workers(2, timeout=120)
    assert not set(victims) & set(client.run(os.getpid).values())
    # Keys are <batch>-describe-<cloud>-<attempt>: the first cloud's features were lost, so it ran again.
    runs = collections.Counter(str(t["key"]).rsplit("-", 2)[1] for t in stream.data if "-describe-" in str(t["key"]))
    assert runs[str(events.seen[0].index)] >= 2, runs
