# SPDX-License-Identifier: MIT
"""The batch on a Dask cluster (``distributed.Client``; the extra ``kissm[dask]``, imported only here).

Points held in memory are scattered once, not shipped with each task, and replicated on two workers: data
scattered to a single worker is lost with it and, unlike a task's result, cannot be recomputed. Features are
task results that stay on the workers: Dask hands them to the pair tasks that depend on them and, when a worker
dies, recomputes from the scattered points whatever was lost, and reruns the tasks that were running there.
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

#: Workers that hold each scattered cloud.
_REPLICAS = 2


def run_dask(client: Any, work: Work, sink: Sink) -> None:
    import distributed

    # Task keys name the batch and the job, so a cluster's dashboard and task stream show what runs.
    batch = f"kissm-{uuid.uuid4().hex[:12]}"
    in_memory = [i for i, cloud in enumerate(work.inputs) if not isinstance(cloud, CloudFile)]
    inputs: list[Any] = list(work.inputs)
    if in_memory:
        scattered = client.scatter([work.inputs[i] for i in in_memory], hash=False)
        workers = len(client.scheduler_info()["workers"])
        if workers > 1:
            client.replicate(scattered, n=min(_REPLICAS, workers))
        for i, future in zip(in_memory, scattered, strict=True):
            inputs[i] = future
        del scattered
    stage: dict[str, tuple[str, int]] = {}
    described: list[Any] = []
    futures: list[Any] = []
    for i, cloud in enumerate(work.inputs):
        if isinstance(cloud, Features):
            described.append(inputs[i])  # described before: scattered as they are, no describe task
            continue
        key = f"{batch}-describe-{i}"
        described.append(client.submit(describe_job, work.config, inputs[i], key=key, pure=False, retries=_RETRIES))
        futures.append(described[-1])
        stage[key] = ("describe", i)
    uses = [len(u) for u in work.users()]
    for j, (s, t) in enumerate(work.pairs):
        key = f"{batch}-register-{j}"
        futures.append(
            client.submit(pair_job, work.config, described[s], described[t], key=key, pure=False, retries=_RETRIES)
        )
        stage[key] = ("register", j)
    # A cloud's points and features are held here until its last pair is done: should a worker die with the
    # features, Dask needs the points to compute them again. After that the cluster may forget both.
    completed = distributed.as_completed(futures)
    del futures
    for future in completed:
        kind, index = stage[future.key]
        if kind == "describe":
            sink.described(index, future.result() if work.keep_features else None)
            continue
        sink.registered(index, future.result())
        for i in set(work.pairs[index]):
            uses[i] -= 1
            if uses[i] == 0:
                described[i] = inputs[i] = None
