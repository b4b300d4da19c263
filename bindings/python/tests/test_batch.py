# SPDX-License-Identifier: MIT
"""kissm.batch on the calling thread, a thread pool and a spawn process pool: results bitwise those of the
serial loop, each cloud described once, failures as values, bad arguments refused before any work.
(test_batch_dask.py and test_batch_ray.py run the same batches on Dask and Ray.)"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import kissm
import kissm.batch
from kissm.batch._jobs import pair_job
from kissm.batch._work import MAX_PAIRS_PER_TASK, group_pairs

import batchcases
from batchcases import ComputeCounter, Events


def test_the_module_is_an_attribute_of_kissm() -> None:
    assert kissm.batch.register_many is not None
    assert "batch" in kissm.__all__


def test_describe_many_and_register_many_take_the_same_settings() -> None:
    # The keyword-only settings are written out in both signatures (type checkers and help() read them there);
    # their meaning is stated once, in register_many's docstring, and this keeps the two lists one list.
    import inspect

    def settings(fn: Any) -> list[tuple[str, Any, Any, Any]]:
        params = inspect.signature(fn).parameters.values()
        return [(p.name, p.kind, p.default, p.annotation) for p in params if p.kind >= p.KEYWORD_ONLY]

    shared = settings(kissm.batch.register_many)
    assert [name for name, *_ in shared] == [
        "threads_per_job",
        "progress",
        "voxel_size",
        "refine",
        "preset",
        "config",
        "overrides",
    ]
    assert settings(kissm.batch.describe_many) == shared
    assert ":func:`register_many` for" in " ".join((kissm.batch.describe_many.__doc__ or "").split())


# ---- the calling thread and a thread pool: synthetic clouds (no data needed) ---------------------------------


@pytest.mark.parametrize("threads", [None, 2])
def test_synthetic_equals_the_serial_loop(synthetic, synthetic_serial, threads, monkeypatch) -> None:
    counter = ComputeCounter(monkeypatch)
    events = Events()
    if threads is None:
        got = kissm.batch.register_many(
            synthetic.pairs, synthetic.clouds, voxel_size=synthetic.voxel_size, progress=events
        )
    else:
        with concurrent.futures.ThreadPoolExecutor(threads) as pool:
            got = kissm.batch.register_many(
                synthetic.pairs, synthetic.clouds, pool, voxel_size=synthetic.voxel_size, progress=events
            )
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    batchcases.assert_each_once(events, synthetic)
    assert counter.calls == len(synthetic.clouds)
    assert sum(r.result is not None and r.result.valid for r in got) >= 4  # the committed pair's four problems


def test_threads_per_job_changes_no_bit(synthetic, synthetic_serial) -> None:
    got = kissm.batch.register_many(
        synthetic.pairs, synthetic.clouds, voxel_size=synthetic.voxel_size, threads_per_job=2
    )
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)


def test_settings_reach_the_jobs(synthetic) -> None:
    """refine= and a preset give what the serial loop gives with the same Config."""
    config = kissm.Config.preset("lidar-handheld", voxel_size=synthetic.voxel_size, refine_mode="gicp")
    expected = batchcases.serial(
        synthetic, **{k: v for k, v in config.to_dict().items() if k not in ("voxel_size", "num_threads")}
    )
    got = kissm.batch.register_many(
        synthetic.pairs, synthetic.clouds, preset="lidar-handheld", voxel_size=synthetic.voxel_size, refine="gicp"
    )
    batchcases.assert_same_as_serial(got, synthetic, expected)
    assert all(p.result is not None and p.result.refined for p in got)


def test_describe_many_gives_the_serial_features(synthetic) -> None:
    with kissm.Matcher(voxel_size=synthetic.voxel_size) as matcher:
        expected = {k: matcher.compute_features(v).to_bytes() for k, v in synthetic.clouds.items()}
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        got = kissm.batch.describe_many(synthetic.clouds, pool, voxel_size=synthetic.voxel_size)
    assert list(got) == list(synthetic.clouds)
    for key, features in got.items():
        assert isinstance(features, kissm.Features)
        assert features.to_bytes() == expected[key]


def test_described_clouds_are_not_described_again(synthetic, synthetic_serial, monkeypatch) -> None:
    described = kissm.batch.describe_many(synthetic.clouds, voxel_size=synthetic.voxel_size)
    counter = ComputeCounter(monkeypatch)
    events = Events()
    got = kissm.batch.register_many(synthetic.pairs, described, voxel_size=synthetic.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, synthetic, synthetic_serial)
    assert counter.calls == 0
    assert not events.described()


def test_only_the_clouds_of_the_pairs_are_described(synthetic, monkeypatch) -> None:
    counter = ComputeCounter(monkeypatch)
    got = kissm.batch.register_many([("source", "target1")], synthetic.clouds, voxel_size=synthetic.voxel_size)
    assert counter.calls == 2
    assert len(got) == 1 and got[0].ok


def test_pair_jobs_take_only_features(synthetic) -> None:
    """A pair job cannot describe points itself, so counting describe jobs counts the descriptions."""
    config = kissm.Config(voxel_size=synthetic.voxel_size)
    with pytest.raises(TypeError, match="takes Features, not ndarray"):
        pair_job(config, synthetic.clouds["source"], synthetic.clouds["target0"])


def test_groups_of_pairs_are_guided() -> None:
    """Large groups first, single pairs last, every pair once and in order (what Dask and Ray tasks take)."""
    groups = group_pairs(list(range(40)), 40, 2)
    assert [len(g) for g in groups] == [5, 4, 3, 3, 3, 2, 2, 2, 2] + [1] * 14
    assert [j for g in groups for j in g] == list(range(40))
    groups = group_pairs(list(range(100, 1100)), 1000, 4)
    assert [j for g in groups for j in g] == list(range(100, 1100))
    assert max(len(g) for g in groups) == len(groups[0]) == MAX_PAIRS_PER_TASK
    assert [len(g) for g in groups[-15:]] == [1] * 15
    # Pairs that became ready later (Ray submits them as their clouds are described) count what is left.
    assert [len(g) for g in group_pairs([7, 8, 9], 3, 1)] == [1, 1, 1]
    assert [len(g) for g in group_pairs([1, 2, 3, 4, 5], 64, 0)] == [5]
    assert group_pairs([], 10, 2) == []


def test_sys_getsizeof_counts_the_library_memory(synthetic) -> None:
    """What Dask's memory accounting reads: the features' memory, not a small Python object's."""
    with kissm.Matcher(voxel_size=synthetic.voxel_size) as matcher:
        features = matcher.compute_features(synthetic.clouds["source"])
    assert features.memory_bytes > 10_000
    assert features.memory_bytes < sys.getsizeof(features) < features.memory_bytes + 1_000


# ---- failures are values ------------------------------------------------------------------------------------


def test_failed_clouds_fail_their_pairs_only(synthetic, synthetic_serial, tmp_path) -> None:
    clouds = dict(synthetic.clouds)
    clouds["missing"] = tmp_path / "no-such-scan.ply"
    clouds["tiny"] = synthetic.clouds["source"][: kissm.MIN_POINTS - 1]
    clouds["not-a-cloud"] = kissm.batch.CloudFile(str(Path(__file__)), "xyz")  # Python is no xyz text
    pairs = [*synthetic.pairs, ("missing", "target0"), ("source", "tiny"), ("not-a-cloud", "source")]
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        got = kissm.batch.register_many(pairs, clouds, pool, voxel_size=synthetic.voxel_size)
    n = len(synthetic.pairs)
    batchcases.assert_same_as_serial(got[:n], synthetic, synthetic_serial)
    missing, tiny, garbage = got[n:]
    assert (missing.source, missing.target, missing.result) == ("missing", "target0", None)
    assert type(missing.error) is kissm.IoError and missing.error.status == kissm.IoError.status
    assert missing.error.message.startswith("source: ") and "no-such-scan.ply" in missing.error.message
    assert type(tiny.error) is kissm.TooFewPointsError and tiny.error.message.startswith("target: ")
    assert isinstance(garbage.error, kissm.ParseError) and not garbage.ok


def test_describe_many_and_failures_on_threads(synthetic, tmp_path) -> None:
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        batchcases.assert_describe_many_and_failures(pool, synthetic, tmp_path)


# ---- bad arguments: kissm errors naming them, before any work --------------------------------------------------

BAD_CALLS: list[tuple[str, dict[str, Any], str]] = [
    (
        "unknown key",
        {"pairs": [("source", "target0"), ("source", "nowhere")]},
        r"pairs\[1\] names the target 'nowhere'",
    ),
    ("pair shape", {"pairs": [("source",)]}, r"pairs\[0\] must be a \(source key, target key\) pair"),
    ("pairs type", {"pairs": "source"}, "pairs must be a sequence"),
    ("clouds type", {"clouds": [1, 2]}, "clouds must be a mapping"),
    ("cloud shape", {"clouds": {"source": np.zeros((10, 2)), "target0": np.zeros((10, 3))}}, r"clouds\['source'\]"),
    ("cloud dtype", {"clouds": {"source": np.array([["a", "b", "c"]]), "target0": np.zeros((10, 3))}}, "dtype"),
    ("cloud format", {"clouds": {"source": kissm.batch.CloudFile("a.bin", "e57"), "target0": "b.ply"}}, "format"),
    ("threads", {"threads_per_job": 0}, "threads_per_job must be an int in 1..1024"),
    ("threads bool", {"threads_per_job": True}, "threads_per_job"),
    ("num_threads", {"num_threads": 2}, "pass threads_per_job, not num_threads"),
    (
        "unknown setting",
        {"voxel_sise": 0.5},
        r"unknown keyword argument 'voxel_sise': not a kissm.Config field \(did you mean 'voxel_size'\?\)",
    ),
    ("bad setting", {"voxel_size": -1.0}, "voxel_size"),
    ("bad enum", {"refine": "icp"}, "refine_mode"),
    ("no voxel size", {"voxel_size": None}, r"voxel_size is required: voxel_size=\"auto\" chooses it .*lidar-vehicle"),
    ("preset", {"preset": "car"}, "preset is 'car'"),
    ("executor name", {"executor": "dask"}, "the only name it accepts is 'ray'"),
    ("executor type", {"executor": 4}, "executor must be None, a concurrent.futures.Executor"),
    ("progress", {"progress": 3}, "progress must be True, False, None"),
]


@pytest.mark.parametrize(("case", "change", "message"), BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_bad_arguments_raise_before_any_work(synthetic, monkeypatch, case, change, message) -> None:
    counter = ComputeCounter(monkeypatch)
    arguments: dict[str, Any] = {
        "pairs": [("source", "target0")],
        "clouds": synthetic.clouds,
        "voxel_size": synthetic.voxel_size,
        **change,
    }
    with pytest.raises(kissm.InvalidArgumentError, match=message):
        kissm.batch.register_many(**arguments)
    assert counter.calls == 0


def test_ray_not_started_is_refused(synthetic) -> None:
    ray = pytest.importorskip("ray", reason="Ray (kissm[ray]) is not installed")
    if ray.is_initialized():
        pytest.skip("a Ray runtime is running in this process")
    with pytest.raises(kissm.InvalidArgumentError, match=r"needs a running Ray runtime: call ray.init\(\)"):
        kissm.batch.register_many([("source", "target0")], synthetic.clouds, "ray", voxel_size=synthetic.voxel_size)


# ---- progress ----------------------------------------------------------------------------------------------


def test_progress_events_count_each_stage(synthetic) -> None:
    events = Events()
    got = kissm.batch.register_many(synthetic.pairs, synthetic.clouds, voxel_size=synthetic.voxel_size, progress=events)
    describes = [e for e in events.seen if e.stage == "describe"]
    registers = [e for e in events.seen if e.stage == "register"]
    assert [e.done for e in describes] == list(range(1, len(synthetic.clouds) + 1))
    assert {e.total for e in describes} == {len(synthetic.clouds)}
    assert [e.done for e in registers] == list(range(1, len(synthetic.pairs) + 1))
    assert [e.pair for e in sorted(registers, key=lambda e: e.index)] == got
    assert all(e.key == (e.pair.source, e.pair.target) for e in registers if e.pair is not None)


def test_progress_prints_only_when_asked_or_on_a_terminal(synthetic, capsys, monkeypatch) -> None:
    one = ([("source", "target0")], synthetic.clouds)
    for progress in (None, False):  # pytest's stderr is no terminal
        kissm.batch.register_many(*one, voxel_size=synthetic.voxel_size, progress=progress)
        assert capsys.readouterr() == ("", "")
    monkeypatch.setitem(sys.modules, "tqdm", None)  # the plain line, as without tqdm
    kissm.batch.register_many(*one, voxel_size=synthetic.voxel_size, progress=True)
    out, err = capsys.readouterr()
    assert out == ""
    assert err.endswith("\rkissm.batch: described 2/2 clouds, registered 1/1 pairs\n")


def test_progress_uses_tqdm_when_installed(synthetic, capsys) -> None:
    pytest.importorskip("tqdm", reason="tqdm is not installed")
    kissm.batch.register_many([("source", "target0")], synthetic.clouds, voxel_size=synthetic.voxel_size, progress=True)
    err = capsys.readouterr().err
    assert "kissm.batch: 100%" in err and "registered 1/1 pairs" in err


# ---- the real pairs: all pairs of the KITTI 07 keyframes ------------------------------------------------------


def test_kitti_thread_pool(kitti, kitti_serial, monkeypatch) -> None:
    counter = ComputeCounter(monkeypatch)
    events = Events()
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        got = kissm.batch.register_many(kitti.pairs, kitti.clouds, pool, voxel_size=kitti.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)
    assert counter.calls == len(kitti.clouds)
    assert sum(p.result is not None and p.result.valid for p in got) >= 4  # at least the consecutive keyframes


def test_kitti_spawn_process_pool(kitti, kitti_serial) -> None:
    events = Events()
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=context) as pool:
        got = kissm.batch.register_many(kitti.pairs, kitti.clouds, pool, voxel_size=kitti.voxel_size, progress=events)
    batchcases.assert_same_as_serial(got, kitti, kitti_serial)
    batchcases.assert_each_once(events, kitti)
