"""The README examples run as written (on synthetic scans saved under the names they use)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import kissm

from conftest import PACKAGE_ROOT

DOCS = [PACKAGE_ROOT / "README_SECTION.md", PACKAGE_ROOT / "README.md"]


def write_ply(path: Path, xyz: np.ndarray) -> None:
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(xyz)}\n"
        "property double x\nproperty double y\nproperty double z\nend_header\n"
    )
    path.write_bytes(header.encode() + np.ascontiguousarray(xyz, dtype="<f8").tobytes())


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_examples_run(doc: Path, pair, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    if not doc.is_file():
        pytest.skip(f"{doc} not found")
    blocks = python_blocks(doc)
    assert blocks, f"no python example in {doc}"
    write_ply(tmp_path / "scan_001.ply", pair.source)
    write_ply(tmp_path / "scan_000.ply", pair.target)
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"map_xyz": pair.target, "scans": [pair.source], "print": lambda *a: None}
    for block in blocks:
        exec(compile(block, str(doc), "exec"), namespace)
    result = namespace["result"]
    assert isinstance(result, kissm.Result) and result.valid


def test_ply_writer_round_trip(pair, tmp_path: Path) -> None:
    write_ply(tmp_path / "a.ply", pair.source)
    assert np.array_equal(kissm.read_points(tmp_path / "a.ply"), pair.source)
