# SPDX-License-Identifier: MIT
"""``kissm.io``'s optional dependencies: ``import kissm`` imports none of them, and a reader called without its
dependency raises ``ModuleNotFoundError`` naming the extra that installs it (no dependency needed: the import is
made to fail)."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import kissm
import kissm._optional


def test_import_kissm_imports_no_optional_dependency() -> None:
    code = "import sys, kissm, kissm.io; print(sorted({'laspy', 'lazrs', 'pye57', 'rosbags'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120)
    assert out.stdout.strip() == "[]"


@pytest.fixture()
def nothing_optional(monkeypatch: pytest.MonkeyPatch) -> None:
    real = importlib.import_module

    def refuse(name: str, package: str | None = None) -> Any:
        if name.split(".")[0] in ("pye57", "rosbags"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return real(name, package)

    monkeypatch.setattr(kissm._optional.importlib, "import_module", refuse)


@pytest.mark.usefixtures("nothing_optional")
def test_missing_dependencies_name_their_extra(tmp_path: Path) -> None:
    with pytest.raises(ModuleNotFoundError) as caught:
        kissm.io.read_e57(tmp_path / "x.e57")
    assert str(caught.value) == (
        "reading and writing E57 needs the Python package pye57: pip install kissm[e57] (No module named 'pye57')"
    )
    with pytest.raises(ModuleNotFoundError, match=r"^reading and writing E57 needs .*pip install kissm\[e57\]"):
        kissm.io.write_e57_poses(tmp_path / "x.e57", tmp_path / "y.e57", np.eye(4)[None])
    with pytest.raises(ModuleNotFoundError) as caught:
        kissm.io.read_bag(tmp_path / "x.bag")
    assert str(caught.value) == (
        "reading ROS bags and MCAP needs the Python package rosbags: pip install kissm[ros] "
        "(No module named 'rosbags.highlevel')"
    )
