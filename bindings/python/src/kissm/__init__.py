# SPDX-License-Identifier: MIT
"""kissm: fast, robust, deterministic global 3D point cloud registration.

A thin Python layer over the kissm C library (loaded through cffi in ABI mode)::

    import kissm

    result = kissm.register(source_xyz, target_xyz, voxel_size=0.5)  # (N, 3) arrays
    if result.valid:
        aligned = source_xyz @ result.rotation.T + result.translation

    with kissm.Matcher(voxel_size=0.5, num_threads=2) as matcher:     # reuse settings and threads
        target = matcher.compute_features(target_xyz)  # describe a map once...
        for scan in scans:  # ...and match it many times
            print(matcher.register_features(matcher.compute_features(scan), target))

    refined = kissm.register(source_xyz, target_xyz, voxel_size=0.5, refine="gicp")  # + fine registration
    tracked = kissm.refine(source_xyz, target_xyz, prior_4x4, voxel_size=0.5)        # from a known pose
    refined.information  # 6x6, rotation then translation: GTSAM's Pose3 convention

    with kissm.PoseGraph(num_scans) as graph:  # many relative poses made into one consistent set
        graph.add_edge(1, 0, refined.transform, refined.information, robust=True)  # scan 1 in scan 0's frame
        solution = graph.optimize(anchor=0)  # .poses (N, 4, 4) in scan 0's frame, .accepted per edge

Results are bitwise identical to the C library's (and the ``kissm`` CLI's) on the same input, whatever
``num_threads``. The library never prints; neither does this package.
"""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np

from . import _config, _ffi, _matcher, _points, _read
from ._config import Config
from ._errors import (
    CancelledError,
    EmptyInputError,
    Error,
    FeaturesMismatchError,
    InternalError,
    InvalidArgumentError,
    IoError,
    NonFiniteError,
    NullArgumentError,
    OutOfMemoryError,
    ParseError,
    StructSizeError,
    TooFewPointsError,
    UnsupportedFormatError,
    VoxelRangeError,
)
from ._matcher import Features, Matcher
from ._points import as_point_array
from ._pose_graph import PoseGraph, PoseGraphSolution
from ._read import read_points
from ._result import Result
from ._voxel import suggest_voxel_size

# Re-exported data and type aliases are assigned here, so that each carries its docstring in the API reference.

__version__: str = _ffi.text(_ffi.lib.kissm_version_string())
"""The library's version (``kissm_version_string()``); equal to the package's."""

MIN_POINTS: int = int(_ffi.lib.KISSM_MIN_POINTS)
"""Fewest points a cloud may have (fewer raise :class:`TooFewPointsError`)."""

FORMATS: dict[str, int] = _read.FORMATS
"""The ``format`` names :func:`read_points` accepts (those of the ``kissm`` CLI's ``--format``), with their C
``KISSM_FORMAT_*`` values."""

library_path: str = _ffi.library_path
"""The path of the shared library this package loaded (its own, or ``$KISSM_LIBRARY``)."""

PointsLike: TypeAlias = _points.PointsLike
"""What the registration functions accept as a cloud: an (N, 3) array-like of real numbers, or an object with
a ``.points`` attribute holding one (an Open3D ``PointCloud``). ``Any`` for type checkers."""

NonFinitePolicy: TypeAlias = _config.NonFinitePolicy
"""The names of :attr:`Config.nonfinite_policy`: ``"reject"`` or ``"drop"``."""

ViewpointMode: TypeAlias = _config.ViewpointMode
"""The names of :attr:`Config.viewpoint_mode`: ``"fixed"``, ``"cloud_center"``, ``"sign_free"`` or ``"local"``."""

RefineMode: TypeAlias = _config.RefineMode
"""The names of :attr:`Config.refine_mode`: ``"none"``, ``"gicp"`` or ``"point_to_plane"``."""

Suppression: TypeAlias = _config.Suppression
"""The names of :attr:`Config.suppression`: ``"none"`` or ``"ground"``."""

PRESETS: tuple[str, ...] = tuple(_config.PRESETS)
"""The names :meth:`Config.preset` accepts (those of the ``kissm`` CLI's ``--preset``)."""

TransformLike: TypeAlias = _matcher.TransformLike
"""What :func:`refine` and :meth:`Matcher.refine` accept as the initial pose: a (4, 4) array-like of real
numbers mapping source points into the target frame. ``Any`` for type checkers."""


def _with_refine(refine: RefineMode | int | None, config: dict[str, Any]) -> dict[str, Any]:
    """``config`` with ``refine`` as its ``refine_mode``."""
    if refine is None:
        return config
    if "refine_mode" in config:
        raise TypeError("pass refine or refine_mode, not both (refine is refine_mode's short name)")
    return {**config, "refine_mode": refine}


VoxelSize: TypeAlias = _config.VoxelSize
"""What :attr:`Config.voxel_size` accepts: a length above 0, or ``"auto"`` (:func:`suggest_voxel_size` of each
call's clouds)."""


def register(
    source: PointsLike,
    target: PointsLike,
    voxel_size: VoxelSize,
    *,
    refine: RefineMode | int | None = None,
    **config: Any,
) -> Result:
    """Register ``source`` against ``target`` once: ``Matcher(voxel_size=voxel_size, **config).register(...)``.

    ``voxel_size`` (the clouds' unit) has no default because it depends on the data: ``"auto"`` chooses it from
    both clouds (:func:`suggest_voxel_size`; ``Result.voxel_size_used`` reports it), or give a length: 0.3-0.5 for
    outdoor LiDAR in metres, about 0.05 for indoor RGB-D fragments. ``refine`` (``"gicp"`` or ``"point_to_plane"``)
    refines the global solver's pose in the same call: it sets :attr:`Config.refine_mode`. Other keyword
    arguments are :class:`Config` fields, e.g. ``num_threads=2`` or ``nonfinite_policy="drop"``. To register
    many pairs, keep a :class:`Matcher`.
    """
    with Matcher(voxel_size=voxel_size, **_with_refine(refine, config)) as matcher:
        return matcher.register(source, target)


def ground_mask(points: PointsLike, voxel_size: VoxelSize, **config: Any) -> np.ndarray:
    """Which points of ``points`` (in the sensor's frame) are ground under the model of ``suppression='ground'``:
    ``Matcher(voxel_size=voxel_size, **config).ground_mask(points)``, a bool array of ``len(points)``.

    The model works on the voxels (every point of a voxel gets its voxel's label) around the sensor at
    ``viewpoint`` (default the origin), perpendicular to ``up`` (default +z); ``sensor_height`` (metres, 0 =
    estimate) helps on clouds whose nearby ground is hidden. Other keyword arguments are :class:`Config` fields.
    """
    with Matcher(voxel_size=voxel_size, **config) as matcher:
        return matcher.ground_mask(points)


def refine(
    source: PointsLike,
    target: PointsLike,
    initial: TransformLike,
    voxel_size: VoxelSize,
    *,
    refine: RefineMode | int | None = None,
    **config: Any,
) -> Result:
    """Refine the pose ``initial`` of ``source`` in ``target`` once:
    ``Matcher(voxel_size=voxel_size, **config).refine(source, target, initial)``.

    ``initial`` is a (4, 4) array-like mapping source points into the target frame (a prior, the previous
    scan's pose). ``refine`` (or ``refine_mode``) picks the cost, ``"gicp"`` when not given; other keyword
    arguments are :class:`Config` fields. See :meth:`Matcher.refine`.
    """
    with Matcher(voxel_size=voxel_size, **_with_refine(refine, config)) as matcher:
        return matcher.refine(source, target, initial)


# The batch API (kissm.batch), a submodule that needs everything above; importing it imports no Dask or Ray;
# multiway registration (kissm.multiway.align), the batch API and the pose graph together; and the readers and
# writers of kissm.io (E57, bags, TUM/KITTI poses), whose dependencies are imported only when called.
from . import batch, io, multiway  # noqa: E402

__all__ = [
    "FORMATS",
    "MIN_POINTS",
    "PRESETS",
    "CancelledError",
    "Config",
    "EmptyInputError",
    "Error",
    "Features",
    "FeaturesMismatchError",
    "InternalError",
    "InvalidArgumentError",
    "IoError",
    "Matcher",
    "NonFiniteError",
    "NonFinitePolicy",
    "NullArgumentError",
    "OutOfMemoryError",
    "ParseError",
    "PointsLike",
    "PoseGraph",
    "PoseGraphSolution",
    "RefineMode",
    "Result",
    "StructSizeError",
    "Suppression",
    "TooFewPointsError",
    "TransformLike",
    "UnsupportedFormatError",
    "ViewpointMode",
    "VoxelRangeError",
    "VoxelSize",
    "__version__",
    "as_point_array",
    "batch",
    "multiway",
    "ground_mask",
    "io",
    "library_path",
    "suggest_voxel_size",
    "read_points",
    "refine",
    "register",
]
