#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Ground-vehicle mode benchmark (issue 16): ground segmentation against Patchwork++, ground suppression, the
4-DoF solver against the reference's Quatro mode (kissm_bench.ground; ``python bench/ground_bench.py --help``)."""

import sys

from kissm_bench.ground import main

if __name__ == "__main__":
    sys.exit(main())
