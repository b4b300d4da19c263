#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The crates build and pass their tests from their own archives, outside the repository:
#   1. kissm-sys/vendor.sh copies the C/C++ core, LICENSE and THIRD_PARTY.md into the crates, and
#      `cargo package --workspace --no-verify` makes both .crate files (cargo resolves kissm's dependency
#      on the unpublished kissm-sys through its local overlay of the packaged crate); the copies are
#      removed again right after, so the repository build never uses them;
#   2. the archives' contents are checked: licence files, README, the vendored core (and no tests/,
#      bench/ or docs/ of the repository in it);
#   3. both archives are unpacked into an empty temporary folder, with a throwaway workspace manifest
#      there that lists them and patches crates-io's kissm-sys to the unpacked one (the repository's
#      Cargo.lock pins the other dependencies);
#   4. `cargo test --release --workspace` runs there: kissm-sys builds the vendored core with CMake
#      (nothing of the repository is visible from there; the script checks that CMake's source folder
#      was the archive's vendor/kissm), and kissm's tests, doc tests and example run against it. The test
#      data comes from a copy of tests/data (KISSM_TEST_DATA) and of tests/abi/layout.json
#      (KISSM_ABI_LAYOUT), with KISSM_REQUIRE_TEST_DATA=1 so that those tests cannot pass by skipping;
#      the C tool (KISSM_CLI, from KISSM_BUILD_DIR) and the real data (KISSM_DATA_DIR) are used when
#      present. Only the comparison with the repository's README.md is skipped there (it has no README).
#
# Environment: KISSM_BUILD_DIR (default build/; for the kissm tool), KISSM_DATA_DIR (default
# ../shared/data), CARGO_TARGET_DIR (default $KISSM_BUILD_DIR/cargo-target; only `cargo package` writes
# there, the build and tests use a target folder inside the temporary folder).
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "$0")/common.sh"
# shellcheck source=../../tools/skips.sh
source "$repo/tools/skips.sh"
export KISSM_DATA_DIR=${KISSM_DATA_DIR:-$repo/../shared/data}
t0=$SECONDS
if ! command -v cargo >/dev/null 2>&1; then
  echo "rust package test: no Rust toolchain (cargo) found" >&2
  exit 1
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/kissm-crates.XXXXXX")
cleanup() {
  bash "$here/kissm-sys/vendor.sh" --clean >/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

# ---------------------------------------------------------------------------------------------------
# 1. Package
# ---------------------------------------------------------------------------------------------------
echo "== rust package: vendor the core and cargo package --workspace =="
bash "$here/kissm-sys/vendor.sh"
package_dir=$CARGO_TARGET_DIR/package
rm -f "$package_dir"/kissm-*.crate
# --allow-dirty: what is tested is the working tree, committed or not (and vendor/ is git-ignored).
(cd "$here" && cargo package --workspace --no-verify --allow-dirty --locked)
bash "$here/kissm-sys/vendor.sh" --clean
sys_crate=$(compgen -G "$package_dir/kissm-sys-*.crate")
safe_crate=$(compgen -G "$package_dir/kissm-[0-9]*.crate")

# ---------------------------------------------------------------------------------------------------
# 2. Contents
# ---------------------------------------------------------------------------------------------------
check_contents() {
  local crate=$1
  shift
  local listing name file
  listing=$(tar -tzf "$crate")
  name=$(basename "$crate" .crate)
  for file in "$@"; do
    if ! grep -qx "$name/$file" <<<"$listing"; then
      echo "rust package: FAIL: $(basename "$crate") has no $file" >&2
      return 1
    fi
  done
  if grep -E "^$name/vendor/kissm/(tests|bench|docs|bindings|build)/" <<<"$listing" | head -3 | grep -q .; then
    echo "rust package: FAIL: $(basename "$crate") carries more of the repository than the core" >&2
    return 1
  fi
  echo "rust package: $(basename "$crate"): $(wc -l <<<"$listing") files, $(du -k "$crate" | cut -f1) KiB"
}
sys_files=(LICENSE THIRD_PARTY.md README.md build.rs src/lib.rs src/bindings.rs vendor/kissm/CMakeLists.txt
  vendor/kissm/LICENSE vendor/kissm/THIRD_PARTY.md vendor/kissm/include/kissm.h vendor/kissm/src/sources.cmake
  vendor/kissm/third_party/nanoflann/nanoflann.hpp vendor/kissm/third_party/nanoflann/LICENSE)
if [[ -f $repo/third_party/eigen/LICENSE.MPL2 ]]; then
  sys_files+=(vendor/kissm/third_party/eigen/LICENSE.MPL2)
fi
check_contents "$sys_crate" "${sys_files[@]}"
check_contents "$safe_crate" LICENSE THIRD_PARTY.md README.md src/lib.rs tests/api.rs tests/register.rs

# ---------------------------------------------------------------------------------------------------
# 3. Unpack into an empty folder outside the repository
# ---------------------------------------------------------------------------------------------------
mkdir -p "$work/crates" "$work/test-data"
tar -xzf "$sys_crate" -C "$work/crates"
tar -xzf "$safe_crate" -C "$work/crates"
sys_name=$(basename "$sys_crate" .crate)
safe_name=$(basename "$safe_crate" .crate)
cat >"$work/crates/Cargo.toml" <<TOML
# Throwaway workspace of package_test.sh: the two unpacked crates, kissm's crates.io dependency on
# kissm-sys patched to the unpacked one.
[workspace]
resolver = "2"
members = ["$sys_name", "$safe_name"]

[patch.crates-io]
kissm-sys = { path = "$sys_name" }
TOML
cp "$here/Cargo.lock" "$work/crates/Cargo.lock"
cp "$repo"/tests/data/roundtrip_* "$repo/tests/data/golden.json" "$work/test-data/"
cp "$repo/tests/abi/layout.json" "$work/test-data/layout.json"

# ---------------------------------------------------------------------------------------------------
# 4. Build and test there
# ---------------------------------------------------------------------------------------------------
echo "== rust package: cargo test --release --workspace in $work/crates =="
unset KISSM_LIB_DIR KISSM_STATIC KISSM_INCLUDE_DIR || true
export KISSM_TEST_DATA=$work/test-data KISSM_ABI_LAYOUT=$work/test-data/layout.json KISSM_REQUIRE_TEST_DATA=1
if [[ -x $build/kissm ]]; then
  export KISSM_CLI=$build/kissm
else
  echo "rust package: WARNING: $build/kissm not found; the comparisons with the C tool will be skipped"
  unset KISSM_CLI || true
fi
# The tests' results (stdout) and the SKIP lines and build output (stderr) apart: interleaved, a SKIP line
# can split a result line that the checks below look for.
log=$work/test.log
errlog=$work/test.stderr.log
set +e
# A target folder of its own inside the temporary folder: builds keyed to this run's temporary path are
# never reused, so they go with it (the C++ core is built again every run, as a user's build would).
(cd "$work/crates" && CARGO_TARGET_DIR=$work/target cargo test --release --locked --workspace >"$log" 2>"$errlog")
status=$?
set -e
cat "$errlog" "$log"
if [[ $status -ne 0 ]]; then
  echo "rust package: FAIL: cargo test in the unpacked crates (exit status $status)" >&2
  exit 1
fi

# The core was built from the archive's vendor/kissm, not from anything else.
if ! grep -qs "CMAKE_HOME_DIRECTORY:INTERNAL=$work/crates/$sys_name/vendor/kissm" \
     "$work"/target/release/build/kissm-sys-*/out/build/CMakeCache.txt; then
  echo "rust package: FAIL: no CMake build of $work/crates/$sys_name/vendor/kissm was found" >&2
  exit 1
fi
for test in scene_registers_accurately registration_errors_carry_code_and_message \
            refine_from_a_perturbed_ground_truth_converges golden_file_matches_bit_for_bit layout_matches_c_abi \
            crate_readme_example_is_the_doc_test; do
  if ! grep -q "^test $test \.\.\. ok$" "$log"; then
    echo "rust package: FAIL: $test did not run and pass from the archive" >&2
    exit 1
  fi
done
if ! grep -Eq "^test $safe_name/src/lib.rs - \(line [0-9]+\) \.\.\. ok$|^test src/lib.rs - \(line [0-9]+\) \.\.\. ok$" "$log"; then
  echo "rust package: FAIL: the README doc test did not run from the archive" >&2
  exit 1
fi
echo "rust package: skipped in the archive run:"
grep '^SKIP' "$errlog" | sed 's/^/  /' || echo "  (nothing)"
record_skips "$errlog"
echo "rust package: both crates build and pass from their archives in $((SECONDS - t0)) s"
