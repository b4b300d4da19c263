# SPDX-License-Identifier: MIT
"""The real-data pairs of $KISSM_DATA_DIR/index.tsv, with the voxel sizes and success thresholds of the C
real-data test (SPEC section 7)."""

from __future__ import annotations

import csv
import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Kind:
    voxel: float
    max_rot_deg: float
    max_trans_m: float
    must_succeed: bool  # object scans may fail, but must never be valid and wrong


KINDS = {
    "lidar_scan": Kind(0.3, 5.0, 2.0, True),
    "lidar_keyframe_downsampled": Kind(0.5, 5.0, 2.0, True),
    "indoor_rgbd_fragment": Kind(0.05, 5.0, 0.3, True),
    "object_range_scan": Kind(0.006, 5.0, 0.01, False),
}


@dataclass(frozen=True)
class RealPair:
    name: str  #: pair_dir, e.g. kitti07_keyframes_gtsam_points/pairs/000000__000001
    source: Path
    target: Path
    source_format: str  #: as in pair.txt (kissm.read_points and the CLI accept these names)
    target_format: str
    gt: np.ndarray  #: 4x4, maps source into target
    kind: Kind
    kind_name: str  #: the index's kind, e.g. lidar_scan

    @property
    def is_lidar(self) -> bool:
        return self.kind_name.startswith("lidar_")


def _pair_txt(path: Path) -> dict[str, str]:
    values = {}
    for line in path.read_text().splitlines():
        key, _, value = line.partition(":")
        values[key.strip()] = value.strip()
    return values


def load_pairs(root: Path) -> list[RealPair]:
    pairs = []
    with open(root / "index.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            pair_dir = root / row["pair_dir"]
            info = _pair_txt(pair_dir / "pair.txt")
            dataset = root / row["dataset"]
            pairs.append(
                RealPair(
                    name=row["pair_dir"],
                    source=dataset / info["source"],
                    target=dataset / info["target"],
                    source_format=info["source_format"],
                    target_format=info["target_format"],
                    gt=np.loadtxt(pair_dir / "gt_T_target_source.txt").reshape(4, 4),
                    kind=KINDS[row["kind"]],
                    kind_name=row["kind"],
                )
            )
    return pairs


def pair_names(root: Path, lidar_only: bool = False) -> list[str]:
    """Names for parametrisation (of every pair, or of the LiDAR pairs), without failing collection when the
    data is absent."""
    try:
        return [p.name for p in load_pairs(root) if p.is_lidar or not lidar_only]
    except OSError:
        return []


@functools.cache
def read_cached(path: Path, fmt: str) -> np.ndarray:
    """A cloud read once per process (``kissm.read_points``), for the tests that share it."""
    import kissm

    return kissm.read_points(path, format=fmt)
