#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Every skip of a tools/test.sh run in one list, each judged against tools/allowed-skips.tsv.

    python3 tools/skip_report.py SKIP_LOG [--junit SUITE=FILE ...] [--ci]

SKIP_LOG holds "SUITE<TAB>WHAT<TAB>WHY" lines (tools/skips.sh, the pytest hook of bindings/python/tests,
the SKIP lines of cargo test). Each --junit file is CTest's JUnit report of one suite: its skipped tests
join the list, with the SKIP line of their output as the reason. A skip is legitimate only when a row of
tools/allowed-skips.tsv matches its suite and text; with --ci (tools/test.sh under CI=true) any other skip
fails the run, because it means something tools/setup.sh provides did not work or a check did not run.
"""

from __future__ import annotations

import fnmatch
import re
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

ALLOWED = Path(__file__).resolve().parent / "allowed-skips.tsv"


@dataclass(frozen=True)
class Skip:
    suite: str
    what: str
    why: str


@dataclass(frozen=True)
class Rule:
    suites: str
    pattern: re.Pattern[str]
    reason: str


def read_rules(path: Path) -> list[Rule]:
    rules = []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        suites, pattern, reason = line.split("\t")
        if suites == "suites":
            continue  # the header
        rules.append(Rule(suites, re.compile(pattern), reason))
    return rules


def read_log(path: Path) -> list[Skip]:
    if not path.is_file():
        return []
    skips = []
    for line in path.read_text(errors="replace").splitlines():
        parts = line.split("\t", 2)
        if len(parts) == 3:
            skips.append(Skip(*parts))
    return skips


def read_junit(suite: str, path: Path) -> list[Skip]:
    """CTest's skipped tests (status "notrun" with a <skipped/> element), with the SKIP line they printed."""
    if not path.is_file():
        return [Skip(suite, "the CTest JUnit report", f"{path} was not written")]
    skips = []
    for case in ET.parse(path).getroot().iter("testcase"):
        if case.find("skipped") is None:
            continue
        out = case.findtext("system-out") or ""
        lines = [ln.strip() for ln in out.splitlines() if ln.strip()]
        why = next((ln for ln in lines if ln.startswith("SKIP")), lines[-1] if lines else "no output")
        skips.append(Skip(suite, f"ctest {case.get('name')}", why))
    return skips


def judge(skip: Skip, rules: list[Rule]) -> Rule | None:
    text = f"{skip.what}: {skip.why}"
    for rule in rules:
        if any(fnmatch.fnmatchcase(skip.suite, s) for s in rule.suites.split(",")) and rule.pattern.search(text):
            return rule
    return None


def main(argv: list[str]) -> int:
    args = list(argv)
    ci = "--ci" in args
    if ci:
        args.remove("--ci")
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    skips = read_log(Path(args.pop(0)))
    while args:
        flag = args.pop(0)
        if flag != "--junit" or not args or "=" not in args[0]:
            print(f"skip_report: bad argument {flag!r}", file=sys.stderr)
            return 2
        suite, file = args.pop(0).split("=", 1)
        skips += read_junit(suite, Path(file))

    rules = read_rules(ALLOWED)
    refused = 0
    print(f"== skipped ({len(skips)}; legitimate ones are listed with their reason in tools/allowed-skips.tsv) ==")
    for skip in skips:
        rule = judge(skip, rules)
        print(f"  [{skip.suite}] {skip.what}: {skip.why}")
        if rule:
            print(f"      legitimate: {rule.reason}")
        else:
            refused += 1
            print("      NOT LEGITIMATE: a check that should run did not (no row of tools/allowed-skips.tsv)")
    if not skips:
        print("  (nothing)")
    if refused and ci:
        print(f"skip_report: FAIL: {refused} skip(s) not allowed under CI=true", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
