#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Rewrites docs/reports/benchmarks.md and its plots from saved results of bench.py (kissm_bench.reports.benchmarks):

python bench/report.py bench/results/latest.json.gz --out docs/reports
"""

import sys

from kissm_bench.reports.benchmarks import main

if __name__ == "__main__":
    sys.exit(main())
