# SPDX-License-Identifier: MIT
"""LAZ (compressed LAS) for ``kissm.read_points``, through laspy and its lazrs backend (the extra
``kissm[las]``): the library's LAS reader does not decompress. The points are the ones the C reader returns for
the same data stored as uncompressed LAS, bit for bit: X * scale + offset in float64 per axis, in that order,
points flagged withheld left out."""

from __future__ import annotations

import importlib
import os
from typing import Any

import numpy as np

from ._errors import IoError, ParseError, UnsupportedFormatError

# The point data format id byte of the LAS header; LASzip marks a compressed file by setting its bit 7 (and bit 6,
# which LAS 1.4 reserves for it too), so the id alone tells LAZ from LAS whatever the file is named.
_FORMAT_ID_OFFSET = 104
_COMPRESSED_BITS = 0xC0

INSTALL_HINT = "reading LAZ needs laspy with its lazrs backend: pip install kissm[las]"


def is_laz(path: str | os.PathLike[str] | bytes) -> bool:
    """Whether ``path`` is a LAS file whose points are compressed (LAZ), judged by its header, not its name. An
    unreadable or short file is not: the library's reader then reports it as it would."""
    try:
        with open(path, "rb") as f:
            head = f.read(_FORMAT_ID_OFFSET + 1)
    except OSError:
        return False
    return len(head) > _FORMAT_ID_OFFSET and head[:4] == b"LASF" and bool(head[_FORMAT_ID_OFFSET] & _COMPRESSED_BITS)


def laspy_with_lazrs() -> Any:
    """The laspy module when it and lazrs are installed, else None."""
    try:
        laspy = importlib.import_module("laspy")  # optional: typed as Any, so mypy needs no laspy
    except ImportError:
        return None
    return laspy if laspy.LazBackend.Lazrs.is_available() else None


def read_laz(laspy: Any, path: str | os.PathLike[str] | bytes) -> tuple[np.ndarray, int]:
    """(N, 3) float64 points of the LAZ file ``path``, as the library's LAS reader computes them, and the number of
    points flagged withheld that were left out."""
    name = os.fsdecode(path)
    try:
        las = laspy.read(name, laz_backend=laspy.LazBackend.Lazrs)  # single-threaded: deterministic, no pool
    except OSError as e:
        raise IoError(f"{name}: {e}") from e
    except (laspy.LaspyException, RuntimeError, ValueError) as e:  # lazrs's LazrsError is a RuntimeError
        raise ParseError(f"{name}: LAZ: {e}") from e
    header = las.header
    keep = ~np.asarray(las.withheld, dtype=bool)
    raw = (np.asarray(las.X), np.asarray(las.Y), np.asarray(las.Z))
    points = np.empty((int(keep.sum()), 3), dtype=np.float64)
    for k in range(3):
        # The C reader's operation: double(X) * scale + offset, two roundings (no fused multiply-add).
        points[:, k] = raw[k][keep].astype(np.float64) * float(header.scales[k]) + float(header.offsets[k])
    return points, int(keep.size - points.shape[0])


def laz_missing(path: str | os.PathLike[str] | bytes, cause: Exception) -> UnsupportedFormatError:
    """The error for a LAZ file read without laspy/lazrs (``cause``: the library's own refusal)."""
    return UnsupportedFormatError(f"{os.fsdecode(path)}: {INSTALL_HINT} (the library said: {cause})")
