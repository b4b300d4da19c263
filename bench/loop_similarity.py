#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Loop candidates by similarity (issue 34, part 2): the recall of true loops among the most similar scans by
Features.signature(), and align(pairs="sequence") with the chain broken (kissm_bench.loop_similarity;
``python bench/loop_similarity.py --help``)."""

import sys

from kissm_bench.loop_similarity import main

if __name__ == "__main__":
    sys.exit(main())
