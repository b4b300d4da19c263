#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the libFuzzer targets (clang, ASan + UBSan; CMakePresets.json "fuzz") and runs each for a while,
# starting from the committed seed corpus. Not part of CI (minutes per target); the seed corpus and the
# regressions are replayed by normal CTest instead.
#   bash tools/fuzz.sh [SECONDS_PER_TARGET=600] [TARGET...]      (targets: ply pcd npy xyz kitti_bin
#                                                                  bin_xyz las register stateful features pose_graph
#                                                                  sequence_loops)
# Findings land in build-fuzz/findings/<target>/; copy a crasher to tests/fuzz/regressions/<target>/ once
# fixed. The grown corpus stays in build-fuzz/corpus/<target>/.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-600}
shift || true
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(ply pcd npy xyz kitti_bin bin_xyz las register stateful features pose_graph sequence_loops)

# clang and libFuzzer: tools/setup.sh's on-demand group "fuzz" (installed as root, else named).
bash "$here/tools/setup.sh" --group fuzz || exit 2
cd "$here"
# KISSM_FUZZ_NO_BUILD=1: use the binaries as built (several fuzz.sh running side by side must not
# reconfigure one build tree at the same time: build once, then start them with this set).
if [[ ${KISSM_FUZZ_NO_BUILD:-0} != 1 ]]; then
  cmake --preset fuzz >/dev/null
  fuzz_targets=()
  for t in "${targets[@]}"; do fuzz_targets+=("fuzz_$t"); done
  cmake --build --preset fuzz --target "${fuzz_targets[@]}"
fi

for t in "${targets[@]}"; do
  corpus=build-fuzz/corpus/$t findings=build-fuzz/findings/$t
  mkdir -p "$corpus" "$findings"
  cp -n tests/fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
  if [[ -d tests/fuzz/regressions/$t ]]; then
    cp -n tests/fuzz/regressions/"$t"/* "$corpus"/ 2>/dev/null || true
  fi
  echo "== fuzz_$t for ${seconds}s =="
  # 64 KiB inputs, 2 GiB RSS, 30 s per input; ASan/UBSan findings abort the run.
  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    build-fuzz/tests/fuzz/fuzz_"$t" "$corpus" -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=2048 \
    -timeout=30 -print_final_stats=1 -artifact_prefix="$findings/" 2>&1 | tee build-fuzz/fuzz_"$t".log |
    grep -E "^(#[0-9]+ *DONE|stat::number_of_executed_units|==[0-9]+==ERROR|SUMMARY|INFO: Running with)" || true
  if ls "$findings"/* >/dev/null 2>&1; then
    echo "fuzz_$t: FINDINGS in $findings" >&2
  fi
done
