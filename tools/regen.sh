#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Regenerates every committed generated file from its source, or (--check) fails when one is out of date:
#
#   file                                      from                          by
#   bindings/python/src/kissm/_cdef.h         include/kissm.h               bindings/python/tools/gen_cdef.py
#   tests/abi/layout_table.h                  include/kissm.h + compiler    tools/gen_layout_table.py
#   tests/abi/layout.json                     the built library's layout    BUILD/tests/abi/abi_layout --json
#   tests/abi/kissm.symbols                   libkissm.so's exports         tests/abi/check_exports.cmake
#   tests/abi/kissm.abi                       libkissm.so (libabigail)      abidw (abigail-tools, tools/setup.sh)
#   tests/data/golden.json                    the round-trip registration   BUILD/tests/roundtrip/roundtrip_golden
#   bindings/rust/kissm-sys/src/bindings.rs   include/kissm.h (bindgen)     bindings/rust/kissm-sys/regen-bindings.sh
#
#   bash tools/regen.sh [BUILD_DIR]            rewrite them (BUILD_DIR default build/, or $KISSM_BUILD_DIR)
#   bash tools/regen.sh --check [BUILD_DIR]    compare fresh copies with the committed files; exit 1 on a diff
#
# BUILD_DIR must be built with the tests (tools/build.sh). The Rust bindings need cargo and libclang: --check
# leaves them to the Rust suite's drift test (bindings/rust/run_tests.sh), and a rewrite without libclang says
# so and fails. The ABI files and the golden file are results of the library: a diff there is a change of
# ABI or of results, to be read (docs/abi-policy.md), never regenerated blindly to make a test pass. The
# CTest test `generated_files_current` runs --check.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=skips.sh
source "$here/tools/skips.sh"
check=0
if [[ ${1:-} == --check ]]; then
  check=1
  shift
fi
build=$(cd "${1:-${KISSM_BUILD_DIR:-$here/build}}" && pwd)
python=${PYTHON:-python3}

failures=()
stale() {
  echo "regen: $1 is out of date (bash tools/regen.sh rewrites it)" >&2
  failures+=("$1")
}
# compare FRESH COMMITTED: a diff means the committed file is stale.
compare() {
  if ! cmp -s "$2" "$1"; then
    diff -u "$2" "$1" | head -n 40 >&2 || true
    stale "${2#"$here"/}"
  fi
}
need() {
  if [[ ! -x $1 ]]; then
    echo "regen: $1 not found: build the tree with its tests first (bash tools/build.sh)" >&2
    exit 1
  fi
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# ---- from the header ---------------------------------------------------------------------------------
echo "== regen: cdef and layout table (from include/kissm.h)"
if ((check)); then
  "$python" "$here/bindings/python/tools/gen_cdef.py" --check >&2 || failures+=(bindings/python/src/kissm/_cdef.h)
  "$python" "$here/tools/gen_layout_table.py" --check || failures+=(tests/abi/layout_table.h)
else
  "$python" "$here/bindings/python/tools/gen_cdef.py" --write
  "$python" "$here/tools/gen_layout_table.py"
fi

# ---- from the built library ------------------------------------------------------------------------------
echo "== regen: ABI baselines and golden file (from $build)"
need "$build/tests/abi/abi_layout"
need "$build/tests/roundtrip/roundtrip_golden"
"$build/tests/abi/abi_layout" --json >"$work/layout.json"
cp "$here/tests/abi/kissm.symbols" "$work/kissm.symbols"
cmake -DNM="$(command -v nm)" -DLIBRARY="$build/libkissm.so" -DSYMBOLS="$work/kissm.symbols" \
  -DHEADER="$here/include/kissm.h" -DUPDATE=1 -P "$here/tests/abi/check_exports.cmake" >/dev/null
"$build/tests/roundtrip/roundtrip_golden" "$here/tests/data" --write >"$work/golden.json"
have_abidw=0
if [[ ! -e $build/tests/abi/probe/libkissm.so ]]; then
  skip "tests/abi/kissm.abi" "$build has no ABI probe library (tests/abi/probe/libkissm.so: a Linux GCC/Clang build)"
elif needs abigail-tools "tests/abi/kissm.abi"; then
  have_abidw=1
  abidw --headers-dir "$here/include" --drop-private-types --exported-interfaces-only --no-corpus-path \
    --no-comp-dir-path --no-elf-needed --no-show-locs --short-locs --type-id-style hash \
    --out-file "$work/kissm.abi" "$build/tests/abi/probe/libkissm.so"
fi
for f in tests/abi/layout.json tests/abi/kissm.symbols tests/data/golden.json tests/abi/kissm.abi; do
  fresh=$work/$(basename "$f")
  [[ -f $fresh ]] || continue
  if ((check)); then
    compare "$fresh" "$here/$f"
  elif ! cmp -s "$fresh" "$here/$f"; then
    cp "$fresh" "$here/$f"
    echo "regen: wrote $f"
  fi
done

# ---- the Rust bindings ----------------------------------------------------------------------------------
if ((check)); then
  echo "regen: bindings/rust/kissm-sys/src/bindings.rs is checked by the Rust suite (tests/bindings_drift.rs)"
else
  echo "== regen: Rust bindings (bindgen)"
  (cd "$here/bindings/rust" && CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$build/cargo-target} KISSM_LIB_DIR=$build KISSM_STATIC=1 \
    bash kissm-sys/regen-bindings.sh)
fi

if ((${#failures[@]})); then
  echo "regen: ${#failures[@]} generated file(s) out of date: ${failures[*]}" >&2
  exit 1
fi
if ((check)); then
  echo "regen: every generated file is current$( ((have_abidw)) || echo ' (kissm.abi not checked: no abidw)')"
fi
