#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""How calibrated the refined information matrix is, and calibration models for it: NEES of real pairs against
their ground truth, of cycles of three registrations on the multi-scan sets, and of simulated scans with exact
truth, under the models given (--model K C) or a grid search (--fit).
(kissm_bench.nees_study; ``python bench/nees_study.py --help``)"""

import sys

from kissm_bench.nees_study import main

if __name__ == "__main__":
    sys.exit(main())
