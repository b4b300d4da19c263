#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Multiway benchmark (issue 34): kissm.multiway.align against Open3D 0.20's multiway registration (FPFH + RANSAC +
ICP per pair, PoseGraph, global_optimization) on the shared multi-scan sets, end to end at the same thread count
(kissm_bench.multiway; ``python bench/multiway_bench.py --help``)."""

import sys

from kissm_bench.multiway import main

if __name__ == "__main__":
    sys.exit(main())
