#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Batch registration throughput (issue 17): pairs per second of kissm.batch.register_many on the calling thread,
a thread pool, Dask and Ray against a per-pair loop (kissm_bench.batch; ``python bench/batch_bench.py --help``)."""

import sys

from kissm_bench.batch import main

if __name__ == "__main__":
    sys.exit(main())
