#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The C/C++ suite under AddressSanitizer + UndefinedBehaviorSanitizer (every test except the ABI ones,
# which check the binary rather than its behaviour), then the concurrency tests under ThreadSanitizer.
# Presets in CMakePresets.json; build trees build-asan/ and build-tsan/. Any finding fails the run.
#   bash tools/sanitize.sh [asan|tsan]     (default: both)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
data_dir=${KISSM_DATA_DIR:-$here/../shared/data}
which=${1:-all}
cd "$here"

if [[ $which == all || $which == asan ]]; then
  echo "== C/C++ tests under ASan + UBSan =="
  cmake --preset asan-ubsan -DKISSM_DATA_DIR="$data_dir" >/dev/null
  cmake --build --preset asan-ubsan
  ctest --preset asan-ubsan --parallel 2 --timeout 900 --output-junit "$here/build-asan/ctest-junit.xml"
fi

if [[ $which == all || $which == tsan ]]; then
  echo "== concurrency tests under TSan =="
  cmake --preset tsan -DKISSM_DATA_DIR="$data_dir" >/dev/null
  # Only what the preset runs: the tests labelled "concurrency".
  mapfile -t targets < <(ctest --test-dir build-tsan -N -L concurrency | sed -n 's/^ *Test *#[0-9]*: //p')
  cmake --build --preset tsan --target "${targets[@]}"
  ctest --preset tsan --parallel 2 --timeout 900 --output-junit "$here/build-tsan/ctest-junit.xml"
fi
