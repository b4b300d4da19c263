# SPDX-License-Identifier: MIT
"""The real data, one home for every benchmark and study: the pairs of ``../shared/data/index.tsv`` (or
KISSM_DATA_DIR, or a script's --data) with their kind's voxel size and success thresholds (SPEC section 7, the
same as the C and Python real-data tests'), reading the clouds, and the KITTI 07 keyframes' world poses."""

from __future__ import annotations

import csv
import functools
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

KEYFRAMES_DIR = "kitti07_keyframes_gtsam_points"


@dataclass(frozen=True)
class Kind:
    """What a kind of data is registered with and judged by."""

    category: str  #: lidar, indoor or object: the thresholds' name in the benchmark's records
    voxel: float  #: voxel size, m
    max_rot_deg: float  #: success: a valid pose within these of the ground truth
    max_trans_m: float


KINDS = {
    "lidar_keyframe_downsampled": Kind("lidar", 0.5, 5.0, 2.0),
    "lidar_scan": Kind("lidar", 0.3, 5.0, 2.0),
    "indoor_rgbd_fragment": Kind("indoor", 0.05, 5.0, 0.3),
    "object_range_scan": Kind("object", 0.006, 5.0, 0.01),
}
#: (max rotation error in degrees, max translation error in m) per category; synthetic scenes are judged as LiDAR.
THRESHOLDS = {k.category: (k.max_rot_deg, k.max_trans_m) for k in KINDS.values()} | {"synthetic": (5.0, 2.0)}


@dataclass(frozen=True)
class Pair:
    """One row of index.tsv, its pair.txt and its ground truth."""

    dataset: str  #: e.g. kitti07_keyframes_gtsam_points
    pair: str  #: the index's pair, e.g. 000000__000001
    name: str  #: the pair's folder, e.g. kitti07_keyframes_gtsam_points/pairs/000000__000001
    kind_name: str  #: the index's kind, e.g. lidar_scan
    kind: Kind
    source: Path
    target: Path
    source_format: str  #: as in pair.txt (kissm.read_points' names; "auto" when it names none)
    target_format: str
    gt: np.ndarray  #: 4x4, maps the source into the target

    @property
    def is_lidar(self) -> bool:
        return self.kind_name.startswith("lidar_")

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """The source and target points, (N, 3) float64 (``kissm.read_points``)."""
        import kissm

        return (
            kissm.read_points(self.source, format=self.source_format),
            kissm.read_points(self.target, format=self.target_format),
        )


def _pair_txt(path: Path) -> dict[str, str]:
    out = {}
    for line in path.read_text().splitlines():
        if ":" in line:
            key, value = line.split(":", 1)
            out[key.strip()] = value.strip()
    return out


def has_index(root: Path) -> bool:
    return (root / "index.tsv").is_file()


def load_pairs(root: Path) -> list[Pair]:
    """Every pair of ``root/index.tsv``, in its order."""
    import numpy as np

    pairs = []
    with open(root / "index.tsv", newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            if row["kind"] not in KINDS:
                raise SystemExit(f"bench: unknown kind {row['kind']!r} in index.tsv; add it to kissm_bench.data.KINDS")
            folder = root / row["pair_dir"]
            info = _pair_txt(folder / "pair.txt")
            # The clouds' paths are relative to the dataset's folder; their formats are kissm.read_points' names.
            source, target = (root / row["dataset"] / info[side] for side in ("source", "target"))
            source_format, target_format = (info.get(f"{side}_format", "auto") for side in ("source", "target"))
            gt = np.loadtxt(folder / "gt_T_target_source.txt", dtype=np.float64).reshape(4, 4)
            kind = row["kind"]
            clouds = (source, target, source_format, target_format)
            pairs.append(Pair(row["dataset"], row["pair"], row["pair_dir"], kind, KINDS[kind], *clouds, gt))
    return pairs


@dataclass(frozen=True)
class Trial:
    """One registration whose truth is known, as the studies run it."""

    name: str  #: its line in a study's listing
    source: np.ndarray
    target: np.ndarray
    gt: np.ndarray  #: maps the source into the target
    kind: Kind  #: the voxel size and the success thresholds
    at: np.ndarray | None = None  #: where the translation error is taken (None: the source's origin)


#: The KITTI 07 keyframes' kind: the studies' scan-to-map and keyframe runs.
KEYFRAME_KIND = KINDS["lidar_keyframe_downsampled"]


@functools.cache
def read_cached(path: Path, fmt: str) -> np.ndarray:
    """A cloud read once per process (``kissm.read_points``), for the runs that share it."""
    import kissm

    return kissm.read_points(path, format=fmt)


def keyframes(root: Path) -> tuple[list[np.ndarray], list[np.ndarray]] | None:
    """The KITTI 07 keyframes: the world pose of each (the pairs' ground truth chained from keyframe 0, at the
    identity) and its points in its sensor frame; None when the data has none."""
    import kissm
    import numpy as np

    folder = root / KEYFRAMES_DIR
    if not folder.is_dir():
        return None
    chain = [np.eye(4)]
    for k in range(1, 5):
        step = np.loadtxt(folder / "pairs" / f"{k - 1:06d}__{k:06d}" / "gt_T_target_source.txt")
        chain.append(chain[-1] @ step)
    cloud = [kissm.read_points(folder / f"{k:06d}" / "points.bin", format="bin_xyz") for k in range(5)]
    return chain, cloud


# ---- multi-scan sets (../shared/data README, "Multi-scan sets") ----


@dataclass(frozen=True)
class ScanSet:
    label: str
    folder: str  #: holds scans.tsv and gt_poses.txt
    voxel: float
    max_trans: float
    closed: bool  #: a loop: the consecutive triplets wrap around
    order: tuple[str, ...] = ()  #: the scans in neighbour order (empty: scans.tsv's)
    extra: tuple[tuple[str, str, str], ...] = ()  #: more triplets (a, b, c) whose three pairs overlap
    every_triplet: bool = False  #: every a < b < c in the order, not only consecutive ones
    note: str = ""


SCAN_SETS = (
    ScanSet(
        "kitti07",
        "kitti07_keyframes_gtsam_points/multiway",
        0.5,
        2.0,
        closed=False,
        every_triplet=True,
        note="a short drive: every triplet a < b < c (each pair overlaps), the 3 consecutive ones among them",
    ),
    ScanSet(
        "bunny",
        "stanford_bunny_scans/multiway",
        0.006,
        0.01,
        closed=True,
        order=("bun000", "bun045", "bun090", "bun180", "bun270", "bun315"),
        # the README's best partners of the views from above and behind, with a neighbour of theirs
        extra=(("bun180", "top2", "ear_back"), ("bun000", "bun045", "top3"), ("bun045", "bun090", "top3")),
        note="the README's turntable ring (closed) and 3 triplets through top2, top3, ear_back's best partners",
    ),
    ScanSet(
        "happy",
        "stanford_happy_stand_scans",
        0.004,
        0.01,
        closed=True,
        note="15 turntable scans 24 degrees apart, a closed loop",
    ),
)


def read_scan_set(folder: Path) -> tuple[list[str], list[Path], list[str], dict[str, np.ndarray]]:
    """A set's scan names, files and formats (scans.tsv order) and each scan's world pose (gt_poses.txt)."""
    import numpy as np

    with open(folder / "scans.tsv", newline="") as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    poses = {}
    for line in (folder / "gt_poses.txt").read_text().splitlines():
        if line.strip():
            name, *numbers = line.split()
            t = np.eye(4)
            t[:3, :] = np.array([float(x) for x in numbers]).reshape(3, 4)
            poses[name] = t
    names = [r["scan"] for r in rows]
    return names, [folder / r["file"] for r in rows], [r["format"] for r in rows], poses
