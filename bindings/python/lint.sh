#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Lint of the Python binding: `ruff check` and `ruff format --check` on the package, its tests and tools,
# and `mypy --strict` on the package (settings in pyproject.toml). Any finding fails the script.
#
# The tools are pinned and live in their own venv, made on the first run and reused after it:
# $KISSM_LINT_VENV, default ${KISSM_BUILD_DIR:-<repo>/build}/venv-lint. PYTHON picks the interpreter.
# Nothing is built: mypy reads the sources (numpy and cffi are installed for their types).
set -euo pipefail
package=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$package/../.." && pwd)
build=${KISSM_BUILD_DIR:-$repo/build}
venv=${KISSM_LINT_VENV:-$build/venv-lint}
python=${PYTHON:-python3}

# Pinned: a new release of a linter must not fail a build that passed yesterday.
tools=(ruff==0.17.5 mypy==2.4.1 numpy==2.4.6 cffi==2.1.1)

if ! "$venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$venv"
  mkdir -p "$(dirname "$venv")"
  "$python" -m venv "$venv"
fi
# pip is quick when everything pinned is already there.
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "${tools[@]}"

cd "$package"
status=0
run() {
  echo "lint: $*"
  "$venv/bin/$1" "${@:2}" || status=1
}
run ruff check --no-cache src/kissm tests tools
run ruff format --check --no-cache src/kissm tests tools
run mypy --strict --cache-dir "$venv/mypy-cache" src/kissm
if ((status != 0)); then
  echo "lint: findings above (ruff format src/kissm tests tools fixes the formatting ones)" >&2
fi
exit "$status"
