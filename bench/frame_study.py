#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Does registration depend on the clouds' coordinate frames? The evidence behind the default viewpoint_mode
(docs/design/frames.md): each viewpoint mode on the same runs, coarse (no refinement), success as in SPEC section 7.
(kissm_bench.frame_study; ``python bench/frame_study.py --help``)"""

import sys

from kissm_bench.frame_study import main

if __name__ == "__main__":
    sys.exit(main())
