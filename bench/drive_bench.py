#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Drive benchmark (issue 34, "Sequence"): kissm.multiway.align(pairs="sequence") on a simulated drive of 1,000+
scans with loops, judged against its exact poses and true loops (kissm_bench.drive; ``python bench/drive_bench.py
--help``)."""

import sys

from kissm_bench.drive import main

if __name__ == "__main__":
    sys.exit(main())
