# SPDX-License-Identifier: MIT
"""Test files written by the reference LAS writer (laspy), shared by the tests of LAS and of LAZ."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest


def write_laspy(
    path: Path,
    xyz: np.ndarray,
    fmt: int,
    version: str,
    offset: np.ndarray,
    scale: float = 1e-3,
    withheld: np.ndarray | None = None,
) -> Any:
    """Writes ``xyz`` with laspy at point format ``fmt`` and ``version`` (quantised to ``scale`` around ``offset``,
    with the withheld flags given) and returns laspy's reading of the file; skips the test without laspy."""
    laspy = pytest.importorskip("laspy", reason="laspy is not installed (it is in the test extra: pip install .[test])")
    header = laspy.LasHeader(point_format=fmt, version=version)
    header.scales = np.array([scale] * 3)
    header.offsets = offset
    las = laspy.LasData(header)
    las.x, las.y, las.z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    if withheld is not None:
        las.withheld = withheld
    las.write(str(path))
    return laspy.read(str(path))
