#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Every test: set up, build, then
#   1. the linters (tools/lint.sh: clang-format, shellcheck, SPDX lines, whitespace, ruff, mypy, rustfmt,
#      clippy), first because they take seconds;
#   2. the C/C++ suite (CTest: per stage, C API, readers, CLI, real data, ABI, reliability, the .deb and
#      .tar.gz install test, the README's C snippet, the Doxygen build), the LAZ reader built in
#      (tools/laz_check.sh), then the same suite under ASan + UBSan and the concurrency tests under TSan;
#   3. the Python binding: pytest against `pip install ./bindings/python`, then its packages (sdist and
#      manylinux wheel, each installed into a fresh venv and tested there);
#   4. a seconds-long benchmark smoke run;
#   5. the API references (tools/docs.sh: Doxygen, pdoc, cargo doc, warnings are errors);
#   6. the Rust binding: cargo test, then both crates packaged and tested from their unpacked archives.
# Tests that need ../shared/data skip with a message when it is absent (point KISSM_DATA_DIR elsewhere to
# use another copy). KISSM_SKIP_SANITIZERS=1 skips step 2's sanitizer builds for a quick local run; CI
# never sets it. Under CI=true nothing that setup provides may skip (tools/allowed-skips.tsv lists the rest).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
# Each step's wall time, on stderr at its end and in a table at the end of a green run: the whole command
# must stay within CI's budget (35 minutes on 2 cores), and this says where the time goes.
# Every skip of every step lands in $KISSM_SKIP_LOG (tools/skips.sh; the pytest hook of bindings/python/tests;
# cargo's SKIP lines), tagged with the step's name; CTest's skips come from its JUnit reports. The list is
# printed beside the time table, and under CI=true a skip that tools/allowed-skips.tsv does not name fails
# the run: whatever setup provides must run, not skip.
# shellcheck source=tools/skips.sh
source "$here/tools/skips.sh"
step_log=()
step() {
  local name=$1 start=$SECONDS
  shift
  KISSM_SKIP_SUITE=$name "$@"
  step_log+=("$(printf '%6d s  %s' $((SECONDS - start)) "$name")")
  echo "== step '$name' took $((SECONDS - start)) s ==" >&2
}
build=${KISSM_BUILD_DIR:-$here/build}
mkdir -p "$build"
export KISSM_SKIP_LOG=$build/skips.tsv
: >"$KISSM_SKIP_LOG"
step setup bash "$here/tools/setup.sh"
data_dir=${KISSM_DATA_DIR:-$here/../shared/data}
step build bash "$here/tools/build.sh" -DKISSM_DATA_DIR="$data_dir"
export KISSM_BUILD_DIR=$build KISSM_DATA_DIR=$data_dir
junit=(--junit "ctest=$build/ctest-junit.xml")

echo "== tools/lint.sh =="
step lint bash "$here/tools/lint.sh"

echo "== C/C++ tests (CTest) =="
step ctest ctest --test-dir "$build" --output-on-failure --parallel 2 --timeout 900 \
  --output-junit "$build/ctest-junit.xml"

# The LAZ reader (KISSM_WITH_LAZ=ON, off by default): the readers and their tests only, in build-laz/.
step laz bash "$here/tools/laz_check.sh"
junit+=(--junit "laz=$here/build-laz/ctest-junit.xml")

if [[ ${KISSM_SKIP_SANITIZERS:-0} != 1 ]]; then
  step "asan+ubsan" bash "$here/tools/sanitize.sh" asan
  step tsan bash "$here/tools/sanitize.sh" tsan
  junit+=(--junit "asan=$here/build-asan/ctest-junit.xml" --junit "tsan=$here/build-tsan/ctest-junit.xml")
fi

run_suite() {
  echo "== $1 =="
  step "$1" bash "$here/$1"
}

# Python binding (its own venv in $build/venv-python, set up by the script), then its packages.
run_suite bindings/python/run_tests.sh
run_suite bindings/python/package_test.sh

# Benchmark smoke run (seconds, in the Python binding's venv): keeps bench/ from rotting. The full
# benchmark is `bash bench/run.sh`, never a timed test.
# A benchmark's "NAME: skipped: WHY" lines (a peer or the data absent) join the skip list.
bench_smoke() {
  echo "== bench/$1 --smoke =="
  local out=$build/$2.log line
  "$build/venv-python/bin/python" "$here/bench/$1" --smoke --out "$build/$2" | tee "$out"
  while IFS= read -r line; do
    skip "bench/$1 ${line%%: *}" "${line#*skipped: }"
  done < <(grep -E '^[a-z_]+: (.*: )?skipped: ' "$out" || true)
}
step "bench.py --smoke" bench_smoke bench.py bench-smoke
step "map_bench.py --smoke" bench_smoke map_bench.py map-bench-smoke
step "ground_bench.py --smoke" bench_smoke ground_bench.py ground-bench-smoke
step "batch_bench.py --smoke" bench_smoke batch_bench.py batch-bench-smoke
step "batch_accounting.py --smoke" bench_smoke batch_accounting.py batch-accounting-smoke
# The default path's instructions per stage (callgrind) against bench/results/instructions.json: a stage that grew
# fails the run, so the next capability cannot slow the default path unnoticed.
step "instruction_check.py --smoke" bench_smoke instruction_check.py instruction-check
# The committed pages of docs/reports/ are what the committed results of bench/results/ render (tables and text).
step "check_pages.py" "$build/venv-python/bin/python" "$here/bench/check_pages.py"

echo "== tools/docs.sh =="
step docs bash "$here/tools/docs.sh"

# Rust binding (cargo test), then its crates from their own archives; last but the time table, so that a
# test runner's summary is near the end of the log.
run_suite bindings/rust/run_tests.sh
run_suite bindings/rust/package_test.sh

echo "== time per step (total $SECONDS s) =="
printf '%s\n' "${step_log[@]}"
ci=()
if [[ ${CI:-} == true ]]; then ci=(--ci); fi
python3 "$here/tools/skip_report.py" "$KISSM_SKIP_LOG" "${junit[@]}" "${ci[@]}"
