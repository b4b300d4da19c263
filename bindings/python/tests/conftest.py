# SPDX-License-Identifier: MIT
"""Shared fixtures: the repository, the real data, the kissm CLI, the committed test pair."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/testdata.py, tests/helpers.py

import kissm  # noqa: E402

import batchcases  # noqa: E402
import testdata  # noqa: E402
from realdata import RealPair, load_pairs  # noqa: E402

TESTS_DIR = Path(__file__).resolve().parent
PACKAGE_ROOT = TESTS_DIR.parent  # bindings/python
REPO_ROOT = PACKAGE_ROOT.parent.parent


def data_dir() -> Path:
    return Path(os.environ.get("KISSM_DATA_DIR") or REPO_ROOT.parent / "shared" / "data")


def cli_path() -> Path | None:
    """The kissm CLI built from the same checkout: $KISSM_CLI, else $KISSM_BUILD_DIR/kissm, else build/kissm."""
    candidates = [os.environ.get("KISSM_CLI")]
    if os.environ.get("KISSM_BUILD_DIR"):
        candidates.append(str(Path(os.environ["KISSM_BUILD_DIR"]) / "kissm"))
    candidates.append(str(REPO_ROOT / "build" / "kissm"))
    for candidate in candidates:
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            return Path(candidate)
    return None


def pytest_report_header(config: pytest.Config) -> list[str]:
    return [
        f"kissm {kissm.__version__} from {Path(kissm.__file__).parent}",
        f"library: {kissm.library_path}",
        f"data: {data_dir()} ({'present' if (data_dir() / 'index.tsv').is_file() else 'absent: real-data tests skip'})",
        f"cli: {cli_path() or 'absent: CLI cross-checks skip'}",
    ]


def _record_skip(nodeid: str, longrepr: object) -> None:
    """Appends a skip to $KISSM_SKIP_LOG (tools/test.sh lists every skip of a run and, under CI, refuses the
    ones tools/allowed-skips.tsv does not name)."""
    log = os.environ.get("KISSM_SKIP_LOG")
    if not log:
        return
    why = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
    why = " ".join(str(why).removeprefix("Skipped: ").split())
    suite = os.environ.get("KISSM_SKIP_SUITE", "pytest")
    with open(log, "a", encoding="utf-8") as f:
        f.write(f"{suite}\t{nodeid}\t{why}\n")


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.skipped and not hasattr(report, "wasxfail"):
        _record_skip(report.nodeid, report.longrepr)


def pytest_collectreport(report: pytest.CollectReport) -> None:
    if report.skipped:  # a module-level importorskip
        _record_skip(report.nodeid, report.longrepr)


@pytest.fixture(scope="session")
def real_data() -> Path:
    root = data_dir()
    if not (root / "index.tsv").is_file():
        pytest.skip(f"real data not found ({root}/index.tsv); set KISSM_DATA_DIR or provide ../shared/data")
    return root


@pytest.fixture(scope="session")
def real_pairs(real_data: Path) -> dict[str, RealPair]:
    """The pairs of the real data's index.tsv, by name."""
    return {p.name: p for p in load_pairs(real_data)}


@pytest.fixture(scope="session")
def cli() -> Path:
    path = cli_path()
    if path is None:
        pytest.skip("the kissm CLI was not found (set KISSM_CLI or KISSM_BUILD_DIR)")
    return path


@pytest.fixture(scope="session")
def demo_clouds(cli: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """source.ply and target.ply (binary float64 PLY) written by `kissm demo`: no real data needed."""
    out = tmp_path_factory.mktemp("demo")
    subprocess.run(
        [str(cli), "demo", "--out", str(out), "--threads", "2"], check=True, capture_output=True, timeout=300
    )
    return out / "source.ply", out / "target.ply"


@pytest.fixture(scope="session")
def pair() -> testdata.Pair:
    """The committed pair of tests/data (shared with the C and Rust suites)."""
    return testdata.committed_pair()


@pytest.fixture(scope="session")
def pairs(pair: testdata.Pair) -> list[testdata.Pair]:
    """The committed pair and three moved, shuffled or noisy variations of it."""
    return testdata.variations(pair)


@pytest.fixture()
def cc() -> str:
    compiler = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if compiler is None:
        pytest.skip("no C compiler")
    return compiler


# ---- the kissm.batch tests (test_batch*.py): their batches and serial results, computed once per module ----


@pytest.fixture(scope="module")
def synthetic() -> batchcases.Batch:
    return batchcases.synthetic_batch()


@pytest.fixture(scope="module")
def synthetic_serial(synthetic: batchcases.Batch) -> list[kissm.Result]:
    return batchcases.serial(synthetic)


@pytest.fixture(scope="module")
def kitti(real_data: Path) -> batchcases.Batch:
    return batchcases.kitti_batch(real_data)


@pytest.fixture(scope="module")
def kitti_serial(kitti: batchcases.Batch) -> list[kissm.Result]:
    return batchcases.serial(kitti)
