#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The committed pages of docs/reports/ are what the committed results of bench/results/ render
(kissm_bench.page_check; ``python bench/check_pages.py --help``)."""

import sys

from kissm_bench.page_check import main

if __name__ == "__main__":
    sys.exit(main())
