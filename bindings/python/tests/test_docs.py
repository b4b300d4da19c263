# SPDX-License-Identifier: MIT
"""The README examples run as written: every ```python block of the repository's README.md and of
bindings/python/README.md, executed in order, on the committed test pair saved under the file names the
examples use. The result they end with must be valid and close to the pair's ground truth."""

from __future__ import annotations

import importlib.util
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import kissm

import testdata
from conftest import PACKAGE_ROOT, REPO_ROOT
from helpers import python_blocks
from testdata import rotation_error_deg

#: The READMEs with Python examples. Outside the repository (tests run from an installed wheel or sdist)
#: they are absent and the test skips; inside it, a README without a Python example fails.
DOCS = {"README.md": REPO_ROOT / "README.md", "bindings/python/README.md": PACKAGE_ROOT / "README.md"}

#: The scans the examples read, and the committed files that stand in for them.
STAND_INS = {"scan_001.ply": testdata.SOURCE, "scan_000.ply": testdata.TARGET}


#: Modules an example may import that the package does not need (the test extra installs them where they have
#: wheels): a block importing one that is missing is left out, with a warning.
OPTIONAL_MODULES = ("gtsam",)


def missing_optional_modules(block: str) -> list[str]:
    return [
        name
        for name in OPTIONAL_MODULES
        if re.search(rf"^\s*(import|from) {name}\b", block, flags=re.M) and importlib.util.find_spec(name) is None
    ]


def test_python_blocks_are_found() -> None:
    text = "intro\n```python\na = 1\n```\n```sh\nls\n```\n```python\nb = 2\n```\n"
    assert python_blocks(text) == ["a = 1\n", "b = 2\n"]


def test_only_optional_modules_that_are_missing_leave_a_block_out(monkeypatch: pytest.MonkeyPatch) -> None:
    assert missing_optional_modules("import numpy as np\n") == []
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    assert missing_optional_modules("x = 1\nimport gtsam\n") == ["gtsam"]
    assert missing_optional_modules("from gtsam import Pose3\n") == ["gtsam"]
    assert missing_optional_modules("import gtsam_extra\n") == []


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
        missing = missing_optional_modules(block)
        if missing:
            warnings.warn(f"{doc} python block {number} not run: {', '.join(missing)} not installed", stacklevel=1)
            continue
        exec(compile(block, f"{doc} (python block {number})", "exec"), namespace)
    result = namespace.get("result")
    assert isinstance(result, kissm.Result), f"the examples in {doc} leave no kissm.Result in `result`"
    assert result.valid, result
    assert rotation_error_deg(result.rotation, pair.rotation) < 3.0
    assert np.linalg.norm(result.translation - pair.translation) < 0.3
