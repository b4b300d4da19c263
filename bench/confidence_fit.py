#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The fit behind kissm_result.confidence: a logistic model per kind of result, fitted on half of the validity
study's runs and judged on the other half (kissm_bench.confidence_fit; ``python bench/confidence_fit.py --help``)."""

import sys

from kissm_bench.confidence_fit import main

if __name__ == "__main__":
    sys.exit(main())
