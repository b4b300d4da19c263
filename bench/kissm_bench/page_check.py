# SPDX-License-Identifier: MIT
"""The committed pages of docs/reports/ are what their committed results render: each page is rewritten from its
file in bench/results/ into a temporary folder and compared with the committed page, line by line. The plots are
left out of the comparison (a machine without matplotlib writes a note where the picture would be, and PNG bytes
depend on matplotlib's version); every table and sentence must be the same. Run by tools/test.sh with the bench
smokes: a page edited by hand, or results committed without their page, fail it."""

from __future__ import annotations

import argparse
import difflib
import re
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .common import REPORTS, RESULTS
from .results import read

# A plot's line in a page (a Markdown picture) or the note a page writes without matplotlib.
PLOT_LINE = re.compile(r"^(!\[[^\]]*\]\([^)]*\)|\(No plot[^)]*\)\.?)\s*$")


def _benchmarks(results: dict[str, Any], out: Path) -> Path:
    from .reports.benchmarks import write_all

    write_all(results, out)
    return out / "benchmarks.md"


def _scan_to_map(results: dict[str, Any], out: Path) -> Path:
    from .reports.scan_to_map import write_report

    write_report(results, out)
    return out / "scan_to_map.md"


def _ground(results: dict[str, Any], out: Path) -> Path:
    from .reports.ground import write_report

    write_report(results, out)
    return out / "ground.md"


def _batch(page: str) -> Callable[[dict[str, Any], Path], Path]:
    def write(results: dict[str, Any], out: Path) -> Path:
        from .reports.batch import write_report

        return write_report(results, out / page)

    return write


#: results file in bench/results/ -> (its page in docs/reports/, the writer of that page)
PAGES: dict[str, tuple[str, Callable[[dict[str, Any], Path], Path]]] = {
    "latest.json.gz": ("benchmarks.md", _benchmarks),
    "map_latest.json.gz": ("scan_to_map.md", _scan_to_map),
    "ground_latest.json.gz": ("ground.md", _ground),
    "batch_latest.json.gz": ("batch-throughput.md", _batch("batch-throughput.md")),
    "batch_coarse_latest.json.gz": ("batch-throughput-coarse.md", _batch("batch-throughput-coarse.md")),
    "batch_long_latest.json.gz": ("batch-throughput-long.md", _batch("batch-throughput-long.md")),
}


def text_lines(path: Path) -> list[str]:
    """A page's lines without its plots, and without the blank lines that surround them."""
    kept = [line for line in path.read_text().splitlines() if not PLOT_LINE.match(line)]
    squeezed: list[str] = []
    for line in kept:
        if line.strip() or (squeezed and squeezed[-1].strip()):
            squeezed.append(line)
    while squeezed and not squeezed[-1].strip():
        squeezed.pop()
    return squeezed


def check(results_dir: Path, reports_dir: Path) -> list[str]:
    """Every page that differs from what its results render, with a short diff; none when all agree."""
    problems: list[str] = []
    committed = sorted(p.name for p in results_dir.glob("*.json.gz"))
    for name in sorted(set(committed) - set(PAGES)):
        problems.append(f"{results_dir / name}: no page is rendered from it (kissm_bench/page_check.py's PAGES)")
    for name, (page, write) in PAGES.items():
        saved, page_path = results_dir / name, reports_dir / page
        if not saved.is_file() or not page_path.is_file():
            problems.append(f"{page_path} or its results {saved} is missing")
            continue
        with tempfile.TemporaryDirectory(prefix="kissm-page-check-") as tmp:
            rendered = text_lines(write(read(saved), Path(tmp)))
        mine = text_lines(page_path)
        if rendered != mine:
            diff = list(difflib.unified_diff(mine, rendered, str(page_path), f"rendered from {saved}", lineterm=""))
            problems.append("\n".join(diff[:40]))
    return problems


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    p.add_argument("--results", type=Path, default=RESULTS, help="the folder of the saved results")
    p.add_argument("--reports", type=Path, default=REPORTS, help="the folder of the committed pages")
    args = p.parse_args(argv)
    problems = check(args.results, args.reports)
    for problem in problems:
        print(problem, file=sys.stderr)
    if problems:
        print(f"page_check: {len(problems)} page(s) differ from their results", file=sys.stderr)
        return 1
    print(f"page_check: the {len(PAGES)} pages of {args.reports} are what their results render")
    return 0
