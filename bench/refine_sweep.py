#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The evidence behind refinement's defaults (docs/parameters.md, "Refinement"): every pair of ../shared/data,
raw and with the source turned by 3 random rotations, refined from kissm's own coarse pose under each setting
given (or a default sweep), with the median and largest errors against the ground truth, iterations,
convergence and the refinement's own time per dataset. Each setting refines the same coarse poses (the solver's
pose does not depend on refinement's settings), from features computed under the setting.
(kissm_bench.refine_sweep; ``python bench/refine_sweep.py --help``)"""

import sys

from kissm_bench.refine_sweep import main

if __name__ == "__main__":
    sys.exit(main())
