#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Every test: set up, build, then the C/C++ suite (CTest), the same suite under ASan + UBSan and the
# concurrency tests under TSan, the Python binding (pytest), a seconds-long benchmark smoke run and the
# Rust binding (cargo test). Tests that need ../shared/data skip with a
# message when it is absent (point KISSM_DATA_DIR elsewhere to use another copy).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/tools/setup.sh"
data_dir=${KISSM_DATA_DIR:-$here/../shared/data}
bash "$here/tools/build.sh" -DKISSM_DATA_DIR="$data_dir"
build=${KISSM_BUILD_DIR:-$here/build}

echo "== C/C++ tests (CTest) =="
ctest --test-dir "$build" --output-on-failure --parallel 2 --timeout 900

run_suite() {
  if [[ -f $here/$1 ]]; then
    echo "== $1 =="
    KISSM_BUILD_DIR=$build KISSM_DATA_DIR=$data_dir bash "$here/$1"
  fi
}

# The same C/C++ suite under ASan + UBSan, and the concurrency tests under TSan (separate build trees).
# KISSM_SKIP_SANITIZERS=1 skips them for a quick local run; CI never sets it.
if [[ ${KISSM_SKIP_SANITIZERS:-0} != 1 ]]; then
  bash "$here/tools/sanitize.sh"
fi

# Python binding (its own venv in $build/venv-python, set up by the script).
run_suite bindings/python/run_tests.sh

# Benchmark smoke run (seconds, in the Python binding's venv): keeps bench/ from rotting. The full
# benchmark is `bash bench/run.sh`, never a timed test.
if [[ -f $here/bench/bench.py && -x $build/venv-python/bin/python ]]; then
  echo "== bench/bench.py --smoke =="
  KISSM_DATA_DIR=$data_dir "$build/venv-python/bin/python" "$here/bench/bench.py" --smoke --out "$build/bench-smoke"
fi

# Rust binding (cargo test), last so that a test runner's summary closes the log.
run_suite bindings/rust/run_tests.sh
