#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Every linter, failing on any finding (run by tools/test.sh, so by CI):
#   clang-format --dry-run -Werror   src, include, tests, examples (style: .clang-format)
#   every shell script of the repository, through shellcheck
#   SPDX lines                       every source file we wrote starts with SPDX-License-Identifier: MIT
#   .editorconfig basics             no trailing whitespace, a final newline, no tabs in source files
#   bindings/python/lint.sh          ruff check, ruff format --check, mypy --strict
#   ruff (ruff.toml)                 ruff check and ruff format --check on bench/, tools/ and tests/, with the
#                                    ruff that bindings/python/lint.sh pins
#   mypy (mypy.ini)                  mypy --strict on bench/ (its scripts and kissm_bench) and tools/*.py, with
#                                    the mypy that bindings/python/lint.sh pins
#   bindings/rust/lint.sh            cargo fmt --check, cargo clippy --all-targets -- -D warnings
#   src/io/laz_rs                    the same two on the LAZ decompressor's C ABI crate (KISSM_WITH_LAZ)
# clang-format and shellcheck come from tools/setup.sh (apt-get as root); the Python tools from PyPI into a
# venv, the Rust ones with the toolchain (rustup components).
#
#   bash tools/lint.sh            all of them
#   bash tools/lint.sh --fix      apply clang-format in place first (then check everything)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
fix=0
if [[ ${1:-} == --fix ]]; then fix=1; fi

failed=()
step() { echo "== lint: $1 =="; }
fail() {
  echo "lint: FAIL: $1" >&2
  failed+=("$1")
}

# ---- tools: clang-format and shellcheck come with tools/setup.sh, probed here (tools/skips.sh: under CI=true
# a tool that does not work fails the run; elsewhere its check is skipped with a recorded SKIP line)
# shellcheck source=skips.sh
source "$here/tools/skips.sh"

# Files git knows (tracked and new, not ignored): the lint sees what a clean clone has.
files() { git ls-files --cached --others --exclude-standard -- "$@" | while read -r f; do [[ -f $f ]] && echo "$f"; done; }

# ---- C and C++ layout --------------------------------------------------------------------------------
if needs clang-format "clang-format"; then
  step "clang-format ($(clang-format --version | sed 's/.*version \([0-9.]*\).*/\1/'))"
  mapfile -t cxx < <(files 'src/*.c' 'src/*.h' 'src/*.cpp' 'src/*.hpp' 'include/*.h' 'tests/*.c' 'tests/*.h' \
    'tests/*.cpp' 'tests/*.hpp' 'examples/*.c' 'examples/*.h' 'examples/*.cpp')
  if ((fix)); then clang-format -i "${cxx[@]}"; fi
  if ! clang-format --dry-run -Werror "${cxx[@]}"; then
    fail "clang-format (bash tools/lint.sh --fix applies it)"
  fi
fi

# ---- shell scripts -----------------------------------------------------------------------------------
if needs shellcheck "shellcheck"; then
  step "shellcheck ($(shellcheck --version | sed -n 's/^version: //p'))"
  mapfile -t scripts < <(files '*.sh' '.ci/run')
  if ! shellcheck -x --source-path=SCRIPTDIR "${scripts[@]}"; then fail "shellcheck"; fi
fi

# ---- licence lines -----------------------------------------------------------------------------------
# Every file we wrote that can hold a comment; generated and third-party files are named here.
step "SPDX-License-Identifier lines"
mapfile -t sources < <(files '*.c' '*.h' '*.cpp' '*.hpp' '*.py' '*.rs' '*.sh' '*.cmake' '*.in' 'CMakeLists.txt' \
  '*.toml' '.ci/run' '.clang-format' '.editorconfig' | grep -v -e '^third_party/' -e '^tests/fuzz/corpus/')
missing=0
for f in "${sources[@]}"; do
  if ! head -n 3 "$f" | grep -q 'SPDX-License-Identifier: MIT'; then
    echo "$f: no 'SPDX-License-Identifier: MIT' in its first three lines" >&2
    missing=1
  fi
done
if ((missing)); then fail "SPDX lines"; fi

# ---- whitespace (.editorconfig) -----------------------------------------------------------------------
step "whitespace (.editorconfig)"
mapfile -t texts < <(files '*.c' '*.h' '*.cpp' '*.hpp' '*.py' '*.rs' '*.sh' '*.cmake' '*.in' '*.toml' '*.json' \
  '*.txt' '*.md' '*.map' '*.yml' 'CMakeLists.txt' '.ci/run' | grep -v -e '^third_party/' -e '^tests/fuzz/corpus/')
ws=0
for f in "${texts[@]}"; do
  if [[ -s $f && $(tail -c 1 "$f" | od -An -c | tr -d ' ') != '\n' ]]; then
    echo "$f: no newline at the end of the file" >&2
    ws=1
  fi
  case $f in
    *.md) ;; # two trailing spaces are a line break in Markdown
    *) if grep -n '[[:blank:]]$' "$f" | head -3 | sed "s|^|$f:|" | grep .; then ws=1; fi ;;
  esac
  case $f in
    *.c | *.h | *.cpp | *.hpp | *.py | *.rs | *.sh | *.toml | *.cmake | CMakeLists.txt)
      if grep -n $'\t' "$f" | head -3 | sed "s|^|$f: tab: |" | grep .; then ws=1; fi
      ;;
  esac
done
if ((ws)); then fail "whitespace"; fi

# ---- the bindings ------------------------------------------------------------------------------------
for sub in bindings/python/lint.sh bindings/rust/lint.sh; do
  step "$sub"
  if ! bash "$sub"; then fail "$sub"; fi
done

# ---- the LAZ decompressor's crate (src/io/laz_rs, built by CMake only with KISSM_WITH_LAZ=ON) ----------------
step "src/io/laz_rs: cargo fmt --check, cargo clippy -- -D warnings"
laz_target=${KISSM_BUILD_DIR:-$here/build}/laz_rs-lint
if ! (cd src/io/laz_rs && cargo fmt --check && CARGO_TARGET_DIR=$laz_target cargo clippy --locked --release --all-targets -- -D warnings); then
  fail "src/io/laz_rs (cargo fmt in src/io/laz_rs fixes the formatting)"
fi

# ---- the repository's own Python outside the package ----------------------------------------------------
# bindings/python/lint.sh made the venv (its pinned ruff and mypy, and numpy for numpy's types); the settings are
# ruff.toml's and mypy.ini's. mypy reads kissm's annotations from bindings/python/src (mypy.ini's mypy_path).
lint_venv=${KISSM_LINT_VENV:-${KISSM_BUILD_DIR:-$here/build}/venv-lint}
ruff_bin=$lint_venv/bin/ruff
step "ruff: bench/ tools/ tests/"
mapfile -t pys < <(files 'bench/*.py' 'tools/*.py' 'tests/*.py')
if [[ ! -x $ruff_bin ]]; then
  fail "ruff: $ruff_bin is missing (bindings/python/lint.sh makes it)"
elif ! "$ruff_bin" check --no-cache "${pys[@]}" || ! "$ruff_bin" format --check --no-cache "${pys[@]}"; then
  fail "ruff on bench/ tools/ tests/ ($ruff_bin format fixes the formatting ones)"
fi

mypy_bin=$lint_venv/bin/mypy
step "mypy: bench/ tools/*.py"
mapfile -t typed < <(files 'bench/*.py' 'tools/*.py')
if [[ ! -x $mypy_bin ]]; then
  fail "mypy: $mypy_bin is missing (bindings/python/lint.sh makes it)"
elif ! "$mypy_bin" --config-file mypy.ini --cache-dir "$lint_venv/mypy-cache-repo" "${typed[@]}"; then
  fail "mypy on bench/ tools/*.py"
fi

if ((${#failed[@]})); then
  echo "lint: ${#failed[@]} check(s) failed: ${failed[*]}" >&2
  exit 1
fi
echo "lint: all checks passed"
