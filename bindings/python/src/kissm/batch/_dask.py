# SPDX-License-Identifier: MIT
"""The batch on a Dask cluster (``distributed.Client``; the extra ``kissm[dask]``, imported only here).

Points held in memory are scattered once, straight to the workers, not shipped with each task. Features are the
describe tasks' results and stay on the workers, where Dask hands them to the pair tasks that need them. A pair
task registers a group of pairs (kissm.batch._work.group_pairs): Dask's cost per task, on its scheduler and its
workers, is about a tenth of matching two LiDAR keyframes.

When a worker dies, Dask reruns the tasks that ran there and recomputes the lost results from their inputs, but
it cannot recompute scattered data: the points that only the dead worker held are gone, and the tasks that need
them are cancelled. Replicating the scattered points would not help for long (the scheduler's active memory
manager drops the extra copies within seconds), so the driver, which still has the points, scatters the lost
clouds again, describes them again and resubmits the cancelled pairs.
"""

from __future__ import annotations

import time
import uuid
from typing import Any

from .._matcher import Features
from ._jobs import describe_job, pairs_job
from ._values import CloudFile
from ._work import Sink, Work, group_pairs, task_clouds

#: Reruns of a task that raised something other than a kissm.Error (a worker lost to a memory limit shows up
#: as such). Dask reruns the tasks of a worker that died on its own (its ``allowed-failures`` setting).
_RETRIES = 2

#: Pair tasks submitted and not yet finished, at most (each of up to MAX_PAIRS_PER_TASK pairs).
_IN_FLIGHT = 1024

#: Times the driver resubmits one task whose inputs were lost with their workers, before giving up.
_RESUBMITS = 3

#: Tries of one scatter whose connection closed (a worker dying or restarting), and the pause before the next try
#: (times the try's number), seconds.
_SCATTER_TRIES = 5
_SCATTER_PAUSE_S = 0.5


class _Cluster:
    """The batch's tasks on one client: one describe task per cloud (again only after a loss), one per group of
    pairs."""

    def __init__(self, client: Any, work: Work) -> None:
        self.client = client
        self.work = work
        self.batch = f"kissm-{uuid.uuid4().hex[:12]}"  # task keys name the batch and the job (dashboards)
        self.stage: dict[str, tuple[str, int]] = {}
        self.described: list[Any] = [None] * len(work.keys)
        self.attempts = 0
        self.submits = 0
        self.slots = sum(client.nthreads().values()) if work.pairs else 0
        self.groups = group_pairs(list(range(len(work.pairs))), len(work.pairs), self.slots)

    def describe(self, clouds: list[int]) -> list[Any]:
        """Submit the describe tasks of ``clouds`` (scattering the points held in memory); their futures."""
        self.attempts += 1
        inputs: dict[int, Any] = {i: self.work.inputs[i] for i in clouds}
        in_memory = [i for i in clouds if not isinstance(inputs[i], CloudFile)]
        holders: dict[Any, Any] = {}
        if in_memory:
            scattered, holders = self._scatter([inputs[i] for i in in_memory])
            inputs.update(zip(in_memory, scattered, strict=True))
        workers = sorted(self.client.scheduler_info().get("workers", {}))
        new = []
        for n, i in enumerate(clouds):
            if isinstance(self.work.inputs[i], Features):
                self.described[i] = inputs[i]  # described before: scattered as they are, no describe task
                continue
            # A describe task goes before any pair task, and is placed (loosely: another worker takes it if that
            # one is gone) where its points are, or in turn on the workers for files. Otherwise the pairs of
            # the clouds described first keep every worker busy while the pairs that need the last clouds wait:
            # a worker runs the tasks of one priority last come first, and an unplaced describe of a batch of
            # more clouds than twice the cluster's threads is held in the scheduler until a worker is idle.
            place = list(holders.get(getattr(inputs[i], "key", None), ())) or workers[n % len(workers) :][:1]
            key = f"{self.batch}-describe-{i}-{self.attempts}"
            self.described[i] = self.client.submit(
                describe_job,
                self.work.config,
                inputs[i],
                key=key,
                pure=False,
                retries=_RETRIES,
                workers=place or None,
                allow_other_workers=True,
                priority=1,
            )
            self.stage[key] = ("describe", i)
            new.append(self.described[i])
        return new

    def _scatter(self, values: list[Any]) -> tuple[list[Any], dict[Any, Any]]:
        """Scatter ``values``; their futures and who holds them. After a loss the scatter can meet a worker that is
        dying or restarting (its connection closes mid-transfer): it is tried again, on the workers then alive."""
        for attempt in range(_SCATTER_TRIES):
            try:
                scattered = self.client.scatter(values, hash=False)
                return scattered, self.client.who_has(scattered)
            except OSError:  # distributed's CommClosedError is one
                if attempt + 1 == _SCATTER_TRIES:
                    raise
                time.sleep(_SCATTER_PAUSE_S * (attempt + 1))
        raise AssertionError("not reached")

    def register(self, g: int) -> Any:
        """Submit the task of group ``g`` of pairs; its future."""
        clouds, pairs = task_clouds(self.work, self.groups[g])
        self.submits += 1
        key = f"{self.batch}-register-{self.groups[g][0]}-{self.submits}"
        self.stage[key] = ("register", g)
        features = [self.described[i] for i in clouds]
        return self.client.submit(pairs_job, self.work.config, features, pairs, key=key, pure=False, retries=_RETRIES)


def run_dask(client: Any, work: Work, sink: Sink) -> None:
    import distributed

    cluster = _Cluster(client, work)
    futures = cluster.describe(list(range(len(work.keys))))
    # At most _IN_FLIGHT pair tasks at a time, the next as one finishes: a batch of millions of pairs is not
    # millions of tasks on the scheduler at once. Enough that Dask sees the whole of an ordinary batch (its work
    # stealing balances the workers, and an adaptive cluster scales to the work it sees).
    submitted = min(_IN_FLIGHT, len(cluster.groups))
    futures += [cluster.register(g) for g in range(submitted)]
    uses = [len(u) for u in work.users()]
    resubmits = [0] * len(work.keys) if work.keep_features else [0] * len(cluster.groups)
    reported: set[int] = set()
    redescribed: set[str] = set()  # the describe tasks submitted again after a loss
    completed = distributed.as_completed(futures)
    del futures  # from here on the tasks, `described` and `completed` hold the data, and no longer than needed

    def describe_again(clouds: list[int]) -> None:
        for new in cluster.describe(clouds):
            redescribed.add(new.key)
            completed.add(new)

    for future in completed:
        kind, index = cluster.stage.pop(future.key)
        try:
            value: Any = None
            if kind == "describe" and not work.keep_features and future.status == "finished":
                pass  # the features stay on the cluster for the pair tasks: gathered here, they would be moved
                # to the driver and loaded there, for nothing
            else:
                value = future.result()  # the job's value; its exception if it raised; cancelled if it was lost
        except distributed.client.FutureCancelledError:
            # Its inputs were lost with a worker. In register_many a cancelled describe's pairs are cancelled too
            # and bring it back with them; describe_many has no pairs, so the describe itself comes back.
            if kind == "describe" and not work.keep_features:
                continue
            if resubmits[index] >= _RESUBMITS:
                raise  # lost again and again: given up
            resubmits[index] += 1
            if kind == "describe":
                describe_again([index])
                continue
            # A cloud is described again unless its features are there or already coming again.
            stale = [
                i
                for i in task_clouds(work, cluster.groups[index])[0]
                if _lost(cluster.described[i])
                or (cluster.described[i].status != "finished" and cluster.described[i].key not in redescribed)
            ]
            describe_again(stale)
            completed.add(cluster.register(index))
            continue
        if kind == "describe":
            if index not in reported:  # a cloud described again after a loss is reported once
                reported.add(index)
                sink.described(index, value if work.keep_features else None)
            continue
        if submitted < len(cluster.groups):
            completed.add(cluster.register(submitted))
            submitted += 1
        for j, result in zip(cluster.groups[index], value, strict=True):
            sink.registered(j, result)
            for i in set(work.pairs[j]):
                uses[i] -= 1
                if uses[i] == 0:
                    cluster.described[i] = None  # the cluster may forget these features: no pair needs them now


def _lost(future: Any) -> bool:
    return future is None or future.status in ("cancelled", "lost", "error")
