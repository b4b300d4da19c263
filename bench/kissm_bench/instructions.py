# SPDX-License-Identifier: MIT
"""Instructions per stage of the default registration path, against a committed baseline: the check that keeps the
next capability from slowing the default path unnoticed.

Wall times on a shared 2-core machine move by 10-30% from run to run; instruction counts under callgrind do not
move at all for the same binary and input (one thread). So the check runs `kissm register` under
``valgrind --tool=callgrind`` on the CLI demo's simulated street pair (no external data; the same scans for the
same seed), once on the default path and once with GICP refinement in the call, and compares the inclusive
instructions of each stage's function with ``bench/results/instructions.json``. A stage more than its tolerance
above the baseline fails the check; one more than that below it asks for the baseline to be renewed, so the next
regression is measured from the gain. Counts are those of one compiler and of the SSE2 kernels (KISSM_SIMD=sse2:
the AVX2 twins of some kernels run only on CPUs that have AVX2): a baseline written with another compiler is
reported and not judged.

    python bench/instruction_check.py                  # check (seconds; run by tools/test.sh)
    python bench/instruction_check.py --update         # write the baseline after a deliberate change
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from .common import REPO, RESULTS, repo_relative

BASELINE = RESULTS / "instructions.json"
#: The scene: the CLI demo's street pair (its default voxel size), one thread.
SEED, VOXEL = 1, 0.3
#: The calls measured: the default path, and GICP refinement in the same call.
CASES = {"default": [], "gicp": ["--refine", "gicp"]}
#: Stage -> the functions whose inclusive instructions it is (callgrind_annotate's demangled names, as regular
#: expressions matched at a name's start after the namespace). The stages are those of kissm_result's time_*_ms.
STAGES: dict[str, tuple[str, ...]] = {
    "voxelize": (r"voxelize\(",),
    "neighbours": (r"radius_neighbors\(",),
    "normals": (r"estimate_normal_sets\(",),
    "fpfh": (r"compute_fpfh\(",),
    "descriptor index": (r"DescriptorIndex::build\(",),
    "matching": (r"match_descriptors\(",),
    "pruning": (r"prune_matches\(",),
    "solver": (r"PoseSolver::solve\(", r"PoseSolver::polish\("),
    "refine": (r"refine_pose\(",),
    "total": (r"kissm_register$",),
}
#: A stage may grow by this fraction of its baseline before the check fails (counts of the same binary are exact;
#: the margin is for harmless changes elsewhere in the code, such as inlining decisions).
TOLERANCE = 0.02
#: Stages below this many instructions are reported, not judged (a few thousand instructions are noise in shares).
SMALL = 2_000_000


def compiler_of(build: Path) -> str:
    """The C++ compiler of a CMake build (its cache), the counts' first condition."""
    cache = build / "CMakeCache.txt"
    if not cache.is_file():
        return "unknown"
    found = {}
    for line in cache.read_text().splitlines():
        for key in ("CMAKE_CXX_COMPILER:", "CMAKE_CXX_COMPILER_ID:", "CMAKE_CXX_COMPILER_VERSION:"):
            if line.startswith(key):
                found[key.split(":")[0]] = line.split("=", 1)[1]
    compiler = found.get("CMAKE_CXX_COMPILER", "")
    if "CMAKE_CXX_COMPILER_VERSION" not in found and compiler:
        out = subprocess.run([compiler, "--version"], capture_output=True, text=True, check=False).stdout
        return out.splitlines()[0] if out else compiler
    return f"{found.get('CMAKE_CXX_COMPILER_ID', '')} {found.get('CMAKE_CXX_COMPILER_VERSION', '')}".strip()


def stage_counts(annotated: str) -> dict[str, int]:
    """The inclusive instructions of each stage from ``callgrind_annotate --inclusive=yes`` output."""
    rows: list[tuple[int, str]] = []
    for line in annotated.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\([\s\d.]+%\)\s+\S*?:(.*?)\s+\[", line)
        if m:
            rows.append((int(m.group(1).replace(",", "")), m.group(2)))
    counts: dict[str, int] = {}
    for stage, patterns in STAGES.items():
        total = 0
        for pattern in patterns:
            regex = re.compile(r"^(?:[\w:]*::)?(?:\(anonymous namespace\)::)?" + pattern)
            # The function itself: not its lambdas when the compiler keeps them apart ("f(...)::{lambda...}"; their
            # instructions are in f's already), nor the std::function wrappers that name f further on.
            total += sum(count for count, name in rows if regex.match(name) and "{lambda" not in name)
        counts[stage] = total
    return counts


def measure(kissm: Path, workdir: Path) -> dict[str, dict[str, int]]:
    """Per case, the instructions of each stage (one thread)."""
    subprocess.run(
        [
            str(kissm),
            "demo",
            "--seed",
            str(SEED),
            "--refine",
            "none",
            "--threads",
            "1",
            "--out",
            str(workdir),
            "--json",
        ],
        check=True,
        capture_output=True,
    )
    out: dict[str, dict[str, int]] = {}
    for case, extra in CASES.items():
        profile = workdir / f"callgrind.{case}.out"
        cmd = [
            "valgrind",
            "--tool=callgrind",
            f"--callgrind-out-file={profile}",
            str(kissm),
            "register",
            str(workdir / "source.ply"),
            str(workdir / "target.ply"),
            "--voxel",
            str(VOXEL),
            "--threads",
            "1",
            *extra,
        ]
        # The SSE2 kernels on every machine: the AVX2 twins run only where the CPU has AVX2 (simd_level.hpp), and a
        # count must not depend on the machine it was taken on.
        subprocess.run(cmd, check=True, capture_output=True, env={**os.environ, "KISSM_SIMD": "sse2"})
        annotated = subprocess.run(
            ["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(profile)],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        out[case] = stage_counts(annotated)
    return out


def judge(baseline: dict[str, Any], now: dict[str, dict[str, int]]) -> tuple[list[str], list[str]]:
    """(failures, notes): stages above the tolerance, and stages so far below it that the baseline is stale."""
    failures: list[str] = []
    notes: list[str] = []
    for case, stages in now.items():
        base = baseline["cases"].get(case, {})
        for stage, count in stages.items():
            before = base.get(stage)
            if before is None or max(before, count) < SMALL:
                continue
            ratio = count / before if before else float("inf")
            if ratio > 1 + TOLERANCE:
                failures.append(
                    f"{case}/{stage}: {count:,} instructions, {ratio - 1:+.1%} on the baseline's {before:,}"
                )
            elif ratio < 1 - TOLERANCE:
                notes.append(f"{case}/{stage}: {count:,} instructions, {ratio - 1:+.1%} on the baseline's {before:,}")
    return failures, notes


def table(baseline: dict[str, Any] | None, now: dict[str, dict[str, int]]) -> str:
    lines = ["| case | stage | baseline | now | change |", "|---|---|--:|--:|--:|"]
    for case, stages in now.items():
        for stage, count in stages.items():
            before = (baseline or {}).get("cases", {}).get(case, {}).get(stage)
            change = f"{count / before - 1:+.2%}" if before else "-"
            lines.append(
                f"| {case} | {stage} | {before:,} | {count:,} | {change} |"
                if before
                else f"| {case} | {stage} | - | {count:,} | {change} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    build = Path(os.environ.get("KISSM_BUILD_DIR") or REPO / "build")
    p.add_argument("--kissm", type=Path, default=build / "kissm", help="the CLI to measure (default: the build's)")
    p.add_argument("--baseline", type=Path, default=BASELINE)
    p.add_argument("--update", action="store_true", help="write the baseline from this run")
    p.add_argument("--out", type=Path, default=None, help="keep the scene, the profiles and the table here")
    p.add_argument("--smoke", action="store_true", help="the test run's call (the check is the same)")
    args = p.parse_args(argv)
    for tool in ("valgrind", "callgrind_annotate"):
        if shutil.which(tool) is None:
            print(f"instruction_check: skipped: {tool} is not installed (bash tools/setup.sh installs it)")
            return 0
    if not args.kissm.is_file():
        print(
            f"instruction_check: {args.kissm} does not exist (build kissm first: bash tools/build.sh)", file=sys.stderr
        )
        return 2
    compiler = compiler_of(args.kissm.parent)
    with tempfile.TemporaryDirectory(prefix="kissm-instructions-") as tmp:
        workdir = args.out or Path(tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        now = measure(args.kissm, workdir)
        baseline = json.loads(args.baseline.read_text()) if args.baseline.is_file() else None
        (workdir / "instructions.md").write_text(table(baseline, now) + "\n")
    print(table(baseline, now))
    if args.update:
        record = {"compiler": compiler, "scene": f"kissm demo --seed {SEED}, voxel {VOXEL}, 1 thread", "cases": now}
        args.baseline.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
        print(f"instruction_check: wrote {repo_relative(args.baseline)}")
        return 0
    if baseline is None:
        print(f"instruction_check: no baseline at {args.baseline} (--update writes it)", file=sys.stderr)
        return 1
    if baseline.get("compiler") != compiler:
        print(
            f"instruction_check: skipped: the baseline was counted with {baseline.get('compiler')}, "
            f"this build uses {compiler}"
        )
        return 0
    failures, notes = judge(baseline, now)
    for line in notes:
        print(f"instruction_check: below the baseline (renew it with --update): {line}")
    for line in failures:
        print(f"instruction_check: FAIL: {line}", file=sys.stderr)
    if failures:
        print(
            "instruction_check: a stage of the default path grew. Find why (callgrind_annotate on the profile); if "
            "the cost is deliberate, say so in docs/design/performance.md and renew the baseline with --update.",
            file=sys.stderr,
        )
        return 1
    print(f"instruction_check: every stage within {TOLERANCE:.0%} of {repo_relative(args.baseline)}")
    return 0
