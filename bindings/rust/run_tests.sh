#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Rust binding's tests, run by tools/test.sh (and so by CI) after the C build:
#   1. cargo test --release: the workspace's tests (API, errors, registrations of the shared test scene of
#      tests/data and of variations of it, real-data registrations, feature reuse, threads, cancellation,
#      bitwise equality with the C tool and with tests/data/golden.json, the README example as a doc test
#      and its drift check); KISSM_REQUIRE_TEST_DATA=1 makes a missing tests/data a failure, not a skip;
#   2. the register example against the C tool on the demo clouds (and a KITTI pair when the data is
#      there): same transform bit for bit, same valid and final_inliers;
#   3. the bindgen drift check: regenerates the bindings from include/kissm.h and fails if they differ
#      from the committed kissm-sys/src/bindings.rs. Needs libclang: installed with apt-get when run as
#      root, otherwise (or when that fails) this step alone is skipped with a SKIP line.
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

# ---------------------------------------------------------------------------------------------------
# Toolchain
# ---------------------------------------------------------------------------------------------------
if ! command -v cargo >/dev/null 2>&1 && [[ -x $HOME/.cargo/bin/cargo ]]; then
  export PATH="$HOME/.cargo/bin:$PATH"
fi
if ! command -v cargo >/dev/null 2>&1; then
  echo "rust: no Rust toolchain (cargo) found; install it with rustup (https://rustup.rs) to run these tests"
  if [[ ${CI:-} == true ]]; then exit 1; fi
  echo "SKIP: Rust binding tests (not under CI, so this is not a failure)"
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
cargo test --release --locked --workspace
echo "rust: cargo test took $((SECONDS - t0)) s"

# ---------------------------------------------------------------------------------------------------
# 2. The example against the C tool
# ---------------------------------------------------------------------------------------------------
# Prints the 16 transform values, valid and final_inliers of a --json output, one per line.
json_summary() {
  local file=$1
  sed -n 's/^ *"transform": *//p' "$file" | tr -d '[],' | tr -s ' ' '\n' | sed '/^$/d'
  sed -n 's/^  "valid": *\([a-z]*\),*$/valid \1/p' "$file"
  sed -n 's/^  "final_inliers": *\([0-9]*\),*$/final_inliers \1/p' "$file"
}

# Compares two --json outputs: equal doubles (parsed, so 1e-05 and 0.00001 are the same number), the
# same validity and final inliers, and the example's output has the tool's keys.
compare_outputs() {
  local c_json=$1 rust_json=$2 what=$3
  local key
  for key in valid reason transform rotation translation final_inliers counts time_ms; do
    if ! grep -q "^  \"$key\":" "$rust_json"; then
      echo "rust: FAIL: the example's JSON has no \"$key\" ($what)"
      return 1
    fi
  done
  local c_lines rust_lines
  c_lines=$(json_summary "$c_json")
  rust_lines=$(json_summary "$rust_json")
  if [[ $(wc -l <<<"$c_lines") -ne 18 || $(wc -l <<<"$rust_lines") -ne 18 ]]; then
    echo "rust: FAIL: could not read transform/valid/final_inliers from both outputs ($what)"
    return 1
  fi
  # awk compares fields that look numeric as doubles (strtod: correctly rounded), others as strings.
  if ! paste -d ' ' <(echo "$c_lines") <(echo "$rust_lines") | awk '
      NF == 2 { if (!($1 == $2)) { printf "  C %s vs Rust %s\n", $1, $2; bad = 1 } }
      NF == 4 { if ($1 != $3 || $2 != $4) { printf "  C %s %s vs Rust %s %s\n", $1, $2, $3, $4; bad = 1 } }
      END { exit bad }'; then
    echo "rust: FAIL: the example's result differs from the C tool's ($what)"
    return 1
  fi
  echo "rust: example == C tool bit for bit: transform, valid, final_inliers ($what)"
}

echo "== rust: the register example against the C tool =="
cargo build --release --locked --example register
example=$CARGO_TARGET_DIR/release/examples/register
if [[ -n ${KISSM_CLI:-} ]]; then
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  "$KISSM_CLI" demo --out "$work/demo" --threads 2 >/dev/null || [[ $? -eq 1 ]]
  set +e
  "$KISSM_CLI" register "$work/demo/source.ply" "$work/demo/target.ply" --voxel 0.3 --threads 1 --json >"$work/c.json"
  c_status=$?
  "$example" "$work/demo/source.ply" "$work/demo/target.ply" --voxel 0.3 --threads 2 --json >"$work/rust.json"
  rust_status=$?
  set -e
  if [[ $c_status -ne $rust_status ]]; then
    echo "rust: FAIL: exit status C $c_status vs example $rust_status (demo clouds)"
    exit 1
  fi
  compare_outputs "$work/c.json" "$work/rust.json" "demo clouds, voxel 0.3"

  kitti=$KISSM_DATA_DIR/kitti07_keyframes_gtsam_points
  if [[ -f $kitti/000001/points.bin && -f $kitti/000000/points.bin ]]; then
    set +e
    "$KISSM_CLI" register "$kitti/000001/points.bin" "$kitti/000000/points.bin" --format bin_xyz --voxel 0.5 \
      --threads 1 --json >"$work/c_kitti.json"
    "$example" "$kitti/000001/points.bin" "$kitti/000000/points.bin" --format bin_xyz --voxel 0.5 \
      --threads 2 --json >"$work/rust_kitti.json"
    set -e
    compare_outputs "$work/c_kitti.json" "$work/rust_kitti.json" "KITTI 07 keyframes 000001 -> 000000, voxel 0.5"
  else
    echo "SKIP rust example on real data: $kitti is absent"
  fi
else
  echo "SKIP rust example comparison: no kissm tool"
fi

# ---------------------------------------------------------------------------------------------------
# 3. bindgen drift check
# ---------------------------------------------------------------------------------------------------
have_libclang() {
  local dir
  if [[ -n ${LIBCLANG_PATH:-} ]] && compgen -G "$LIBCLANG_PATH/libclang*.so*" >/dev/null; then return 0; fi
  for dir in /usr/lib/llvm-*/lib /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu /usr/lib64 /usr/lib \
             /usr/local/lib; do
    if compgen -G "$dir/libclang.so" >/dev/null || compgen -G "$dir/libclang-*.so" >/dev/null; then
      return 0
    fi
  done
  return 1
}

echo "== rust: bindgen drift check (kissm-sys/src/bindings.rs vs include/kissm.h) =="
if ! have_libclang && [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null 2>&1; then
  echo "rust: installing libclang-dev for the drift check"
  if ! { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libclang-dev >/dev/null; }; then
    echo "rust: could not install libclang-dev"
  fi
fi
if have_libclang; then
  # Link the C build's static library instead of building the core a second time for this feature set.
  if [[ -f $build/libkissm.a ]]; then
    export KISSM_LIB_DIR=$build KISSM_STATIC=1
  fi
  cargo test --release --locked -p kissm-sys --features bindgen --test bindings_drift
  unset KISSM_LIB_DIR KISSM_STATIC
else
  echo "SKIP bindgen drift check: libclang not found and not installable here (apt-get install libclang-dev)"
fi

echo "rust: all Rust steps passed in $((SECONDS - t0)) s"
