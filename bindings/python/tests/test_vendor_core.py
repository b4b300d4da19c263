# SPDX-License-Identifier: MIT
"""tools/vendor_core.py: the core copied for the sdist is complete, minimal, and synced without touching
unchanged files (so that incremental builds of the package stay incremental)."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path
from types import ModuleType

import pytest

from conftest import PACKAGE_ROOT, REPO_ROOT

SCRIPT = PACKAGE_ROOT / "tools" / "vendor_core.py"


@pytest.fixture(scope="module")
def vendor_core() -> ModuleType:
    if not SCRIPT.is_file() or not (REPO_ROOT / "include" / "kissm.h").is_file():
        pytest.skip("tools/vendor_core.py or the kissm checkout not found (tests run outside the repository)")
    spec = importlib.util.spec_from_file_location("vendor_core", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_copies_what_the_core_build_needs_and_nothing_else(vendor_core: ModuleType, tmp_path: Path) -> None:
    dest = tmp_path / "_core"
    assert vendor_core.is_checkout(REPO_ROOT)
    written = vendor_core.vendor(REPO_ROOT, dest)
    copied = {p.relative_to(dest).as_posix() for p in dest.rglob("*") if p.is_file()}
    assert written == len(copied)
    for needed in (
        "CMakeLists.txt",
        "LICENSE",
        "THIRD_PARTY.md",
        "include/kissm.h",
        "src/sources.cmake",
        "third_party/nanoflann/nanoflann.hpp",
        "third_party/nanoflann/LICENSE",
    ):
        assert needed in copied, needed
        assert (dest / needed).read_bytes() == (REPO_ROOT / needed).read_bytes(), needed
    assert {path.split("/")[0] for path in copied} == {
        "CMakeLists.txt",
        "LICENSE",
        "THIRD_PARTY.md",
        "cmake",
        "include",
        "src",
        "third_party",
    }


def test_sync_keeps_unchanged_files_and_removes_stale_ones(vendor_core: ModuleType, tmp_path: Path) -> None:
    dest = tmp_path / "_core"
    vendor_core.vendor(REPO_ROOT, dest)
    header = dest / "include" / "kissm.h"
    os.utime(header, (1_000_000, 1_000_000))  # an old timestamp a rewrite would replace
    stale = dest / "src" / "gone.cpp"
    stale.write_text("// removed from the repository\n")
    changed = dest / "cmake" / "kissm.pc.in"
    changed.write_text("edited\n")
    assert vendor_core.vendor(REPO_ROOT, dest) == 1  # only the edited file is copied again
    assert header.stat().st_mtime == 1_000_000
    assert not stale.exists()
    assert changed.read_bytes() == (REPO_ROOT / "cmake" / "kissm.pc.in").read_bytes()


def test_refuses_a_directory_that_is_not_a_checkout(vendor_core: ModuleType, tmp_path: Path) -> None:
    assert not vendor_core.is_checkout(tmp_path)
    assert vendor_core.main(["--repo", str(tmp_path), "--dest", str(tmp_path / "_core")]) == 1
    assert not (tmp_path / "_core").exists()
