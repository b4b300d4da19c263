# SPDX-License-Identifier: MIT
"""The batch on a Dask cluster (``distributed.Client``; the extra ``kissm[dask]``, imported only here).

Points held in memory are scattered once, straight to the workers, not shipped with each task. Features are the
describe tasks' results and stay on the workers, where Dask hands them to the pair tasks that need them.

When a worker dies, Dask reruns the tasks that ran there and recomputes the lost results from their inputs, but
it cannot recompute scattered data: the points that only the dead worker held are gone, and the tasks that need
them are cancelled. Replicating the scattered points would not help for long (the scheduler's active memory
manager drops the extra copies within seconds), so the driver, which still has the points, scatters the lost
clouds again, describes them again and resubmits the cancelled pairs.
"""

from __future__ import annotations

import uuid
from typing import Any

from ._batch_jobs import describe_job, pair_job
from ._batch_values import CloudFile
from ._batch_work import Sink, Work
from ._matcher import Features

#: Reruns of a task that raised something other than a kissm.Error (a worker lost to a memory limit shows up
#: as such). Dask reruns the tasks of a worker that died on its own (its ``allowed-failures`` setting).
_RETRIES = 2

#: Times the driver resubmits one pair whose inputs were lost with their workers, before giving up.
_RESUBMITS = 3


class _Cluster:
    """The batch's tasks on one client: one describe task per cloud (again only after a loss), one per pair."""

    def __init__(self, client: Any, work: Work) -> None:
        self.client = client
        self.work = work
        self.batch = f"kissm-{uuid.uuid4().hex[:12]}"  # task keys name the batch and the job (dashboards)
        self.stage: dict[str, tuple[str, int]] = {}
        self.described: list[Any] = [None] * len(work.keys)
        self.attempts = 0

    def describe(self, clouds: list[int]) -> list[Any]:
        """Submit the describe tasks of ``clouds`` (scattering the points held in memory); their futures."""
        self.attempts += 1
        inputs: dict[int, Any] = {i: self.work.inputs[i] for i in clouds}
        in_memory = [i for i in clouds if not isinstance(inputs[i], CloudFile)]
        if in_memory:
            scattered = self.client.scatter([inputs[i] for i in in_memory], hash=False)
            inputs.update(zip(in_memory, scattered, strict=True))
        new = []
        for i in clouds:
            if isinstance(self.work.inputs[i], Features):
                self.described[i] = inputs[i]  # described before: scattered as they are, no describe task
                continue
            key = f"{self.batch}-describe-{i}-{self.attempts}"
            self.described[i] = self.client.submit(
                describe_job, self.work.config, inputs[i], key=key, pure=False, retries=_RETRIES
            )
            self.stage[key] = ("describe", i)
            new.append(self.described[i])
        return new

    def register(self, j: int) -> Any:
        s, t = self.work.pairs[j]
        key = f"{self.batch}-register-{j}-{self.attempts}"
        self.stage[key] = ("register", j)
        return self.client.submit(
            pair_job, self.work.config, self.described[s], self.described[t], key=key, pure=False, retries=_RETRIES
        )


def run_dask(client: Any, work: Work, sink: Sink) -> None:
    import distributed

    cluster = _Cluster(client, work)
    futures = cluster.describe(list(range(len(work.keys))))
    futures += [cluster.register(j) for j in range(len(work.pairs))]
    uses = [len(u) for u in work.users()]
    resubmits = [0] * len(work.keys) if work.keep_features else [0] * len(work.pairs)
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
            value = future.result()
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
                for i in sorted(set(work.pairs[index]))
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
        sink.registered(index, value)
        for i in set(work.pairs[index]):
            uses[i] -= 1
            if uses[i] == 0:
                cluster.described[i] = None  # the cluster may forget these features: no pair needs them now


def _lost(future: Any) -> bool:
    return future is None or future.status in ("cancelled", "lost", "error")
