#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The evidence behind the validity rules (docs/design/accuracy.md, "The validity rules"): registrations whose truth is
known, each without refinement, with GICP and with point-to-plane, and the fields each rule reads. A run is
RIGHT when its pose is within the success thresholds of SPEC section 7 and WRONG otherwise; a WRONG run reported
valid is the worst bug kissm can ship, and the summary counts them per family and mode.
(kissm_bench.validity_study; ``python bench/validity_study.py --help``)"""

import sys

from kissm_bench.validity_study import main

if __name__ == "__main__":
    sys.exit(main())
