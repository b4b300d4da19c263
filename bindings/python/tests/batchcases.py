# SPDX-License-Identifier: MIT
"""The batches the kissm.batch tests run on every engine, the serial loop they must equal bit for bit, and a
recorder of the progress events that shows which jobs ran."""

from __future__ import annotations

import collections
import itertools
import threading
from collections.abc import Hashable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import kissm
import kissm.batch

import testdata
from helpers import TIME_FIELDS, assert_same_result
from realdata import read_cached

#: The KITTI 07 keyframes of the real data, registered at 0.5 m voxels (as the C real-data test does).
KITTI = "kitti07_keyframes_gtsam_points"
KITTI_VOXEL = 0.5
KITTI_FORMAT = "bin_xyz_f32"

#: A result's fields that may differ between identical calls.
TIMES = TIME_FIELDS | {"time_suppression_ms"}


@dataclass
class Batch:
    clouds: dict[Hashable, Any]
    pairs: list[tuple[Hashable, Hashable]]
    voxel_size: float


def kitti_batch(root: Path) -> Batch:
    """Every pair of the five keyframes (later scan as source); three as arrays, two as files read on the
    workers, so both ways in are exercised on every engine."""
    frames = sorted(p.name for p in (root / KITTI).iterdir() if (p / "points.bin").is_file())
    assert len(frames) >= 5, f"{root / KITTI}: expected 5 keyframes, found {frames}"
    clouds: dict[Hashable, Any] = {}
    for n, frame in enumerate(frames):
        path = root / KITTI / frame / "points.bin"
        clouds[frame] = kissm.batch.CloudFile(str(path), KITTI_FORMAT) if n % 2 else read_cached(path, KITTI_FORMAT)
    pairs = [(later, earlier) for earlier, later in itertools.combinations(frames, 2)]
    return Batch(clouds, pairs, KITTI_VOXEL)


def synthetic_batch() -> Batch:
    """The committed pair's target and the four variations' targets and sources, in a ring of pairs: no real
    data needed."""
    base = testdata.committed_pair()
    clouds: dict[Hashable, Any] = {"source": base.source}
    for n, variation in enumerate(testdata.variations(base)):
        clouds[f"target{n}"] = variation.target
    pairs: list[tuple[Hashable, Hashable]] = [("source", f"target{n}") for n in range(4)]
    pairs += [("target1", "target2"), ("target3", "target0")]
    return Batch(clouds, pairs, testdata.VOXEL_SIZE)


def repeated(batch: Batch, times: int) -> Batch:
    """The batch with its pair list repeated: enough pairs that Dask and Ray group several in one task."""
    return Batch(batch.clouds, batch.pairs * times, batch.voxel_size)


def points(cloud: Any) -> Any:
    if isinstance(cloud, kissm.batch.CloudFile):
        return kissm.read_points(cloud.path, cloud.format)
    return cloud


def serial(batch: Batch, **config: Any) -> list[kissm.Result]:
    """The loop kissm.batch must equal: each cloud described once, each pair from the features."""
    with kissm.Matcher(voxel_size=batch.voxel_size, **config) as matcher:
        features = {key: matcher.compute_features(points(cloud)) for key, cloud in batch.clouds.items()}
        return [matcher.register_features(features[s], features[t]) for s, t in batch.pairs]


def assert_same_as_serial(got: list[kissm.batch.PairResult], batch: Batch, expected: list[kissm.Result]) -> None:
    assert [(p.source, p.target) for p in got] == batch.pairs  # input order
    for pair, want in zip(got, expected, strict=True):
        assert pair.error is None, f"{pair.source}->{pair.target}: {pair.error!r}"
        assert pair.result is not None
        assert_same_result(pair.result, want, ignore=TIMES)


@dataclass
class Events:
    """A ``progress`` callable recording every event (the driver calls it from one thread)."""

    seen: list[kissm.batch.Progress] = field(default_factory=list)

    def __call__(self, event: kissm.batch.Progress) -> None:
        self.seen.append(event)

    def described(self) -> collections.Counter[Hashable]:
        return collections.Counter(e.key for e in self.seen if e.stage == "describe")

    def registered(self) -> collections.Counter[int]:
        return collections.Counter(e.index for e in self.seen if e.stage == "register")


class ComputeCounter:
    """Counts Matcher.compute_features calls in this process (threads of a pool included)."""

    def __init__(self, monkeypatch: Any) -> None:
        self.calls = 0
        self._lock = threading.Lock()
        original = kissm.Matcher.compute_features

        def counted(matcher: kissm.Matcher, cloud: Any) -> kissm.Features:
            with self._lock:
                self.calls += 1
            return original(matcher, cloud)

        monkeypatch.setattr(kissm.Matcher, "compute_features", counted)


def assert_each_once(events: Events, batch: Batch) -> None:
    """One describe event per distinct cloud, one register event per pair: no cloud described twice."""
    used = {key for pair in batch.pairs for key in pair}
    assert events.described() == collections.Counter(used)
    assert events.registered() == collections.Counter(range(len(batch.pairs)))


def assert_describe_many_and_failures(executor: Any, batch: Batch, tmp_path: Path) -> None:
    """describe_many gives the serial features bit for bit, and the errors of a missing file and of a tiny cloud
    as values; register_many fails only the pairs of those clouds, saying which side failed."""
    clouds = {**batch.clouds, "missing": str(tmp_path / "gone.ply"), "tiny": points(batch.clouds["source"])[:3]}
    described = kissm.batch.describe_many(clouds, executor, voxel_size=batch.voxel_size)
    assert list(described) == list(clouds)
    assert type(described["missing"]) is kissm.IoError
    assert type(described["tiny"]) is kissm.TooFewPointsError
    with kissm.Matcher(voxel_size=batch.voxel_size) as matcher:
        for key, cloud in batch.clouds.items():
            features = described[key]
            assert isinstance(features, kissm.Features)
            assert features.to_bytes() == matcher.compute_features(points(cloud)).to_bytes()
    pairs = [("source", "target0"), ("missing", "source"), ("source", "tiny")]
    good, missing, tiny = kissm.batch.register_many(pairs, clouds, executor, voxel_size=batch.voxel_size)
    assert good.ok and good.result is not None
    assert type(missing.error) is kissm.IoError and missing.error.message.startswith("source: ")
    assert type(tiny.error) is kissm.TooFewPointsError and tiny.error.message.startswith("target: ")
