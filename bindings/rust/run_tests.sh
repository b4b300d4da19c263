#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Rust binding's tests, run by tools/test.sh (and so by CI) after the C build:
#   1. cargo test --release: the workspace's tests (API, errors, registrations of the shared test scene of
#      tests/data and of variations of it, refinement, the validity rules' settings, real-data registrations
#      and refinements, feature reuse, threads, cancellation, bitwise equality with the C tool and with
#      tests/data/golden.json, the README examples as doc tests and their drift check);
#      KISSM_REQUIRE_TEST_DATA=1 makes a missing tests/data a failure, not a skip;
#   2. the register example against the C tool (register, with and without refinement, and refine from
#      an initial transform) on the demo clouds, the test scene and a KITTI pair when the data is there:
#      the same exit status and the same --json output byte for byte, times and thread count aside;
#   3. the bindgen drift check: regenerates the bindings from include/kissm.h and fails if they differ
#      from the committed kissm-sys/src/bindings.rs. Needs libclang-dev (tools/setup.sh), probed first:
#      under CI=true a failing probe fails the run, elsewhere this step alone is skipped (a recorded SKIP).
#
# Environment: KISSM_BUILD_DIR (the CMake build with the kissm tool and libkissm.a; default build/),
# KISSM_DATA_DIR (default ../shared/data), CARGO_TARGET_DIR (default $KISSM_BUILD_DIR/cargo-target).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
build=$(cd "${KISSM_BUILD_DIR:-$repo/build}" 2>/dev/null && pwd || echo "${KISSM_BUILD_DIR:-$repo/build}")
export KISSM_DATA_DIR=${KISSM_DATA_DIR:-$repo/../shared/data}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$build/cargo-target}
export CARGO_TERM_COLOR=never
# tests/data is part of the checkout: the tests that read it must not skip here.
export KISSM_REQUIRE_TEST_DATA=1
# shellcheck source=../../tools/skips.sh
source "$repo/tools/skips.sh"

# ---------------------------------------------------------------------------------------------------
# Toolchain
# ---------------------------------------------------------------------------------------------------
if ! command -v cargo >/dev/null 2>&1 && [[ -x $HOME/.cargo/bin/cargo ]]; then
  export PATH="$HOME/.cargo/bin:$PATH"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "rust: no Rust toolchain (cargo) found; install it with rustup (https://rustup.rs) to run these tests"
  if [[ ${CI:-} == true ]]; then exit 1; fi
  skip "Rust binding tests" "no cargo (not under CI, so this is not a failure)"
  exit 0
fi
echo "rust: $(cargo --version), $(rustc --version)"

cli=$build/kissm
if [[ -x $cli ]]; then
  export KISSM_CLI=$cli
else
  echo "rust: WARNING: $cli not found; the comparisons with the C tool will be skipped"
  unset KISSM_CLI || true
fi

cd "$here"
t0=$SECONDS

# ---------------------------------------------------------------------------------------------------
# 1. cargo test
# ---------------------------------------------------------------------------------------------------
echo "== rust: cargo test --release (the C++ core is built once by kissm-sys's build.rs) =="
# The tests' SKIP lines (stderr) are recorded for tools/test.sh's list of skips.
errlog=$(mktemp)
{ cargo test --release --locked --workspace 2>&1 1>&3 | tee "$errlog" >&2; } 3>&1
record_skips "$errlog"
rm -f "$errlog"
echo "rust: cargo test took $((SECONDS - t0)) s"

# ---------------------------------------------------------------------------------------------------
# 2. The example against the C tool
# ---------------------------------------------------------------------------------------------------
# The --json output with the values that may differ masked: the times (the "time_ms" object and
# "read_ms") and "threads" (the tool runs with 1 thread, the example with 2: results do not depend on it).
masked_json() {
  sed -e '/^  "time_ms": {$/,/^  }/s/^\(    "[a-z]*": \).*[^,]\(,*\)$/\1T\2/' \
      -e 's/^\(  "read_ms": \).*$/\1T/' \
      -e 's/^\(  "threads": \)[0-9]*,$/\1N,/' "$1"
}

# Runs the tool and the example with the same arguments (the tool with --threads 1, the example with
# --threads 2) and requires the same exit status and the same --json output byte for byte, times and
# thread count aside.
compare_with_tool() {
  local what=$1 command=$2
  shift 2
  local c_status=0 rust_status=0
  "$KISSM_CLI" "$command" "$@" --threads 1 --json >"$work/c.json" || c_status=$?
  # The example has no subcommands: it refines when given --initial, as `kissm refine` needs it.
  "$example" "$@" --threads 2 --json >"$work/rust.json" || rust_status=$?
  if [[ $c_status -ne $rust_status || $c_status -gt 1 ]]; then
    echo "rust: FAIL: exit status C $c_status vs example $rust_status ($what)"
    return 1
  fi
  if ! grep -q '"time_ms": {' "$work/c.json" || ! grep -q '"transform": \[\[' "$work/c.json"; then
    echo "rust: FAIL: the tool's output is not the expected JSON ($what)"
    return 1
  fi
  if ! diff <(masked_json "$work/c.json") <(masked_json "$work/rust.json"); then
    echo "rust: FAIL: the example's --json output differs from the tool's (< C, > Rust; $what)"
    return 1
  fi
  echo "rust: example == C tool byte for byte, times aside ($what)"
}

echo "== rust: the register example against the C tool =="
cargo build --release --locked --example register
example=$CARGO_TARGET_DIR/release/examples/register
if [[ -n ${KISSM_CLI:-} ]]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  "$KISSM_CLI" demo --out "$work/demo" --threads 2 >/dev/null || [[ $? -eq 1 ]]
  scene=$repo/tests/data
  compare_with_tool "demo clouds, voxel 0.3" register "$work/demo/source.ply" "$work/demo/target.ply" --voxel 0.3
  compare_with_tool "demo clouds, voxel 0.3, GICP" register "$work/demo/source.ply" "$work/demo/target.ply" \
    --voxel 0.3 --refine gicp
  compare_with_tool "test scene, voxel 0.25, point-to-plane" register "$scene/roundtrip_source.ply" \
    "$scene/roundtrip_target.ply" --voxel 0.25 --refine point-to-plane
  compare_with_tool "test scene refined from its ground truth, GICP" refine "$scene/roundtrip_source.ply" \
    "$scene/roundtrip_target.ply" --voxel 0.25 --initial "$scene/roundtrip_ground_truth.txt"

  kitti=$KISSM_DATA_DIR/kitti07_keyframes_gtsam_points
  if [[ -f $kitti/000001/points.bin && -f $kitti/000000/points.bin ]]; then
    kitti_args=("$kitti/000001/points.bin" "$kitti/000000/points.bin" --format bin_xyz --voxel 0.5)
    compare_with_tool "KITTI 07 keyframes 000001 -> 000000, voxel 0.5" register "${kitti_args[@]}"
    compare_with_tool "KITTI 07 keyframes 000001 -> 000000, voxel 0.5, GICP" register "${kitti_args[@]}" \
      --refine gicp
  else
    skip "rust example on real data" "$kitti is absent"
  fi
else
  skip "rust example comparison" "no kissm tool at $cli (bash tools/build.sh makes it)"
fi

# ---------------------------------------------------------------------------------------------------
# 3. bindgen drift check
# ---------------------------------------------------------------------------------------------------
echo "== rust: bindgen drift check (kissm-sys/src/bindings.rs vs include/kissm.h) =="
# The probe parses a header including <stddef.h> as bindgen would (tools/probe_libclang.py).
if needs libclang-dev "bindgen drift check"; then
  # Link the C build's static library instead of building the core a second time for this feature set.
  if [[ -f $build/libkissm.a ]]; then
    export KISSM_LIB_DIR=$build KISSM_STATIC=1
  fi
  cargo test --release --locked -p kissm-sys --features bindgen --test bindings_drift
  unset KISSM_LIB_DIR KISSM_STATIC
fi

echo "rust: all Rust steps passed in $((SECONDS - t0)) s"
