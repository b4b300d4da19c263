#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Lint of the Rust binding; fails on any finding:
#   1. cargo fmt --check (rustfmt.toml of this workspace);
#   2. cargo clippy --workspace --all-targets -- -D warnings (library, tests, examples, build script);
#   3. the same clippy run of kissm-sys with the bindgen feature (the code generator in build.rs and the
#      drift test), which needs libclang-dev;
#   4. shellcheck of this folder's scripts.
# Steps 3 and 4 need what tools/setup.sh installs (libclang-dev, shellcheck), probed first: under CI=true a
# probe that fails fails the script; elsewhere the step is skipped with a recorded SKIP line (tools/skips.sh).
#
# Environment: KISSM_BUILD_DIR (a CMake build holding libkissm.a: linked instead of building the C++ core
# again; default build/), CARGO_TARGET_DIR (default $KISSM_BUILD_DIR/cargo-target).
set -euo pipefail
# shellcheck source=common.sh
source "$(dirname "$0")/common.sh"
# shellcheck source=../../tools/skips.sh
source "$repo/tools/skips.sh"
# Clippy only type-checks, so the already built static library saves building the C++ core here.
link_cmake_build
cd "$here"

echo "== rust lint: cargo fmt --check =="
cargo fmt --all --check

echo "== rust lint: cargo clippy --workspace --all-targets -- -D warnings =="
cargo clippy --locked --workspace --all-targets -- -D warnings

echo "== rust lint: cargo clippy -p kissm-sys --features bindgen =="
# The probe parses a header including <stddef.h> with the libclang bindgen would load: a libclang file
# without clang's builtin headers (Debian's libclang1-14, which doxygen brings) fails it, as bindgen would.
if needs libclang-dev "clippy with the bindgen feature"; then
  cargo clippy --locked -p kissm-sys --features bindgen --all-targets -- -D warnings
fi

echo "== rust lint: shellcheck =="
if needs shellcheck "shellcheck of bindings/rust"; then
  shellcheck -x ./*.sh kissm-sys/*.sh
fi
echo "rust lint: all passed"
