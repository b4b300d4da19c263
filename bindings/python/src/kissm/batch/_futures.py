# SPDX-License-Identifier: MIT
"""The batch on a ``concurrent.futures.Executor`` (threads or processes), or on the calling thread.

The driver keeps the features: each cloud is described by one job, and a pair job is submitted as soon as both
of its clouds are described, with the Features themselves (pickled for a process pool, shared for threads).
Features no pair needs any more are dropped at once, and at most a window of pair jobs is in flight, so memory
stays bounded on long pair lists.
"""

from __future__ import annotations

import collections
import concurrent.futures as cf
from collections.abc import Callable
from typing import Any

from .._matcher import Features
from ._jobs import describe_job, pair_job
from ._work import Sink, Work

#: Pair jobs in flight per batch: enough to keep any pool busy, few enough that queued jobs (each holding its
#: pickled features in a process pool) do not pile up.
_WINDOW = 256


class _Here(cf.Executor):
    """Runs each job when it is submitted, on the calling thread (``executor=None``)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future[Any]:
        future: cf.Future[Any] = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as e:  # re-raised by future.result(), as a pool would
            future.set_exception(e)
        return future


def run_here(work: Work, sink: Sink) -> None:
    run_futures(_Here(), work, sink)


def run_futures(executor: cf.Executor, work: Work, sink: Sink) -> None:
    users = work.users()
    uses = [len(u) for u in users]
    described: dict[int, Any] = {}
    pending: dict[cf.Future[Any], tuple[str, int]] = {}
    ready: collections.deque[int] = collections.deque()
    in_flight = 0

    def cloud_done(i: int, value: Any) -> None:
        described[i] = value
        for j in users[i]:
            s, t = work.pairs[j]
            if s in described and t in described:
                ready.append(j)

    try:
        for i, cloud in enumerate(work.inputs):
            if isinstance(cloud, Features):
                cloud_done(i, cloud)
            else:
                pending[executor.submit(describe_job, work.config, cloud)] = ("describe", i)
        while pending or ready:
            while ready and in_flight < _WINDOW:
                j = ready.popleft()
                s, t = work.pairs[j]
                pending[executor.submit(pair_job, work.config, described[s], described[t])] = ("register", j)
                in_flight += 1
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for future in done:
                stage, index = pending.pop(future)
                value = future.result()  # a job raises only for what is not a kissm.Error: a bug, a lost worker
                if stage == "describe":
                    sink.described(index, value)
                    cloud_done(index, value)
                    continue
                in_flight -= 1
                sink.registered(index, value)
                for i in set(work.pairs[index]):
                    uses[i] -= 1
                    if uses[i] == 0:
                        del described[i]  # no pair needs these features any more
    finally:
        for future in pending:
            future.cancel()
