# SPDX-License-Identifier: MIT
"""The jobs of ``kissm.batch``, as module-level functions so that every engine (a process pool, Dask, Ray) can
pickle them by reference: describe one cloud, register one pair of described clouds, or several pairs in one task.

A job returns a library failure as its value instead of raising it, so that the engines carry it back like a
result and one bad cloud or pair cannot abort the others. Anything else (a bug, a lost worker) still raises.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence

import numpy as np

from .._config import Config
from .._errors import Error
from .._matcher import Features, Matcher
from .._read import read_points
from .._result import Result
from ._values import CloudFile

#: What a describe job reads: points already in memory, or a file to read where the job runs.
CloudInput = np.ndarray | CloudFile

# One Matcher per thread and settings: a job reuses its thread's matcher (its worker threads and buffers)
# instead of creating one per job, and two threads never share one (a Matcher serialises its calls).
_local = threading.local()


def _matcher(config: Config) -> Matcher:
    cache: dict[Config, Matcher] | None = getattr(_local, "matchers", None)
    if cache is None:
        cache = _local.matchers = {}
    matcher = cache.get(config)
    if matcher is None:
        if len(cache) >= 4:  # a worker serving several batches of other settings keeps only the last few
            cache.pop(next(iter(cache))).close()
        matcher = cache[config] = Matcher(config)
    return matcher


def describe_job(config: Config, cloud: CloudInput) -> Features | Error:
    """The features of ``cloud`` under ``config``, or the :class:`kissm.Error` that prevented them (an
    unreadable file, too few points...)."""
    try:
        points = read_points(cloud.path, cloud.format) if isinstance(cloud, CloudFile) else cloud
        return _matcher(config).compute_features(points)
    except Error as e:
        return e


def pair_job(config: Config, source: Features | Error, target: Features | Error) -> Result | Error:
    """``source`` registered against ``target`` (both described by :func:`describe_job`), or the
    :class:`kissm.Error` of the cloud that could not be described, or of the registration.

    Only features are accepted, never points: a pair job cannot describe a cloud again behind the batch's back.
    """
    for side, value in (("source", source), ("target", target)):
        if isinstance(value, Error):
            # The cloud's own error class (and status), its message saying which side of the pair it was.
            return type(value)(f"{side}: {value.message}")
        if not isinstance(value, Features):
            raise TypeError(f"a kissm.batch pair job takes Features, not {type(value).__name__} ({side})")
    assert isinstance(source, Features) and isinstance(target, Features)  # for mypy: checked just above
    try:
        return _matcher(config).register_features(source, target)
    except Error as e:
        return e


def pairs_job(
    config: Config, features: Sequence[Features | Error], pairs: Sequence[tuple[int, int]]
) -> list[Result | Error]:
    """:func:`pair_job` for each ``(s, t)`` of ``pairs``, indices into ``features``: several pairs in one task,
    for the engines that pay a fixed cost per task (a cloud in several of them is moved once)."""
    return [pair_job(config, features[s], features[t]) for s, t in pairs]
