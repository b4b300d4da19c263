#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Where a batch's CPU goes (issue 17): the thread pool, Dask and Ray kept running, with the CPU time and page faults
of every process (kissm_bench.batch_accounting; ``python bench/batch_accounting.py --help``)."""

import sys

from kissm_bench.batch_accounting import main

if __name__ == "__main__":
    sys.exit(main())
