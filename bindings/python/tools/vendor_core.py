#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Copy the kissm core that the Python package compiles into ``bindings/python/_core/``.

The package's CMake build and its licence files refer to ``_core/``, so that an sdist (which holds only
``bindings/python``) carries everything it needs: the repository's top-level CMakeLists.txt, cmake/,
include/, src/, third_party/ (nanoflann and the licence texts), LICENSE and THIRD_PARTY.md. Not tests/,
bench/, docs/ or data: the package's build turns the core's tests and CLI off.

The in-tree build backend (``kissm_build_backend.py``) runs this before every build from a checkout, so
``pip install ./bindings/python`` and ``python -m build bindings/python`` need no extra step. The copy is
a sync: unchanged files keep their timestamps (incremental CMake builds stay incremental), files gone from
the repository are removed. Outside a checkout (building from the sdist) there is nothing to copy from
and ``_core/`` is used as shipped. Nothing is ever downloaded.
"""

from __future__ import annotations

import argparse
import filecmp
import shutil
import sys
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent.parent  # bindings/python
DEFAULT_REPO = PACKAGE_DIR.parent.parent
DEFAULT_DEST = PACKAGE_DIR / "_core"

#: What the core's CMake build (with KISSM_BUILD_TESTS and KISSM_BUILD_CLI off) and the licences need.
CORE_FILES = ("CMakeLists.txt", "LICENSE", "THIRD_PARTY.md")
CORE_DIRS = ("cmake", "include", "src", "third_party")
IGNORED = {"__pycache__", ".git"}


def is_checkout(repo: Path) -> bool:
    """Whether ``repo`` is the kissm repository around this package (not, e.g., an unpacked sdist)."""
    return (repo / "include" / "kissm.h").is_file() and (repo / "bindings" / "python" / "pyproject.toml").is_file()


def _wanted(repo: Path) -> dict[Path, Path]:
    """Relative path in _core -> source file, for every file to vendor."""
    files = {Path(name): repo / name for name in CORE_FILES}
    for top in CORE_DIRS:
        for path in sorted((repo / top).rglob("*")):
            relative = path.relative_to(repo)
            if path.is_file() and not IGNORED.intersection(relative.parts):
                files[relative] = path
    missing = [str(source) for source in files.values() if not source.is_file()]
    if missing:
        raise FileNotFoundError(f"vendor_core: not in the kissm checkout: {', '.join(missing)}")
    return files


def vendor(repo: Path = DEFAULT_REPO, dest: Path = DEFAULT_DEST) -> int:
    """Make ``dest`` an exact copy of the core files of ``repo``; returns how many files were written."""
    wanted = _wanted(repo)
    written = 0
    for relative, source in wanted.items():
        target = dest / relative
        if target.is_file() and filecmp.cmp(source, target, shallow=False):
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
        written += 1
    if dest.is_dir():
        for path in sorted(dest.rglob("*"), reverse=True):  # children before their directories
            relative = path.relative_to(dest)
            if path.is_file() and relative not in wanted:
                path.unlink()
            elif path.is_dir() and not any(path.iterdir()):
                path.rmdir()
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repo", type=Path, default=DEFAULT_REPO, help="the kissm checkout (default: %(default)s)")
    parser.add_argument("--dest", type=Path, default=DEFAULT_DEST, help="where to copy it (default: %(default)s)")
    args = parser.parse_args(argv)
    if not is_checkout(args.repo):
        sys.stderr.write(f"vendor_core: {args.repo} is not a kissm checkout\n")
        return 1
    vendor(args.repo, args.dest)
    return 0


if __name__ == "__main__":
    sys.exit(main())
