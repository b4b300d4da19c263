# SPDX-License-Identifier: MIT
# shellcheck shell=bash
# Sourced by lint.sh, docs.sh and package_test.sh. Sets `here` (bindings/rust), `repo` and `build`
# (KISSM_BUILD_DIR, default build/), exports CARGO_TARGET_DIR (default $build/cargo-target) and puts
# ~/.cargo/bin on PATH when cargo is not found otherwise.
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/../.." && pwd)
build=${KISSM_BUILD_DIR:-$repo/build}
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$build/cargo-target}
export CARGO_TERM_COLOR=never
if ! command -v cargo >/dev/null 2>&1 && [[ -x $HOME/.cargo/bin/cargo ]]; then
  export PATH="$HOME/.cargo/bin:$PATH"
fi

# Links the CMake build's libkissm.a instead of building the C++ core again (for steps that only check,
# document or lint the Rust code), when that build has it.
link_cmake_build() {
  if [[ -f $build/libkissm.a ]]; then
    export KISSM_LIB_DIR=$build KISSM_STATIC=1
  fi
}
