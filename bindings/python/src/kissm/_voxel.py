# SPDX-License-Identifier: MIT
"""``kissm.suggest_voxel_size``: the automatic voxel size of ``voxel_size="auto"`` (``kissm_suggest_voxel_size``)."""

from __future__ import annotations

from ._errors import InvalidArgumentError, check
from ._ffi import ffi, lib
from ._points import PointsLike, points_view


def suggest_voxel_size(*clouds: PointsLike) -> float:
    """The voxel size ``voxel_size="auto"`` uses for these clouds together (``kissm_suggest_voxel_size``): one
    cloud, a pair (in either order) or a set of scans to be described alike.

    Each cloud's own voxel is the smallest of 2^(k/8) (k an integer, in the clouds' unit) whose grid holds at most
    3000 occupied voxels, or 2000 for a compact cloud (an object scan, an indoor fragment); a quarter of its points
    when it has fewer than 4 times as many. The suggestion is the clouds' own lower median (the smaller of a pair).
    It depends on the points alone (not their order, not the thread count); non-finite points are ignored.
    docs/design/voxel_auto.md has the rule's evidence.

    Raises:
        TypeError, ValueError: no cloud, a cloud that is not an (N, 3) array of real numbers, or one without 4
            distinct finite points (:class:`kissm.TooFewPointsError`, :class:`kissm.EmptyInputError`).
    """
    if not clouds:
        raise InvalidArgumentError("suggest_voxel_size: give at least one cloud")
    views = [points_view(c, f"clouds[{i}]") for i, c in enumerate(clouds)]
    array = ffi.new("kissm_points[]", len(views))
    for i, v in enumerate(views):
        array[i] = v.c[0]
    out = ffi.new("double *")
    check(lib.kissm_suggest_voxel_size(array, len(views), out))
    return float(out[0])
