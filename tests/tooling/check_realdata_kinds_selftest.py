# SPDX-License-Identifier: MIT
"""check_realdata_kinds.py finds what it must: on a copy of the four tables with planted mistakes (a voxel size in
the benchmarks' table, a translation threshold in the Rust test's, a misspelt kind in the Python tests') it reports
exactly those, and on the unchanged copy nothing."""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import check_realdata_kinds as check

ROOT = Path(__file__).resolve().parents[2]
PLANTS = {
    check.BENCH: ('"indoor_rgbd_fragment": Kind("indoor", 0.05,', '"indoor_rgbd_fragment": Kind("indoor", 0.04,'),
    check.RUST: (
        'Kind { name: "lidar_scan", voxel: 0.3, max_trans: 2.0 }',
        'Kind { name: "lidar_scan", voxel: 0.3, max_trans: 2.5 }',
    ),
    check.PYTHON_TESTS: ('"object_range_scan": Kind(', '"object_scan": Kind('),
}
EXPECTED = {
    f"{check.BENCH}: indoor_rgbd_fragment voxel 0.04; {check.CPP} says 0.05",
    f"{check.RUST}: lidar_scan max translation (m) 2.5; {check.CPP} says 2",
    f"{check.PYTHON_TESTS}: object_scan is not a kind of the data's index",
}


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for f in check.ROWS:
            (root / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / f, root / f)
        clean = check.check(root)
        if clean:
            print("selftest: the unchanged copy already disagrees:", *clean, sep="\n  ", file=sys.stderr)
            return 1
        for f, (old, new) in PLANTS.items():
            text = (root / f).read_text()
            assert text.count(old) == 1, (f, old)
            (root / f).write_text(text.replace(old, new))
        found = set(check.check(root))
    if found != EXPECTED:
        print("selftest: missed:", *sorted(EXPECTED - found), sep="\n  ", file=sys.stderr)
        print("selftest: reported beyond the plants:", *sorted(found - EXPECTED), sep="\n  ", file=sys.stderr)
        return 1
    print(f"selftest: the {len(EXPECTED)} planted mistakes found, nothing else")
    return 0


if __name__ == "__main__":
    sys.exit(main())
