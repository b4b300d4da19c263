# SPDX-License-Identifier: MIT
"""kissm.batch on a real Dask cluster (a LocalCluster of two single-threaded worker processes, shared by the
module): results bitwise those of the serial loop, one describe task per cloud in the scheduler's task stream,
failures as values, and a worker killed mid-run changing no bit of the results; and the Dask settings docs/batch.md
suggests for kissm clusters: real Dask settings, which the workers of a cluster started under them have, and
under which the results are the same bits."""

from __future__ import annotations

import ast
import collections
import importlib.util
import logging
import os
import re
import signal
import sys
from collections.abc import Iterator
from typing import Any

import pytest

import kissm
import kissm.batch
import kissm.batch._dask

import batchcases
from batchcases import Batch, Events
from conftest import REPO_ROOT
from helpers import python_blocks

distributed: Any = pytest.importorskip(
    "distributed", reason="Dask (pip install 'kissm[dask]') is not installed: the Dask engine is not tested here"
)


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    with local_cluster() as cluster, distributed.Client(cluster) as client:
        yield client


def local_cluster() -> Any:
    """The cluster of these tests: two single-threaded worker processes."""
    return distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.CRITICAL
    )


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
    import kissm.batch._dask

    monkeypatch.setattr(kissm.batch._dask, "_IN_FLIGHT", 2)
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


def test_a_scatter_cut_off_is_tried_again(client, synthetic, synthetic_serial, monkeypatch) -> None:
    """A scatter whose connection closes (a worker dying or restarting after a loss) is tried again; the batch
    ends as the serial loop does. Closed every time, the error reaches the caller after the last try."""
    real_scatter = client.scatter
    calls: list[int] = []

    def cut_off_first(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        if len(calls) == 1:
            raise distributed.comm.CommClosedError("in <TCP (closed) ConnectionPool.scatter>: Stream is closed")
        return real_scatter(*args, **kwargs)

    monkeypatch.setattr(kissm.batch._dask, "_SCATTER_PAUSE_S", 0.0)
    monkeypatch.setattr(client, "scatter", cut_off_first)
    got = kissm.batch.register_many(synthetic.pairs, synthetic.clouds, client, voxel_size=synthetic.voxel_size)
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    assert len(calls) == 2

    def always_closed(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        raise distributed.comm.CommClosedError("in <TCP (closed) ConnectionPool.scatter>: Stream is closed")

    calls.clear()
    monkeypatch.setattr(client, "scatter", always_closed)
    with pytest.raises(distributed.comm.CommClosedError):
        kissm.batch.register_many(synthetic.pairs, synthetic.clouds, client, voxel_size=synthetic.voxel_size)
    assert len(calls) == kissm.batch._dask._SCATTER_TRIES


def documented_settings() -> dict[str, Any]:
    """The ``dask.config.set({...})`` of docs/batch.md ("Dask settings for kissm clusters"), as written there."""
    doc = REPO_ROOT / "docs" / "batch.md"
    if not doc.is_file():
        pytest.skip("docs/batch.md is absent (the tests run outside the repository)")
    blocks = python_blocks(doc.read_text(encoding="utf-8"))
    found = [m.group(1) for b in blocks if (m := re.search(r"^dask\.config\.set\((\{.*\})\)$", b, flags=re.S | re.M))]
    assert len(found) == 1, "docs/batch.md should show the settings in one dask.config.set({...}) block"
    settings = ast.literal_eval(found[0])
    assert isinstance(settings, dict)
    return settings


def test_documented_settings_are_dask_settings() -> None:
    """A misspelt key would be set without a word and change nothing: every one must be a key Dask has (with its
    default, which the setting changes), durations must parse, and the benchmark must measure these settings."""
    import dask
    from dask.utils import parse_timedelta

    settings = documented_settings()
    assert len(settings) == 5, settings
    for key, value in settings.items():
        default = dask.config.get(key, default=KeyError)
        assert default is not KeyError, f"{key} is not a Dask setting"
        assert default != value, f"{key}: {value!r} is Dask's default already"
        if isinstance(value, str):
            assert parse_timedelta(value) >= parse_timedelta(default), key  # less often, never more
    assert dask.config.get("distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_") == 65536
    # The benchmark's package (bench/kissm_bench), imported from its folder for this check and forgotten after it.
    path, modules = list(sys.path), set(sys.modules)
    try:
        sys.path.insert(0, str(REPO_ROOT / "bench"))
        module = importlib.import_module("kissm_bench.batch")
    finally:
        sys.path[:] = path
        for name in set(sys.modules) - modules:
            if name == "kissm_bench" or name.startswith("kissm_bench."):
                del sys.modules[name]
    assert module.DASK_FOR_KISSM == settings


def test_synthetic_on_a_cluster_with_the_documented_settings(
    synthetic, synthetic_serial, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A LocalCluster started under docs/batch.md's settings: its workers have them (no MALLOC_TRIM_THRESHOLD_,
    no profiler), and the batch gives the serial loop's bits."""
    import dask

    settings = documented_settings()
    # The module's cluster's nannies set MALLOC_TRIM_THRESHOLD_ in this process too; new workers would inherit it.
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    with (
        dask.config.set(settings),
        local_cluster() as cluster,
        distributed.Client(cluster) as client,
    ):
        assert set(client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_")).values()) == {None}
        profilers = client.run(lambda dask_worker: [k for k in dask_worker.periodic_callbacks if "profile" in k])
        assert list(profilers.values()) == [[], []], profilers
        got, events, describes = run_recorded(client, synthetic)
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    batchcases.assert_each_once(events, synthetic)
    assert_each_described_once(describes, synthetic)
