# SPDX-License-Identifier: MIT
"""The real data's kinds (voxel size and success thresholds, SPEC section 7) are written in four places, one per
language that reads the data: the C++ real-data test, the Python tests' helper, the Rust real-data test and the
benchmarks' data module. Each keeps its own table because each suite must run without the others; this check keeps
them equal (a kind a table leaves out is fine: the Rust suite does not register the bunny), so a threshold changed
in one place cannot make the suites and the benchmark pages judge the same run differently.

    python3 tests/tooling/check_realdata_kinds.py --root .
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

# Where each table is, and how one row reads: kind name, voxel, max rotation (deg, where written), max translation.
CPP = "tests/realdata/test_realdata.cpp"
PYTHON_TESTS = "bindings/python/tests/realdata.py"
BENCH = "bench/kissm_bench/data.py"
RUST = "bindings/rust/kissm/tests/realdata.rs"

NUMBER = r"([0-9]+(?:\.[0-9]*)?(?:e-?[0-9]+)?)"
ROWS = {
    # {"lidar_scan", {0.3, 5.0, 2.0, true}},
    CPP: re.compile(r'\{"(\w+)",\s*\{' + NUMBER + r",\s*" + NUMBER + r",\s*" + NUMBER + r","),
    # "lidar_scan": Kind(0.3, 5.0, 2.0, True),
    PYTHON_TESTS: re.compile(r'"(\w+)":\s*Kind\(' + NUMBER + r",\s*" + NUMBER + r",\s*" + NUMBER + r","),
    # "lidar_keyframe_downsampled": Kind("lidar", 0.5, 5.0, 2.0),
    BENCH: re.compile(r'"(\w+)":\s*Kind\("\w+",\s*' + NUMBER + r",\s*" + NUMBER + r",\s*" + NUMBER + r"\)"),
    # Kind { name: "lidar_scan", voxel: 0.3, max_trans: 2.0 },
    RUST: re.compile(r'Kind \{ name: "(\w+)", voxel: ' + NUMBER + r"(), max_trans: " + NUMBER),
}
# The tables' kinds must be the index's kinds (data/README.md): a misspelt name would never be looked up.
KNOWN = {"lidar_scan", "lidar_keyframe_downsampled", "indoor_rgbd_fragment", "object_range_scan"}


def table(root: Path, path: str) -> dict[str, tuple[float, float | None, float]]:
    rows: dict[str, tuple[float, float | None, float]] = {}
    for name, voxel, rot, trans in ROWS[path].findall((root / path).read_text()):
        rows[name] = (float(voxel), float(rot) if rot else None, float(trans))
    return rows


def check(root: Path) -> list[str]:
    """Every disagreement, as a line; none when the tables agree."""
    problems: list[str] = []
    tables = {path: table(root, path) for path in ROWS}
    for path, rows in tables.items():
        if len(rows) < 3:
            problems.append(f"{path}: found {len(rows)} kind rows; the check no longer reads this table")
        for name in sorted(set(rows) - KNOWN):
            problems.append(f"{path}: {name} is not a kind of the data's index")
    reference = tables[CPP]
    fields = ("voxel", "max rotation (deg)", "max translation (m)")
    for path, rows in tables.items():
        for name, values in sorted(rows.items()):
            if name not in reference:
                continue
            for field, mine, theirs in zip(fields, values, reference[name], strict=True):
                if mine is not None and mine != theirs:
                    problems.append(f"{path}: {name} {field} {mine:g}; {CPP} says {theirs:g}")
    return problems


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[2])
    args = p.parse_args()
    problems = check(args.root)
    for line in problems:
        print(line, file=sys.stderr)
    if problems:
        return 1
    print(f"realdata kinds: the {len(ROWS)} tables agree")
    return 0


if __name__ == "__main__":
    sys.exit(main())
