# SPDX-License-Identifier: MIT
"""Many pairs, many machines: describe each distinct cloud once, register every pair from the features, on the
calling thread, a ``concurrent.futures`` pool, a Dask cluster or a Ray cluster::

    import kissm.batch

    clouds = {"a": a_xyz, "b": "scans/b.ply", "c": kissm.batch.CloudFile("c.bin", "bin_xyz_f32")}
    pairs = [("b", "a"), ("c", "a"), ("c", "b")]
    for pair in kissm.batch.register_many(pairs, clouds, executor=pool, voxel_size=0.5):
        if pair.error is None and pair.result.valid:
            print(pair.source, pair.target, pair.result.transform)

Results are bitwise identical to the serial loop (``Matcher.compute_features`` once per cloud, then
``Matcher.register_features`` per pair) on every engine, whatever ``threads_per_job``; only the times differ.
A pair that fails (an unreadable file, a cloud with too few points) is a :class:`PairResult` whose ``error``
is the :class:`kissm.Error`: the other pairs go on. Arguments are checked before any work starts; a bad one
raises :class:`kissm.InvalidArgumentError` naming it. docs/batch.md has the clusters and the memory per job.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from typing import Any

from .._config import Config, RefineMode
from .._errors import Error, InternalError
from .._matcher import Features
from ._args import batch_config, check_cloud, check_clouds, check_pairs, engine_name, set_voxel_size
from ._progress import Reporter, check_progress
from ._values import CloudFile, PairResult, Progress
from ._work import Sink, Work

ProgressLike = bool | None | Callable[[Progress], object]
"""What ``progress`` accepts: True (a bar on stderr: tqdm's if installed), False, None (a bar only when stderr is a
terminal), or a callable called with a :class:`Progress` after each job."""


def _run(executor: Any, work: Work, progress: ProgressLike) -> Sink:
    engine = engine_name(executor)  # checks it (Ray running, Dask client open) before any work
    check_progress(progress)
    if engine == "ray":
        from ._ray import check_cpus

        check_cpus(work.config.num_threads)
    reporter = Reporter(progress, sum(not isinstance(c, Features) for c in work.inputs), len(work.pairs))
    sink = Sink(work, reporter)
    try:
        if engine == "here":
            from ._futures import run_here

            run_here(work, sink)
        elif engine == "futures":
            from ._futures import run_futures

            run_futures(executor, work, sink)
        elif engine == "dask":
            from ._dask import run_dask

            run_dask(executor, work, sink)
        else:
            from ._ray import run_ray

            run_ray(work, sink)
    finally:
        reporter.close()
    return sink


# describe_many and register_many take the same keyword-only settings, written out in both signatures so that type
# checkers and help() show them; what they mean is stated once, in register_many's docstring, and
# test_describe_many_and_register_many_take_the_same_settings keeps the two lists equal. Both hand them to
# batch_config unchanged.
def describe_many(
    clouds: Mapping[Hashable, Any],
    executor: Any = None,
    *,
    threads_per_job: int = 1,
    progress: ProgressLike = None,
    voxel_size: float | None = None,
    refine: RefineMode | int | None = None,
    preset: str | None = None,
    config: Config | None = None,
    **overrides: Any,
) -> dict[Hashable, Features | Error]:
    """The :class:`kissm.Features` of every cloud, each described by one job on ``executor`` (see
    :func:`register_many` for ``clouds``, ``executor``, ``threads_per_job``, ``progress`` and the settings).

    Returns a dict in the order of ``clouds``: each key's Features, or the :class:`kissm.Error` that prevented
    them (``isinstance(value, kissm.Error)``). The features come back to the calling process; give them to
    :func:`register_many` as clouds (already described, they are not described again), or save them with
    :meth:`kissm.Features.to_bytes`.

    Raises:
        kissm.InvalidArgumentError: a bad argument, naming it, before any work starts.
    """
    clouds = check_clouds(clouds)
    cfg = batch_config(threads_per_job, voxel_size, refine, preset, config, overrides)
    keys = list(clouds)
    inputs = [check_cloud(k, clouds[k]) for k in keys]
    work = Work(set_voxel_size(cfg, inputs), keys, inputs, [], keep_features=True)
    sink = _run(executor, work, progress)
    out: dict[Hashable, Features | Error] = {}
    for key, given, value in zip(keys, work.inputs, sink.features, strict=True):
        out[key] = given if isinstance(given, Features) else value  # type: ignore[assignment]
    return out


def register_many(
    pairs: Sequence[tuple[Hashable, Hashable]],
    clouds: Mapping[Hashable, Any],
    executor: Any = None,
    *,
    threads_per_job: int = 1,
    progress: ProgressLike = None,
    voxel_size: float | None = None,
    refine: RefineMode | int | None = None,
    preset: str | None = None,
    config: Config | None = None,
    **overrides: Any,
) -> list[PairResult]:
    """Register every ``(source key, target key)`` of ``pairs``; one :class:`PairResult` per pair, in input order.

    ``clouds`` maps each key to an (N, 3) array-like (read as :func:`kissm.register` reads it), a file path
    (``str`` or ``os.PathLike``, read on the worker in the format its extension says), a :class:`CloudFile`
    (a path and a format), or :class:`kissm.Features` described before. Only the clouds that ``pairs`` names
    are described, each exactly once, by one job; every pair job then takes the two features, never points.

    ``executor``:

    * ``None``: the calling thread, one job at a time.
    * a ``concurrent.futures.Executor``: a ``ThreadPoolExecutor`` (the library releases the GIL) or a
      ``ProcessPoolExecutor`` (spawn or fork); features are pickled to each pair job in a process pool.
    * a Dask ``distributed.Client``: points held in memory are scattered once; the features stay on the
      workers; a pair whose inputs died with a worker is recomputed (the driver scatters and describes the lost
      clouds again). A task registers a group of pairs.
    * ``"ray"``: the running Ray runtime (``ray.init()`` first); points are ``ray.put`` once, every task asks
      for ``num_cpus=threads_per_job``, and a task registers a group of pairs.

    ``threads_per_job`` is each job's :attr:`kissm.Config.num_threads` (results do not depend on it): keep it at
    1 and let the executor run one job per core, or raise it for fewer, larger jobs.

    The settings are those of :func:`kissm.register`: ``voxel_size`` (required unless ``preset`` or ``config``
    gives one), ``refine`` (``"gicp"``...), any other :class:`kissm.Config` field as a keyword, and either
    ``preset`` (a name of :data:`kissm.PRESETS`, as :meth:`kissm.Config.preset`) or ``config`` (a
    :class:`kissm.Config`) as the base they change.

    ``progress``: True (a bar on stderr: tqdm's if installed, else a line of counts), False, None (a bar only
    when stderr is a terminal; the default), or a callable called on the calling thread with a :class:`Progress`
    after each finished job.

    Raises:
        kissm.InvalidArgumentError: before any work starts, for a bad argument, naming it: a key of ``pairs``
            not in ``clouds``, a cloud that is not an (N, 3) array of real numbers, an unknown setting or an
            out-of-range value, an executor of no known kind, a Ray runtime not started.
        Exception: what a job raised that is not a :class:`kissm.Error` (a bug, a worker lost more often than
            the engine retries); the remaining jobs are cancelled.
    """
    clouds = check_clouds(clouds)
    cfg = batch_config(threads_per_job, voxel_size, refine, preset, config, overrides)
    checked_pairs = check_pairs(pairs, clouds)
    index: dict[Hashable, int] = {}
    for pair in checked_pairs:
        for key in pair:
            index.setdefault(key, len(index))
    keys = list(index)
    inputs = [check_cloud(k, clouds[k]) for k in keys]
    cfg = set_voxel_size(cfg, inputs)
    work = Work(cfg, keys, inputs, [(index[s], index[t]) for s, t in checked_pairs], keep_features=False)
    sink = _run(executor, work, progress)
    out = [pair for pair in sink.pairs if pair is not None]
    if len(out) != len(checked_pairs):  # every engine waits for every pair job; anything else is a bug here
        raise InternalError(f"kissm.batch finished with {len(checked_pairs) - len(out)} pairs unaccounted for")
    return out


__all__ = ["CloudFile", "PairResult", "Progress", "ProgressLike", "describe_many", "register_many"]
