# SPDX-License-Identifier: MIT
"""The checks ``kissm.batch`` makes before any work starts: every bad argument raises
:class:`kissm.InvalidArgumentError` naming it, so a batch never fails an hour in for a typo."""

from __future__ import annotations

import dataclasses
import os
import sys
from collections.abc import Hashable, Mapping, Sequence
from concurrent.futures import Executor
from typing import Any

from .._config import PRESETS, Config, did_you_mean
from .._errors import Error, InvalidArgumentError
from .._matcher import Features
from .._points import as_point_array
from .._read import FORMATS, read_points
from .._voxel import suggest_voxel_size
from ._values import CloudFile

#: What a cloud becomes once checked: points (an (N, 3) array), a file to read on the worker, or features
#: described before.
Checked = Any

_CONFIG_FIELDS = frozenset(f.name for f in dataclasses.fields(Config))


def batch_config(
    threads_per_job: object,
    voxel_size: float | None,
    refine: object,
    preset: str | None,
    config: Config | None,
    overrides: Mapping[str, Any],
) -> Config:
    """The settings of every job: ``preset`` or ``config`` (else the library's defaults), then ``voxel_size``,
    ``refine`` and the other :class:`kissm.Config` fields, with ``num_threads=threads_per_job``."""
    if isinstance(threads_per_job, bool) or not isinstance(threads_per_job, int) or not 1 <= threads_per_job <= 1024:
        raise InvalidArgumentError(f"threads_per_job must be an int in 1..1024, not {threads_per_job!r}")
    unknown = sorted(set(overrides) - _CONFIG_FIELDS)
    if unknown:
        raise InvalidArgumentError(
            f"unknown keyword argument {unknown[0]!r}: not a kissm.Config field{did_you_mean(unknown[0])}"
        )
    if "num_threads" in overrides:
        raise InvalidArgumentError("pass threads_per_job, not num_threads: each job runs with threads_per_job threads")
    if "refine_mode" in overrides and refine is not None:
        raise InvalidArgumentError("pass refine or refine_mode, not both (refine is refine_mode's short name)")
    if preset is not None and config is not None:
        raise InvalidArgumentError("pass preset or config, not both")
    if config is not None and not isinstance(config, Config):
        raise InvalidArgumentError(f"config must be a kissm.Config or None, not {type(config).__name__}")
    if voxel_size is None and preset is None and config is None:
        # As kissm.register: the voxel size depends on the data, so it has no silent default.
        raise InvalidArgumentError(
            'voxel_size is required: voxel_size="auto" chooses it from the clouds, or give a length in their unit '
            "(0.3-0.5 for outdoor LiDAR in metres), a preset= (" + ", ".join(map(repr, PRESETS)) + ") or a config="
        )
    changes = dict(overrides, num_threads=threads_per_job)
    if voxel_size is not None:
        changes["voxel_size"] = voxel_size
    if refine is not None:
        changes["refine_mode"] = refine
    try:
        if preset is not None:
            if preset not in PRESETS:
                raise InvalidArgumentError(f"preset is {preset!r}; use one of {', '.join(map(repr, PRESETS))}")
            return Config.preset(preset, **changes)
        return (config or Config()).replace(**changes)
    except Error:
        raise  # the library's own message names the field
    except (TypeError, ValueError) as e:
        raise InvalidArgumentError(f"config: {e}") from None


def check_clouds(clouds: object) -> Mapping[Hashable, Any]:
    if not isinstance(clouds, Mapping):
        raise InvalidArgumentError(f"clouds must be a mapping of key to cloud (a dict), not {type(clouds).__name__}")
    return clouds


def check_cloud(key: Hashable, cloud: object) -> Checked:
    """``cloud`` as a describe job takes it. Arrays are checked here (shape, dtype); files and point counts are
    the jobs' (a missing file or a tiny cloud fails its pairs, not the batch)."""
    name = f"clouds[{key!r}]"
    if isinstance(cloud, Features):
        return cloud
    if isinstance(cloud, (str, os.PathLike)):
        cloud = CloudFile(os.fspath(cloud))
    if isinstance(cloud, CloudFile):
        if not isinstance(cloud.path, (str, os.PathLike)):
            raise InvalidArgumentError(
                f"{name}: the path must be a str or os.PathLike, not {type(cloud.path).__name__}"
            )
        if cloud.format not in FORMATS:
            raise InvalidArgumentError(f"{name}: format is {cloud.format!r}; use one of kissm.FORMATS")
        return CloudFile(os.fspath(cloud.path), cloud.format)
    if isinstance(cloud, bytes):
        raise InvalidArgumentError(f"{name} is bytes: give a path as str or os.PathLike, or points as an (N, 3) array")
    try:
        return as_point_array(cloud, name)
    except (TypeError, ValueError) as e:
        raise InvalidArgumentError(str(e)) from None


def check_pairs(pairs: object, clouds: Mapping[Hashable, Any]) -> list[tuple[Hashable, Hashable]]:
    """``pairs`` as a list of (source key, target key), each key one of ``clouds``' (else the caller's error)."""
    if isinstance(pairs, (str, bytes, Mapping)) or not isinstance(pairs, (Sequence, list, tuple)):
        raise InvalidArgumentError(f"pairs must be a sequence of (source key, target key), not {type(pairs).__name__}")
    checked = []
    for i, pair in enumerate(pairs):
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise InvalidArgumentError(f"pairs[{i}] must be a (source key, target key) pair, not {pair!r}")
        for side, key in zip(("source", "target"), pair, strict=True):
            try:
                known = key in clouds
            except TypeError:  # unhashable
                known = False
            if not known:
                raise InvalidArgumentError(f"pairs[{i}] names the {side} {key!r}, which is not a key of clouds")
        checked.append((pair[0], pair[1]))
    return checked


def engine_name(executor: object) -> str:
    """Which engine runs the jobs: ``"here"``, ``"futures"``, ``"dask"`` or ``"ray"``."""
    if executor is None:
        return "here"
    if isinstance(executor, str):
        if executor != "ray":
            raise InvalidArgumentError(f"executor is {executor!r}; the only name it accepts is 'ray'")
        try:
            import ray  # the extra kissm[ray]; already imported by whoever started the runtime
        except ImportError:
            raise InvalidArgumentError("executor='ray' needs Ray: pip install 'kissm[ray]'") from None
        if not ray.is_initialized():
            raise InvalidArgumentError(
                "executor='ray' needs a running Ray runtime: call ray.init() or ray.init(address)"
            )
        return "ray"
    distributed: Any = sys.modules.get("distributed")  # a Client exists only if its module was imported
    if distributed is not None and isinstance(executor, distributed.Client):
        if executor.status != "running":
            raise InvalidArgumentError(f"executor is a Dask Client that is {executor.status}, not running")
        return "dask"
    if isinstance(executor, Executor):
        return "futures"
    raise InvalidArgumentError(
        f"executor must be None, a concurrent.futures.Executor, a dask.distributed Client or 'ray', "
        f"not {type(executor).__name__}"
    )


def set_voxel_size(cfg: Config, inputs: Sequence[Checked]) -> Config:
    """``cfg`` with ``voxel_size="auto"`` made the one voxel of every cloud of the batch together
    (:func:`kissm.suggest_voxel_size` of them all), so that any two of them match; other configs as given. The files
    are read here for it; features described before carry their own voxel, so they cannot take part."""
    if cfg.voxel_size != "auto":
        return cfg
    points = []
    for cloud in inputs:
        if isinstance(cloud, Features):
            raise InvalidArgumentError(
                "voxel_size='auto' needs every cloud's points, not features described before: describe them with "
                "voxel_size=kissm.suggest_voxel_size(*clouds) instead"
            )
        points.append(read_points(cloud.path, format=cloud.format) if isinstance(cloud, CloudFile) else cloud)
    return cfg.replace(voxel_size=suggest_voxel_size(*points)) if points else cfg
