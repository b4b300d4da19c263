#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Reading LAS and LAZ (issue 35): kissm against laspy and PDAL's Python reader if it installs, on a survey-sized
georeferenced cloud made from the shared LiDAR scans (kissm_bench.reading; ``python bench/read_bench.py --help``)."""

import sys

from kissm_bench.reading import main

if __name__ == "__main__":
    sys.exit(main())
