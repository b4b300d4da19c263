#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Lint of the Rust binding; fails on any finding:
#   1. cargo fmt --check (rustfmt.toml of this workspace);
#   2. cargo clippy --workspace --all-targets -- -D warnings (library, tests, examples, build script);
#   3. the same clippy run of kissm-sys with the bindgen feature (the code generator in build.rs and the
#      drift test), when libclang is installed (otherwise a SKIP line for this step only);
#   4. shellcheck of this folder's scripts, when shellcheck is installed (otherwise a SKIP line).
#
# Environment: KISSM_BUILD_DIR (a CMake build holding libkissm.a: linked instead of building the C++ core
# again; default build/), CARGO_TARGET_DIR (default $KISSM_BUILD_DIR/cargo-target).
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "$0")/common.sh"
# Clippy only type-checks, so the already built static library saves building the C++ core here.
link_cmake_build
cd "$here"

echo "== rust lint: cargo fmt --check =="
cargo fmt --all --check

echo "== rust lint: cargo clippy --workspace --all-targets -- -D warnings =="
cargo clippy --locked --workspace --all-targets -- -D warnings

echo "== rust lint: cargo clippy -p kissm-sys --features bindgen =="
libclang=""
for dir in ${LIBCLANG_PATH:-} /usr/lib/llvm-*/lib /usr/lib/x86_64-linux-gnu /usr/lib/aarch64-linux-gnu /usr/lib64 /usr/lib; do
  if compgen -G "$dir/libclang*.so*" >/dev/null; then
    libclang=$dir
    break
  fi
done
if [[ -n $libclang ]]; then
  cargo clippy --locked -p kissm-sys --features bindgen --all-targets -- -D warnings
else
  echo "SKIP clippy with the bindgen feature: libclang not found (apt-get install libclang-dev)"
fi

echo "== rust lint: shellcheck =="
if command -v shellcheck >/dev/null 2>&1; then
  shellcheck -x ./*.sh kissm-sys/*.sh
else
  echo "SKIP shellcheck: not installed (apt-get install shellcheck)"
fi
echo "rust lint: all passed"
