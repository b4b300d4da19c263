#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Pose-graph benchmark (issue 34): kissm's optimiser against GTSAM's Levenberg-Marquardt on synthetic drives, with
and without wrong loop closures (kissm_bench.pose_graph; ``python bench/pose_graph_bench.py --help``)."""

import sys

from kissm_bench.pose_graph import main

if __name__ == "__main__":
    sys.exit(main())
