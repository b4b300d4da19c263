#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""kissm benchmark: kissm against the reference KISS-Matcher and Open3D, on real pairs and synthetic scenes
(kissm_bench.benchmark; ``python bench/bench.py --help``). Also the entry point of its worker processes."""

import sys

from kissm_bench.benchmark import main

if __name__ == "__main__":
    sys.exit(main())
