# SPDX-License-Identifier: MIT
"""Turning array-likes into ``kissm_points`` views: checks first, copies only when unavoidable."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ._ffi import ffi, lib

#: What the registration functions accept as a cloud: an (N, 3) array-like of real numbers
#: (``numpy.typing.ArrayLike``), or an object with a ``.points`` attribute holding one (an Open3D
#: ``PointCloud``), hence ``Any`` for type checkers.
PointsLike = Any

_SCALAR_TYPES = {np.dtype(np.float32): lib.KISSM_SCALAR_FLOAT32, np.dtype(np.float64): lib.KISSM_SCALAR_FLOAT64}


class PointsView(NamedTuple):
    """A ``kissm_points *`` and the array it points into (keep ``array`` alive while C reads it)."""

    c: Any
    array: np.ndarray


def as_point_array(cloud: PointsLike, name: str = "cloud") -> np.ndarray:
    """The (N, 3) float32/float64 array kissm reads for ``cloud``; ``cloud`` itself (or a view of it) when
    possible.

    Float32 and float64 arrays are used as they are when each point's x, y, z are adjacent in memory, aligned,
    with a non-negative row stride: C- or F-ordered rows of a wider array (``a[:, :3]``), every other row
    (``a[::2]``) and read-only arrays need no copy. Anything else (an F-ordered (N, 3) array, reversed rows,
    integers, float16, lists) is copied once into a new array; the input is never written to.

    Raises:
        TypeError: the values are not real numbers (bool, complex, object, strings...).
        ValueError: the shape is not (N, 3).
    """
    if not isinstance(cloud, np.ndarray):
        points = getattr(cloud, "points", None)
        if points is not None and not callable(points):
            cloud = points  # Open3D PointCloud.points (a Vector3dVector: buffer protocol, no copy)
        try:
            cloud = np.asarray(cloud)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{name} cannot be read as an (N, 3) array: {e}") from None
    array: np.ndarray = cloud
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{name} has dtype {array.dtype}; kissm needs real coordinates (float32 or float64; integers are converted)"
        )
    if array.ndim != 2 or array.shape[1] != 3:
        hint = f" (pass {name}[:, :3] for x, y, z of wider rows: no copy)" if array.ndim == 2 else ""
        raise ValueError(f"{name} must have shape (N, 3), not {array.shape}{hint}")
    if array.dtype not in _SCALAR_TYPES:  # integers, float16, long double, non-native byte order
        array = array.astype(np.float64)
    if not _usable_layout(array):
        array = np.ascontiguousarray(array)
    return array


def _usable_layout(array: np.ndarray) -> bool:
    item = array.itemsize
    row_stride, column_stride = array.strides
    if array.shape[0] == 0:
        return True  # nothing is read
    if not array.flags.aligned or column_stride != item:
        return False
    return array.shape[0] == 1 or (row_stride >= 3 * item and row_stride % item == 0)


def points_view(cloud: PointsLike, name: str = "cloud") -> PointsView:
    """A ``kissm_points`` view of ``cloud`` (see :func:`as_point_array`)."""
    array = as_point_array(cloud, name)
    c = ffi.new("kissm_points *")
    c.data = ffi.cast("const void *", array.__array_interface__["data"][0])
    c.count = array.shape[0]
    row_stride = array.strides[0]
    c.stride_bytes = 0 if array.shape[0] <= 1 or row_stride == 3 * array.itemsize else row_stride
    c.scalar_type = _SCALAR_TYPES[array.dtype]
    c.reserved = 0
    return PointsView(c, array)
