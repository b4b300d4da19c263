#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# abi_abidiff: compares a freshly built libkissm.so (with debug info) against the committed ABI baseline
# tests/abi/kissm.abi with libabigail's abidiff, and fails on any change that is not an addition.
#
#   check_abi.sh BASELINE.abi LIBRARY.so SUPPRESSIONS [SYMBOLS]
#
# Policy (docs/abi-policy.md, "What the abidiff test accepts"): only additions pass.
#  - added functions are compatible: --no-added-syms leaves them out of the verdict;
#  - fields appended at the end of kissm_config / kissm_result are compatible: kissm.abignore suppresses
#    them in pass 1, and pass 2 checks that appending is all that happened to these two structs;
#  - anything else abidiff reports fails, whatever its exit bits: 8 (ABIDIFF_ABI_INCOMPATIBLE_CHANGE: a
#    removed symbol) and also 4 (ABIDIFF_ABI_CHANGE: a changed parameter, return or field type, a moved or
#    removed field, a grown kissm_points, ...). libabigail sets only bit 4 for most type changes because
#    some are harmless in some libraries; under our rules none is. Bits 1 and 2 (abidiff's own error or
#    usage error) fail too.
# abidiff_selftest.sh proves these verdicts on a miniature library, one kind of change at a time.
# SYMBOLS (tests/abi/kissm.symbols), when given, must all be described by the library's debug info:
# otherwise abidiff could only compare symbol names and would miss type changes.
#
# Exit status: 0 compatible, 1 incompatible or error, 77 skipped (no abidiff / abidw, or not x86-64: the
# baseline describes the x86-64 ABI).
set -uo pipefail

if (($# < 3 || $# > 4)); then
  echo "usage: $0 BASELINE.abi LIBRARY.so SUPPRESSIONS [SYMBOLS]" >&2
  exit 1
fi
baseline=$1 library=$2 suppressions=$3 symbols=${4:-}

for tool in abidiff abidw; do
  if ! command -v "$tool" >/dev/null; then
    echo "SKIP: $tool not found. Install libabigail's tools (Debian/Ubuntu: apt-get install abigail-tools;" \
         "tools/setup.sh does it when run as root) to check the ABI against tests/abi/kissm.abi."
    exit 77
  fi
done
baseline_arch=$(grep -o -m1 "architecture='[^']*'" "$baseline" | cut -d"'" -f2)
if [[ $baseline_arch == elf-amd-x86_64 && $(uname -m) != x86_64 ]]; then
  echo "SKIP: $baseline describes the x86-64 ABI; this machine is $(uname -m)"
  exit 77
fi
for f in "$baseline" "$library" "$suppressions"; do
  [[ -r $f ]] || { echo "FAIL: cannot read $f"; exit 1; }
done

echo "abidiff $(abidiff --version | awk '{print $2}'): $baseline vs $library"

if [[ -n $symbols ]]; then
  dump=$(abidw --exported-interfaces-only --drop-private-types --no-show-locs "$library") || {
    echo "FAIL: abidw could not read $library"
    exit 1
  }
  missing=()
  while read -r name; do
    [[ -z $name || $name == \#* ]] && continue
    grep -q "<function-decl name='$name'" <<<"$dump" || missing+=("$name")
  done <"$symbols"
  if ((${#missing[@]})); then
    echo "FAIL: no debug info for ${missing[*]} in $library: build it with -g (the kissm_abi_probe target" \
         "compiles src/capi with -g; an exported function defined elsewhere needs the same)"
    exit 1
  fi
fi

fail_break() {
  cat <<EOF
FAIL: $1
The shared library is no longer compatible with the baseline $baseline, so programs built against an
earlier libkissm.so would break. Undo the change, or make it compatible (add a new function instead of
changing one; append fields only at the end of kissm_config / kissm_result). A deliberate break needs a
new major version and SOVERSION, then a new baseline: docs/abi-policy.md and tests/abi/update_baseline.sh.
EOF
  exit 1
}

# Pass 1: everything except the members of kissm_config / kissm_result (suppressed when they grow).
report=$(abidiff --no-added-syms --fail-no-debug-info --suppressions "$suppressions" "$baseline" "$library" 2>&1)
status=$?
echo "$report"
if ((status & 3)); then
  echo "FAIL: abidiff itself failed (exit status $status: 1 = error, 2 = usage error)"
  exit 1
fi
if ((status != 0)); then
  what=()
  ((status & 8)) && what+=("an incompatible change (8)")
  ((status & 4)) && what+=("an ABI change (4)")
  fail_break "abidiff exit status $status: ${what[*]}."
fi

# Pass 2: kissm_config and kissm_result may only have grown by fields at the end. libabigail's
# has_data_member_inserted_at suppression (pass 1) also hides a changed member type in a struct that did
# not shrink, so read abidiff's leaf-change report of these two structs without suppressions: every line
# must be a size increase or an insertion at an offset at or past the old size. Any other line (a
# changed, moved or removed member, another type, or a report format this check does not know) fails.
leaf=$(abidiff --leaf-changes-only --no-added-syms --fail-no-debug-info "$baseline" "$library" 2>&1)
status=$?
if ((status & 3)); then
  echo "$leaf"
  echo "FAIL: abidiff itself failed (exit status $status)"
  exit 1
fi
if ((status != 0)); then
  verdict=$(awk -v q="'" '
    function bad(why) { print "  " why ": " $0; failed = 1 }
    substr($0, 1, 1) == q {
      block = index($0, q "struct kissm_config ") == 1 || index($0, q "struct kissm_result ") == 1 ||
              index($0, q "struct kissm_config" q) == 1 || index($0, q "struct kissm_result" q) == 1
      old = -1
      if (!block) bad("not a kissm_config / kissm_result change")
      next
    }
    !block || /^[ \t]*$/ { next }
    /^  type size changed from [0-9]+ to [0-9]+ \(in bits\)$/ {
      old = $5 + 0
      if ($7 + 0 <= old) bad("the struct did not grow")
      next
    }
    /^  [0-9]+ data member insertions?:$/ { next }
    /, at offset [0-9]+ \(in bits\)/ && substr($0, 1, 5) == "    " q {
      offset = $0
      sub(/.*, at offset /, "", offset)
      sub(/ .*/, "", offset)
      if (old < 0 || offset + 0 < old) bad("a field inserted before the old end")
      next
    }
    { bad("not an insertion at the end") }
    END { if (!failed) print "ok" }' <<<"$leaf")
  if [[ $verdict != ok ]]; then
    echo "$leaf"
    fail_break "kissm_config / kissm_result changed other than by fields appended at the end:
$verdict"
  fi
  echo "kissm_config / kissm_result: only fields appended at the end (compatible)"
fi
echo "PASS: the ABI is compatible with the baseline (additions only)"
exit 0
