#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the API reference of both crates (cargo doc --no-deps --workspace) with every rustdoc warning an
# error (broken intra-doc links, bad code blocks, ...; missing docs are denied in the crates themselves)
# and copies it into OUTDIR: OUTDIR/index.html leads to OUTDIR/kissm/index.html and
# OUTDIR/kissm_sys/index.html.
#
#   bash bindings/rust/docs.sh OUTDIR
#
# Environment: KISSM_BUILD_DIR (a CMake build holding libkissm.a: linked instead of building the C++ core
# again; default build/), CARGO_TARGET_DIR (default $KISSM_BUILD_DIR/cargo-target).
set -euo pipefail
if [[ $# -ne 1 || -z $1 ]]; then
  echo "usage: docs.sh OUTDIR" >&2
  exit 2
fi
out=$1
# shellcheck source=common.sh
source "$(dirname "$0")/common.sh"
link_cmake_build
cd "$here"
# The docs of earlier runs (other crates, removed items) must not end up in OUTDIR.
rm -rf "$CARGO_TARGET_DIR/doc"
RUSTDOCFLAGS="${RUSTDOCFLAGS:-} -D warnings" cargo doc --locked --no-deps --workspace
mkdir -p "$out"
cp -R "$CARGO_TARGET_DIR/doc/." "$out/"
cat >"$out/index.html" <<'HTML'
<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>kissm Rust API</title>
<meta http-equiv="refresh" content="0; url=kissm/index.html"></head>
<body><p><a href="kissm/index.html">kissm</a> (the safe API) and
<a href="kissm_sys/index.html">kissm-sys</a> (the raw FFI).</p></body></html>
HTML
for crate in kissm kissm_sys; do
  if [[ ! -f $out/$crate/index.html ]]; then
    echo "docs.sh: $out/$crate/index.html was not produced" >&2
    exit 1
  fi
done
echo "docs.sh: API reference in $out (open $out/index.html)"
