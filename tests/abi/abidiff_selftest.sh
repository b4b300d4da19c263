#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# abi_abidiff_selftest: proves that check_abi.sh, with the committed kissm.abignore and abidiff's exit
# status handling, accepts the changes docs/abi-policy.md allows and rejects the others. It builds a
# miniature kissm (abidiff_selftest/mini_kissm.{h,c}) once as a baseline and once per kind of change.
#
#   abidiff_selftest.sh CC WORKDIR
#
# Exit status: 0 every verdict as expected, 1 otherwise, 77 skipped (no abidiff / abidw).
set -uo pipefail
if (($# != 2)); then
  echo "usage: $0 CC WORKDIR" >&2
  exit 1
fi
cc=$1 work=$2
for tool in abidiff abidw; do
  if ! command -v "$tool" >/dev/null; then
    echo "SKIP: $tool not found (Debian/Ubuntu: apt-get install abigail-tools)"
    exit 77
  fi
done
here=$(cd "$(dirname "$0")" && pwd)
src=$here/abidiff_selftest
rm -rf "$work"
mkdir -p "$work"

build() { # build NAME [-DMACRO]
  local name=$1
  shift
  mkdir -p "$work/$name"
  "$cc" -g -O0 -fPIC -shared -I"$src" "$@" "$src/mini_kissm.c" -o "$work/$name/libkissm.so.0" \
    -Wl,-soname,libkissm.so.0 || { echo "FAIL: cannot build the $name variant"; exit 1; }
}

build baseline
# Same options as tests/abi/update_baseline.sh uses for the real baseline.
abidw --headers-dir "$src" --drop-private-types --exported-interfaces-only --no-corpus-path \
  --no-comp-dir-path --no-elf-needed --short-locs --type-id-style hash \
  --out-file "$work/baseline.abi" "$work/baseline/libkissm.so.0" || { echo "FAIL: abidw"; exit 1; }

# variant, macros (comma-separated), expected verdict (0 = compatible, 1 = rejected)
cases=(
  "unchanged                 -DMINI_NOTHING                            0"
  "added_function            -DMINI_ADD_FUNCTION                       0"
  "appended_config           -DMINI_APPEND_CONFIG                      0"
  "appended_result           -DMINI_APPEND_RESULT                      0"
  "appended_config_and_fn    -DMINI_APPEND_CONFIG,-DMINI_ADD_FUNCTION  0"
  "appended_points           -DMINI_APPEND_POINTS                      1"
  "reordered_fields          -DMINI_REORDER                            1"
  "changed_field_type        -DMINI_FIELD_TYPE                         1"
  "changed_result_field      -DMINI_RESULT_FIELD_TYPE                  1"
  "appended_and_changed      -DMINI_APPEND_CONFIG,-DMINI_FIELD_TYPE    1"
  "appended_and_reordered    -DMINI_APPEND_CONFIG,-DMINI_REORDER       1"
  "changed_param_type        -DMINI_PARAM_TYPE                         1"
  "changed_return_type       -DMINI_RETURN_TYPE                        1"
  "removed_function          -DMINI_REMOVE_FUNCTION                    1"
)
# Changed #define values are not in debug info: the abi_header_* tests pin them.

failures=0
for c in "${cases[@]}"; do
  read -r name macros expected <<<"$c"
  IFS=, read -r -a flags <<<"$macros"
  build "$name" "${flags[@]}"
  bash "$here/check_abi.sh" "$work/baseline.abi" "$work/$name/libkissm.so.0" "$here/kissm.abignore" \
    >"$work/$name/report.txt" 2>&1
  status=$?
  verdict=$((status == 0 ? 0 : 1))
  if ((status == 77)); then
    echo "SKIP: check_abi.sh skipped: $(tail -1 "$work/$name/report.txt")"
    exit 77
  fi
  if ((verdict == expected)); then
    printf '  ok    %-24s %s\n' "$name" "$( ((verdict)) && echo rejected || echo accepted)"
  else
    printf '  FAIL  %-24s expected %s, got %s; check_abi.sh said:\n' "$name" \
      "$( ((expected)) && echo rejected || echo accepted)" "$( ((verdict)) && echo rejected || echo accepted)"
    sed 's/^/        /' "$work/$name/report.txt"
    failures=$((failures + 1))
  fi
done
if ((failures)); then
  echo "FAIL: $failures verdicts differ from docs/abi-policy.md"
  exit 1
fi
echo "PASS: check_abi.sh accepts additions and appended config/result fields, and rejects every other change"
