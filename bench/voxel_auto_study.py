#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The evidence behind voxel_size="auto" (docs/design/voxel_auto.md): every real pair raw and turned, and every
multi-scan set, registered with the data README's voxel and with candidate rules' voxels.
(kissm_bench.voxel_auto_study; ``python bench/voxel_auto_study.py --help``)"""

import sys

from kissm_bench.voxel_auto_study import main

if __name__ == "__main__":
    sys.exit(main())
