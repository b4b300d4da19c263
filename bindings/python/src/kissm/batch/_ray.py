# SPDX-License-Identifier: MIT
"""The batch on the running Ray runtime (``executor="ray"``; the extra ``kissm[ray]``, imported only here).

Points held in memory are put in the object store once (``ray.put``) and passed by reference. Features are the
describe tasks' return objects, handed by reference to the pair tasks; Ray reruns a task whose worker died and
rebuilds a lost return object from its task (lineage). Every task asks for ``num_cpus=threads_per_job``, so
Ray packs as many jobs on a node as it has CPUs for.

Ray would load (unpickle) both features of every pair task from the object store, and loading a keyframe's
features (checking its bytes, rebuilding its search indexes) costs a tenth of matching two of them. So a pair
task gets its features' references in a list, which Ray hands over as they are, and each worker process keeps
the last few features it loaded, by object id: a cloud in many pairs is loaded about once per worker. The cache
holds the loaded features, not their references, so the object store still frees them when the batch drops them.
A pair task registers a group of pairs (kissm.batch._work.group_pairs), which Ray's cost per task asks for too.
"""

from __future__ import annotations

import collections
import threading
from typing import Any

from .._errors import InvalidArgumentError
from .._matcher import Features
from ._jobs import describe_job, pairs_job
from ._values import CloudFile
from ._work import Sink, Work, group_pairs, task_clouds

#: Reruns of a task whose worker process died (Ray's default too), and of one that raised something other
#: than a kissm.Error (Ray's default is none: a job that raised because it ran out of memory may pass alone).
_RETRIES = 3


#: The worker cache: at most this many loaded features, and this many bytes of them (Features.memory_bytes),
#: least recently used first out. A cloud too large for the budget is loaded for each pair that uses it.
_CACHE_ENTRIES = 8
_CACHE_BYTES = 1 << 30

_cache: collections.OrderedDict[str, Features] = collections.OrderedDict()
_cache_lock = threading.Lock()


def _load(ref: Any) -> Any:
    """The value of the object reference ``ref`` (Features, or a describe job's kissm.Error), through this
    worker's cache."""
    import ray

    key = ref.hex()
    with _cache_lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
    value = ray.get(ref)
    if isinstance(value, Features) and value.memory_bytes <= _CACHE_BYTES:
        with _cache_lock:
            _cache[key] = value
            while len(_cache) > _CACHE_ENTRIES or sum(f.memory_bytes for f in _cache.values()) > _CACHE_BYTES:
                _cache.popitem(last=False)
    return value


def cached_pairs_job(config: Any, features: list[Any], pairs: list[tuple[int, int]]) -> Any:
    """:func:`pairs_job` on the features of the object references ``features``, loaded through the worker's
    cache."""
    return pairs_job(config, [_load(ref) for ref in features], pairs)


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
    register = ray.remote(cached_pairs_job).options(**options)
    slots = int(ray.cluster_resources().get("CPU", 1)) // work.config.num_threads
    config = ray.put(work.config)
    inputs: list[Any] = [c if isinstance(c, CloudFile) else ray.put(c) for c in work.inputs]
    stage: dict[Any, tuple[str, list[int]]] = {}
    described: list[Any] = []
    users = work.users()
    uses = [len(u) for u in users]
    ready: set[int] = set()
    unsubmitted = len(work.pairs)

    def cloud_ready(i: int) -> list[Any]:
        """Submits the pairs that cloud ``i`` completes. Only then: a pair task holds its features' references
        in a list, which Ray does not wait for, and one that blocked on an unfinished describe would give its
        CPU back to Ray (which starts more worker processes to use it)."""
        nonlocal unsubmitted
        ready.add(i)
        now = [j for j in users[i] if work.pairs[j][0] in ready and work.pairs[j][1] in ready]
        new = []
        for group in group_pairs(now, unsubmitted, slots):
            clouds, pairs = task_clouds(work, group)
            new.append(register.remote(config, [described[c] for c in clouds], pairs))
            stage[new[-1]] = ("register", group)
            unsubmitted -= len(group)
        return new

    for i, cloud in enumerate(work.inputs):
        if isinstance(cloud, Features):
            described.append(inputs[i])  # described before: in the object store as they are
            continue
        described.append(describe.remote(config, inputs[i]))
        stage[described[-1]] = ("describe", [i])
    pending = list(stage)
    for i, cloud in enumerate(work.inputs):
        if isinstance(cloud, Features):
            pending += cloud_ready(i)
    while pending:
        done, pending = ray.wait(pending, num_returns=1)
        # Whatever else finished meanwhile, without waiting (one call per job would be quadratic in the pairs).
        more, pending = ray.wait(pending, num_returns=len(pending), timeout=0) if pending else ([], [])
        for ref in done + more:
            kind, indices = stage.pop(ref)
            if kind == "describe":
                sink.described(indices[0], ray.get(ref) if work.keep_features else None)
                pending += cloud_ready(indices[0])
                continue
            for j, result in zip(indices, ray.get(ref), strict=True):
                sink.registered(j, result)
                for i in set(work.pairs[j]):
                    uses[i] -= 1
                    if uses[i] == 0:
                        described[i] = inputs[i] = None  # the object store may free them
