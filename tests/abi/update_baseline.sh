#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Regenerates the committed ABI baselines of tests/abi from a build tree:
#   kissm.symbols  the exported symbols of libkissm.so        (checked by abi_exports)
#   kissm.abi      libabigail's description of libkissm.so   (checked by abi_abidiff)
#   layout.json    sizes, offsets and types of the structs    (checked by abi_layout_json; read by the
#                  Python and Rust tests)
#
#   tests/abi/update_baseline.sh [BUILD_DIR]     (default: build, or $KISSM_BUILD_DIR)
#
# When: kissm.abi and kissm.symbols at a release, after the tests passed against the previous baseline
# (additions only) or after a deliberate, version-bumped ABI break; layout.json whenever fields were
# appended (with tests/abi/layout_table.h). Never to make a failing ABI test pass: read
# docs/abi-policy.md first, and review `git diff tests/abi` (a removed or changed line is a break).
#
# kissm.abi is written from the debug-info copy of libkissm.so the tests build (kissm_abi_probe), with:
#   abidw --headers-dir include --drop-private-types --exported-interfaces-only --no-corpus-path
#         --no-comp-dir-path --no-elf-needed --no-show-locs --short-locs --type-id-style hash
#         --out-file tests/abi/kissm.abi BUILD_DIR/tests/abi/probe/libkissm.so
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${1:-${KISSM_BUILD_DIR:-$root/build}}
build=$(cd "$build" && pwd)

probe=$build/tests/abi/probe/libkissm.so
layout=$build/tests/abi/abi_layout
shared=$build/libkissm.so
for f in "$probe" "$layout" "$shared"; do
  if [[ ! -e $f ]]; then
    echo "update_baseline: $f not found: configure with -DKISSM_BUILD_TESTS=ON and build first" >&2
    echo "  (cmake --build $build --target kissm kissm_abi_probe abi_layout)" >&2
    exit 1
  fi
done
command -v abidw >/dev/null || {
  echo "update_baseline: abidw not found (Debian/Ubuntu: apt-get install abigail-tools)" >&2
  exit 1
}

cmake -DNM="$(command -v nm)" -DLIBRARY="$shared" -DSYMBOLS="$here/kissm.symbols" \
  -DHEADER="$root/include/kissm.h" -DUPDATE=1 -P "$here/check_exports.cmake"

abidw --headers-dir "$root/include" --drop-private-types --exported-interfaces-only --no-corpus-path \
  --no-comp-dir-path --no-elf-needed --no-show-locs --short-locs --type-id-style hash \
  --out-file "$here/kissm.abi" "$probe"
echo "-- wrote $here/kissm.abi ($(grep -c "<function-decl name='kissm_" "$here/kissm.abi") functions)"

"$layout" --json >"$here/layout.json"
echo "-- wrote $here/layout.json"

git -C "$root" diff --stat -- tests/abi/kissm.symbols tests/abi/kissm.abi tests/abi/layout.json || true
