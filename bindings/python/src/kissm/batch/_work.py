# SPDX-License-Identifier: MIT
"""A batch as the engines see it: the distinct clouds to describe, the pairs as indices into them, and the sink
that collects what the jobs return (in input order, whatever order they finish in)."""

from __future__ import annotations

import dataclasses
from collections.abc import Hashable

from .._config import Config
from .._errors import Error
from .._matcher import Features
from .._result import Result
from ._args import Checked
from ._progress import Reporter
from ._values import PairResult

#: At most this many pairs in one task of a Dask or Ray batch.
MAX_PAIRS_PER_TASK = 8


def group_pairs(ready: list[int], remaining: int, slots: int) -> list[list[int]]:
    """Splits the pairs ``ready`` to run (in their order) into tasks, for an engine that pays a fixed cost per
    task (scheduling, messages, moving the features; on Dask about a tenth of a LiDAR pair's matching).

    Guided, as loops are split among threads: a task takes a quarter of the share of each of the ``slots`` (jobs
    the cluster runs at once) of the ``remaining`` pairs (those not yet in a task, ``ready`` included), between
    1 and :data:`MAX_PAIRS_PER_TASK`. The first tasks are the largest and the last ones single pairs, so that
    the slots still finish together. A grouping changes no result: each pair is registered on its own."""
    out: list[list[int]] = []
    i = 0
    while i < len(ready):
        size = max(1, min(MAX_PAIRS_PER_TASK, remaining // (4 * max(1, slots))))
        out.append(ready[i : i + size])
        i += size
        remaining -= size
    return out


def task_clouds(work: Work, group: list[int]) -> tuple[list[int], list[tuple[int, int]]]:
    """The distinct clouds of a group of pairs, and each pair as indices into that list (see pairs_job)."""
    clouds = sorted({i for j in group for i in work.pairs[j]})
    at = {c: n for n, c in enumerate(clouds)}
    return clouds, [(at[work.pairs[j][0]], at[work.pairs[j][1]]) for j in group]


@dataclasses.dataclass
class Work:
    config: Config
    keys: list[Hashable]
    """The distinct clouds, in order of first use."""
    inputs: list[Checked]
    """Per cloud: points, a CloudFile, or Features given already described (no describe job)."""
    pairs: list[tuple[int, int]]
    """Per pair: the indices of its source and target in ``keys``."""
    keep_features: bool
    """Whether the features come back to the caller (describe_many) or stay with the engine."""

    def users(self) -> list[list[int]]:
        """Per cloud, the pairs that use it (a pair of a cloud with itself once)."""
        users: list[list[int]] = [[] for _ in self.keys]
        for j, (s, t) in enumerate(self.pairs):
            users[s].append(j)
            if t != s:
                users[t].append(j)
        return users


class Sink:
    """Where the engines put what finished; tells the reporter about each job."""

    def __init__(self, work: Work, reporter: Reporter) -> None:
        self._work = work
        self._reporter = reporter
        self.features: list[Features | Error | None] = [None] * len(work.keys)
        self.pairs: list[PairResult | None] = [None] * len(work.pairs)

    def described(self, i: int, value: Features | Error | None) -> None:
        """Cloud ``i`` was described (``value`` is None when the engine keeps it)."""
        if self._work.keep_features:
            self.features[i] = value
        self._reporter.described(self._work.keys[i], i)

    def registered(self, j: int, value: Result | Error) -> None:
        s, t = self._work.pairs[j]
        source, target = self._work.keys[s], self._work.keys[t]
        if isinstance(value, Error):
            pair = PairResult(source, target, None, value)
        elif isinstance(value, Result):
            pair = PairResult(source, target, value, None)
        else:
            raise TypeError(f"a kissm.batch pair job returned {type(value).__name__}")  # a bug of this module
        self.pairs[j] = pair
        self._reporter.registered(j, pair)
