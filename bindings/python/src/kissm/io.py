# SPDX-License-Identifier: MIT
"""The files users have, beyond what :func:`kissm.read_points` reads (docs/files.md):

    scans = kissm.io.read_e57("site.e57")                  # pip install kissm[e57]
    alignment = kissm.multiway.align([s.points for s in scans], 0.05,
                                     pairs="sequence", priors=[s.pose for s in scans])
    world = scans[0].pose @ alignment.poses                # the file's world <- scan
    kissm.io.write_e57_poses("site.e57", "site_aligned.e57", world)

    for stamp, points in kissm.io.read_bag("drive.bag"):  # pip install kissm[ros]: ROS 1/2 bags, MCAP
        ...

    kissm.io.write_tum("poses.txt", poses, stamps)         # trajectories as text
    kissm.io.write_kitti("poses.kitti", poses)

LAZ needs no function of its own: :func:`kissm.read_points` reads it when laspy and lazrs are installed
(``pip install kissm[las]``). Each reader imports its dependency when called, so ``import kissm`` needs none of
them; a missing one raises ``ModuleNotFoundError`` naming the ``pip install`` that brings it.
"""

from __future__ import annotations

from ._bags import read_bag
from ._e57 import E57Scan, read_e57, write_e57_poses
from ._pose_files import write_kitti, write_tum

__all__ = ["E57Scan", "read_bag", "read_e57", "write_e57_poses", "write_kitti", "write_tum"]
