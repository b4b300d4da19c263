# SPDX-License-Identifier: MIT
"""``kissm.read_points``: the library's point-file readers, returning numpy arrays."""

from __future__ import annotations

import os
from typing import Literal, Union, overload

import numpy as np

from ._errors import Error, check
from ._ffi import ffi, lib
from ._laz import is_laz, laspy_with_lazrs, laz_missing, read_laz

#: Names accepted by :func:`read_points` (those of the ``kissm`` CLI's ``--format``).
FORMATS: dict[str, int] = {
    "auto": lib.KISSM_FORMAT_AUTO,
    "ply": lib.KISSM_FORMAT_PLY,
    "pcd": lib.KISSM_FORMAT_PCD,
    "kitti_bin": lib.KISSM_FORMAT_KITTI_BIN,
    "npy": lib.KISSM_FORMAT_NPY,
    "xyz": lib.KISSM_FORMAT_XYZ,
    "bin_xyz": lib.KISSM_FORMAT_BIN_XYZ,
    "las": lib.KISSM_FORMAT_LAS,
    # The data sets' pair.txt names, as the CLI accepts them.
    "kitti": lib.KISSM_FORMAT_KITTI_BIN,
    "kitti_bin_xyzi_f32": lib.KISSM_FORMAT_KITTI_BIN,
    "bin_xyz_f32": lib.KISSM_FORMAT_BIN_XYZ,
    "npy_xyz": lib.KISSM_FORMAT_NPY,
    "txt": lib.KISSM_FORMAT_XYZ,
}

StrPath = Union[str, "os.PathLike[str]", bytes]


@overload
def read_points(path: StrPath, format: str = ..., *, return_withheld: Literal[False] = ...) -> np.ndarray: ...


@overload
def read_points(path: StrPath, format: str = ..., *, return_withheld: Literal[True]) -> tuple[np.ndarray, int]: ...


def read_points(
    path: StrPath, format: str = "auto", *, return_withheld: bool = False
) -> np.ndarray | tuple[np.ndarray, int]:
    """Read a point file with the library's readers (the ones the ``kissm`` CLI uses).

    Formats: PLY (ascii, binary), PCD (ascii, binary), KITTI ``.bin`` (float32 x y z intensity), ``.npy``
    (float32/float64, (N, 3) or (N, k >= 3)), whitespace ``xyz`` text (.xyz .txt .pts .asc), LAS 1.0-1.4
    (.las, point formats 0-10: scale and offset applied in float64, points flagged withheld left out), and raw
    float32 x y z triples with ``format="bin_xyz"``. ``"auto"`` picks by extension, then by content.

    LAZ (compressed LAS, any name: its header says it is compressed) is read with ``"auto"`` or ``"las"``
    through laspy and its lazrs backend, installed by ``pip install kissm[las]``: the same points, bit for bit,
    as the library returns for that data stored uncompressed. Without them it raises
    :class:`kissm.UnsupportedFormatError` naming that command.

    Returns:
        A new (N, 3) float64 C-contiguous array. Non-finite points are kept as they are (the registration's
        ``nonfinite_policy`` decides). With ``return_withheld=True``, ``(array, withheld)``: ``withheld`` is
        the number of points the reader left out on purpose (LAS points flagged withheld; 0 for the other
        formats), ``kissm_cloud_num_withheld`` in C.

    Raises:
        kissm.IoError: the file cannot be opened or read (an OSError).
        kissm.ParseError, kissm.UnsupportedFormatError: the content is malformed or of no known format (or LAZ
            without laspy and lazrs).
        ValueError: ``format`` is not one of :data:`FORMATS`.
    """
    if format not in FORMATS:
        names = ", ".join(repr(name) for name in list(FORMATS)[:8])
        raise ValueError(f"format is {format!r}; use one of {names}")
    encoded = os.fsencode(path)
    if b"\0" in encoded:
        raise ValueError("path contains a NUL character")
    laz = format in ("auto", "las") and is_laz(encoded)
    if laz:
        laspy = laspy_with_lazrs()
        if laspy is not None:
            points, withheld = read_laz(laspy, encoded)
            return (points, withheld) if return_withheld else points
    out = ffi.new("kissm_cloud **")
    try:
        check(lib.kissm_read_points(encoded, FORMATS[format], out))
    except Error as e:
        if laz:  # the library cannot decompress: name what can
            raise laz_missing(encoded, e) from e
        raise
    cloud = ffi.gc(out[0], lib.kissm_cloud_destroy)
    try:
        count = int(lib.kissm_cloud_count(cloud))
        array = np.empty((count, 3), dtype=np.float64)
        if count:
            ffi.memmove(ffi.from_buffer(array), lib.kissm_cloud_data(cloud), 24 * count)
        if return_withheld:
            return array, int(lib.kissm_cloud_num_withheld(cloud))
        return array
    finally:
        ffi.release(cloud)
