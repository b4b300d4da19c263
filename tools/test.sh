#!/usr/bin/env bash
# Every test: set up, build, then the C/C++ suite (CTest). Tests that need ../shared/data skip with a
# message when it is absent (point KISSM_DATA_DIR elsewhere to use another copy).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/tools/setup.sh"
data_dir=${KISSM_DATA_DIR:-$here/../shared/data}
bash "$here/tools/build.sh" -DKISSM_DATA_DIR="$data_dir"
build=${KISSM_BUILD_DIR:-$here/build}

echo "== C/C++ tests (CTest) =="
ctest --test-dir "$build" --output-on-failure --parallel 2 --timeout 900

# Language bindings: each has its own script (set-up included) that runs its suite against this build.
for suite in bindings/python/run_tests.sh bindings/rust/run_tests.sh; do
  if [[ -f $here/$suite ]]; then
    echo "== $suite =="
    KISSM_BUILD_DIR=$build KISSM_DATA_DIR=$data_dir bash "$here/$suite"
  fi
done

# Benchmark smoke run (seconds): keeps bench/ from rotting. The full benchmark is `bash bench/run.sh`,
# never a timed test.
if [[ -f $here/bench/bench.py && -x $build/venv-python/bin/python ]]; then
  echo "== bench/bench.py --smoke =="
  KISSM_DATA_DIR=$data_dir "$build/venv-python/bin/python" "$here/bench/bench.py" --smoke --out "$build/bench-smoke"
fi
