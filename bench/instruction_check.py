#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Instructions per stage of the default registration path under callgrind, against the committed baseline
bench/results/instructions.json (kissm_bench.instructions; ``python bench/instruction_check.py --help``)."""

import sys

from kissm_bench.instructions import main

if __name__ == "__main__":
    sys.exit(main())
