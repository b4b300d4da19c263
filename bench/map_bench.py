#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Scan-to-map benchmark (issue 15): one LiDAR scan against maps of growing size (kissm_bench.scan_to_map;
``python bench/map_bench.py --help``). Also the entry point of its worker processes."""

import sys

from kissm_bench.scan_to_map import main

if __name__ == "__main__":
    sys.exit(main())
