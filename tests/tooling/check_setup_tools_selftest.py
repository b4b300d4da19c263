#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""check_setup_tools.py finds what it must and only that: run on a miniature repository.

The miniature's scripts call unlisted programs in every place a shell runs one (a pipeline, $(...), <(...),
`command -v`, `env X=1 prog`, `bash -c '...'`, a trap, a subshell) and write unlisted names where no
program runs (here-docs, case patterns, arrays, [[ ... ]], function calls, variables, paths, comments).
The check must exit 1 naming exactly the first set, with file and line, and 0 once they are listed.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

CHECK = Path(__file__).resolve().with_name("check_setup_tools.py")

HEADER = "group\tpackage\tprograms\tprobe\twhy\n"

SCRIPT = r"""#!/usr/bin/env bash
# frob_comment would be a program if comments were read
set -euo pipefail
helper() { echo "$1"; }
listed --version
frob_plain --x
cat file | frob_pipe
x=$(frob_subst arg)
diff <(frob_procsub) file
if command -v frob_probe >/dev/null; then :; fi
env -u HOME X=1 frob_env arg
bash -c 'frob_bashc "$1"' _ y
trap 'frob_trap' EXIT
( cd /tmp && frob_subshell )
helper arg
"$x"/bin/tool arg
$x arg
./local_script.sh
arr=(frob_array other)
[[ -n $x && frob_test == y ]] && echo ok
((x > 1)) || true
case $x in
  frob_case) listed ;;
  *) frob_in_case ;;
esac
cat <<EOF
frob_heredoc
EOF
for frob_for in a b; do listed; done
y="frob_quoted"
listed 2>&1 | listed >/dev/null
"""

EXPECTED = {
    "frob_plain": 6,
    "frob_pipe": 7,
    "frob_subst": 8,
    "frob_procsub": 9,
    "frob_probe": 10,
    "frob_env": 11,
    "frob_bashc": 12,
    "frob_trap": 13,
    "frob_subshell": 14,
    "frob_in_case": 24,
}

CMAKE = """cmake_minimum_required(VERSION 3.16)
find_program(FOUND_LISTED listed)
find_program(FOUND_OTHER frob_cmake)
find_program(FOUND_NAMES NAMES frob_names1 frob_names2 DOC "frob_doc")
"""


def run(root: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECK), "--root", str(root)], capture_output=True, text=True)


def main() -> int:
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "tools").mkdir()
        (root / "tests" / "sub").mkdir(parents=True)
        (root / "tools" / "packages.tsv").write_text(HEADER + "g\tpkg\tlisted\ttrue\tthe one listed program\n")
        (root / "tests" / "sub" / "a.sh").write_text(SCRIPT)
        (root / "CMakeLists.txt").write_text(CMAKE)
        got = run(root)
        if got.returncode != 1:
            failures.append(f"unlisted programs: exit {got.returncode}, not 1")
        found = {}
        for line in got.stderr.splitlines():
            where, _, rest = line.partition(": ")
            name = rest.split("'")[1] if "'" in rest else rest
            found[name] = where
        want = {n: f"tests/sub/a.sh:{ln}" for n, ln in EXPECTED.items()}
        want.update(
            {n: "CMakeLists.txt:" + str(k) for n, k in [("frob_cmake", 3), ("frob_names1", 4), ("frob_names2", 4)]}
        )
        for name, where in want.items():
            if found.get(name) != where:
                failures.append(f"{name}: reported at {found.get(name)}, expected {where}")
        for name in sorted(set(found) - set(want)):
            failures.append(f"{name} reported at {found[name]}, where no program runs")

        # Once the programs are listed (setup's table or a sourced helper's function), the check passes.
        programs = ",".join(["listed", *EXPECTED, "frob_cmake", "frob_names1", "frob_names2"])
        (root / "tools" / "packages.tsv").write_text(HEADER + f"g\tpkg\t{programs}\ttrue\tall listed\n")
        got = run(root)
        if got.returncode != 0:
            failures.append(f"all listed: exit {got.returncode}, not 0: {got.stderr.strip()}")

        # A function is a program nowhere but in the scripts that define or source it.
        (root / "tools" / "lib.sh").write_text("shared_fn() { :; }\n")
        (root / "tools" / "user.sh").write_text('source "$(dirname "$0")/lib.sh"\nshared_fn\n')
        (root / "tools" / "other.sh").write_text("shared_fn\n")
        got = run(root)
        if got.returncode != 1 or "tools/other.sh:1: calls 'shared_fn'" not in got.stderr or "user.sh" in got.stderr:
            failures.append(f"functions of sourced scripts: exit {got.returncode}: {got.stderr.strip()}")

    for f in failures:
        print(f"FAIL {f}", file=sys.stderr)
    if not failures:
        print(f"check_setup_tools selftest: {len(want)} unlisted calls found at their lines, nothing else")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
