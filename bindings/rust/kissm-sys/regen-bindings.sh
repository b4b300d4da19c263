#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Regenerates src/bindings.rs from include/kissm.h with the exact bindgen options of build.rs (feature
# "bindgen"; needs libclang, e.g. Debian's libclang-dev). Commit the result; the drift check
# (tests/bindings_drift.rs, run by bindings/rust/run_tests.sh) fails whenever the two differ.
#
# Set KISSM_LIB_DIR=<a build folder holding libkissm.a> and KISSM_STATIC=1 to skip building the C++ core.
set -euo pipefail
cd "$(dirname "$0")/.."
KISSM_BLESS=1 cargo test -p kissm-sys --features bindgen --test bindings_drift -- --nocapture
git diff --stat -- kissm-sys/src/bindings.rs 2>/dev/null || true
