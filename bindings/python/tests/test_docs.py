# SPDX-License-Identifier: MIT
"""The README examples run as written: every ```python block of the repository's README.md and of
bindings/python/README.md, executed in order, on the committed test pair saved under the file names the
examples use. The result they end with must be valid and close to the pair's ground truth."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import kissm

import testdata
from conftest import PACKAGE_ROOT, REPO_ROOT
from testdata import rotation_error_deg

#: The READMEs with Python examples. Outside the repository (tests run from an installed wheel or sdist)
#: they are absent and the test skips; inside it, a README without a Python example fails.
DOCS = {"README.md": REPO_ROOT / "README.md", "bindings/python/README.md": PACKAGE_ROOT / "README.md"}

#: The scans the examples read, and the committed files that stand in for them.
STAND_INS = {"scan_001.ply": testdata.SOURCE, "scan_000.ply": testdata.TARGET}


def python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_python_blocks_are_found() -> None:
    text = "intro\n```python\na = 1\n```\n```sh\nls\n```\n```python\nb = 2\n```\n"
    assert python_blocks(text) == ["a = 1\n", "b = 2\n"]


# A deprecated name in a README example is an error.
@pytest.mark.filterwarnings("error::DeprecationWarning")
@pytest.mark.parametrize("name", ["README.md", "bindings/python/README.md"])
def test_examples_run(name: str, pair: testdata.Pair, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    doc = DOCS[name]
    if not doc.is_file():
        pytest.skip(f"{doc} not found: the tests run outside the kissm repository")
    blocks = python_blocks(doc.read_text(encoding="utf-8"))
    assert blocks, f"no ```python example in {doc}"
    for stand_in, committed in STAND_INS.items():
        shutil.copyfile(testdata.data_dir() / committed, tmp_path / stand_in)
    monkeypatch.chdir(tmp_path)
    printed: list[tuple[object, ...]] = []
    namespace: dict[str, object] = {
        "__name__": "__readme__",
        "map_xyz": pair.target,  # names the examples leave to the reader
        "scans": [pair.source],
        "print": lambda *args, **_: printed.append(args),
    }
    for number, block in enumerate(blocks, 1):
        exec(compile(block, f"{doc} (python block {number})", "exec"), namespace)
    result = namespace.get("result")
    assert isinstance(result, kissm.Result), f"the examples in {doc} leave no kissm.Result in `result`"
    assert result.valid, result
    assert rotation_error_deg(result.rotation, pair.rotation) < 3.0
    assert np.linalg.norm(result.translation - pair.translation) < 0.3
