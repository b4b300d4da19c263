#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Can a validity rule refuse the wrong poses that loop registrations on a simulated city report valid, without
losing right ones? (kissm_bench.city_validity; ``python bench/city_validity_study.py --help``)"""

import sys

from kissm_bench.city_validity import main

if __name__ == "__main__":
    sys.exit(main())
