# SPDX-License-Identifier: MIT
"""check_setting_docs.py finds what it must: on a copy of the four files with planted mistakes (a range in
kissm.h, a range in the Python docstrings, a default in the Rust docs, a setter whose docs are gone) it reports
exactly those, and on the unchanged copy nothing."""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import check_setting_docs

ROOT = Path(__file__).resolve().parents[2]
FILES = [
    "docs/parameters.md",
    "include/kissm.h",
    "bindings/python/src/kissm/_config.py",
    "bindings/rust/kissm/src/config.rs",
]
PLANTS = {
    "include/kissm.h": (
        "FPFH radius = gain * voxel_size; in [1.5, 50]",
        "FPFH radius = gain * voxel_size; in [1.5, 60]",
    ),
    "bindings/python/src/kissm/_config.py": ("Refinement iteration cap, 1..1000.", "Refinement iteration cap, 1..100."),
    "bindings/rust/kissm/src/config.rs": ("in (0, 1]; 1 = off (default 0.9).", "in (0, 1]; 1 = off (default 0.8)."),
}
EXPECTED = {
    "kissm.h: fpfh_radius_gain states [1.5, 60]; docs/parameters.md says [1.5, 50]",
    "Python: refine_max_iterations states [1, 100]; docs/parameters.md says [1, 1000]",
    "Rust: ratio_test default 0.8; docs/parameters.md says 0.9",
    "Rust: no documentation found for min_normal_neighbors",
}


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for f in FILES:
            (root / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / f, root / f)
        clean = check_setting_docs.check(root)
        if clean:
            print("selftest: the unchanged copy already disagrees:", *clean, sep="\n  ", file=sys.stderr)
            return 1
        for f, (old, new) in PLANTS.items():
            text = (root / f).read_text()
            assert text.count(old) == 1, (f, old)
            (root / f).write_text(text.replace(old, new))
        rust = root / "bindings/rust/kissm/src/config.rs"
        text = rust.read_text()
        old = (
            "        /// Neighbours needed for a normal and a descriptor, 3..=100000 (default 3).\n"
            "        min_normal_neighbors: count,\n"
        )
        assert text.count(old) == 1
        rust.write_text(text.replace(old, ""))
        found = set(check_setting_docs.check(root))
    if found != EXPECTED:
        print("selftest: missed", sorted(EXPECTED - found), "and reported", sorted(found - EXPECTED), file=sys.stderr)
        return 1
    print(f"selftest: the {len(EXPECTED)} planted disagreements found, nothing else")
    return 0


if __name__ == "__main__":
    sys.exit(main())
