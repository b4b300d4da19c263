# SPDX-License-Identifier: MIT
"""The batch on the running Ray runtime (``executor="ray"``; the extra ``kissm[ray]``, imported only here).

Points held in memory are put in the object store once (``ray.put``) and passed by reference. Features are the
describe tasks' return objects, handed by reference to the pair tasks; Ray reruns a task whose worker died and
rebuilds a lost return object from its task (lineage). Every task asks for ``num_cpus=threads_per_job``, so
Ray packs as many jobs on a node as it has CPUs for.
"""

from __future__ import annotations

from typing import Any

from ._batch_jobs import describe_job, pair_job
from ._batch_values import CloudFile
from ._batch_work import Sink, Work
from ._errors import InvalidArgumentError
from ._matcher import Features

#: Reruns of a task whose worker process died (Ray's default too), and of one that raised something other
#: than a kissm.Error (Ray's default is none: a job that raised because it ran out of memory may pass alone).
_RETRIES = 3


def check_cpus(threads_per_job: int) -> None:
    """A task asking for more CPUs than the cluster has would wait forever: refused before any work."""
    import ray

    cpus = ray.cluster_resources().get("CPU", 0)
    if threads_per_job > cpus:
        raise InvalidArgumentError(
            f"threads_per_job={threads_per_job} but the Ray cluster has {cpus:g} CPUs: its tasks could never start"
        )


def run_ray(work: Work, sink: Sink) -> None:
    import ray

    options = {"num_cpus": work.config.num_threads, "max_retries": _RETRIES, "retry_exceptions": [MemoryError]}
    describe = ray.remote(describe_job).options(**options)
    register = ray.remote(pair_job).options(**options)
    config = ray.put(work.config)
    inputs: list[Any] = [c if isinstance(c, CloudFile) else ray.put(c) for c in work.inputs]
    stage: dict[Any, tuple[str, int]] = {}
    described: list[Any] = []
    for i, cloud in enumerate(work.inputs):
        if isinstance(cloud, Features):
            described.append(inputs[i])  # described before: in the object store as they are
            continue
        described.append(describe.remote(config, inputs[i]))
        stage[described[-1]] = ("describe", i)
    uses = [len(u) for u in work.users()]
    for j, (s, t) in enumerate(work.pairs):
        stage[register.remote(config, described[s], described[t])] = ("register", j)
    pending = list(stage)
    while pending:
        done, pending = ray.wait(pending, num_returns=1)
        # Whatever else finished meanwhile, without waiting (one call per job would be quadratic in the pairs).
        more, pending = ray.wait(pending, num_returns=len(pending), timeout=0) if pending else ([], [])
        for ref in done + more:
            kind, index = stage.pop(ref)
            if kind == "describe":
                sink.described(index, ray.get(ref) if work.keep_features else None)
                continue
            sink.registered(index, ray.get(ref))
            for i in set(work.pairs[index]):
                uses[i] -= 1
                if uses[i] == 0:
                    described[i] = inputs[i] = None  # the object store may free them
