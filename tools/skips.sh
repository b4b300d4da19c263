# SPDX-License-Identifier: MIT
# shellcheck shell=bash
# Sourced by the test scripts: every skip goes through here, so that tools/test.sh can list them all at the
# end (tools/skip_report.py) and CI can refuse the ones that are not legitimate (tools/allowed-skips.tsv).
#   skip WHAT WHY           prints "SKIP WHAT: WHY" and appends "SUITE<TAB>WHAT<TAB>WHY" to $KISSM_SKIP_LOG
#                           (SUITE: $KISSM_SKIP_SUITE, which tools/test.sh sets to the step's name)
#   record_skips FILE       records every "SKIP WHAT: WHY" line of FILE (a test runner's output)
#   needs PACKAGE WHAT      true when PACKAGE of tools/packages.tsv works (its probe). Otherwise, under
#                           CI=true, FAIL lines and exit 1 (setup provides it: it must not be skipped);
#                           elsewhere a recorded skip of WHAT and false. Use: if needs P "what"; then ...; fi
skips_repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

skip() {
  echo "SKIP $1: $2"
  if [[ -n ${KISSM_SKIP_LOG:-} ]]; then
    printf '%s\t%s\t%s\n' "${KISSM_SKIP_SUITE:-manual}" "$1" "$2" >>"$KISSM_SKIP_LOG"
  fi
}

record_skips() {
  local line what why
  [[ -n ${KISSM_SKIP_LOG:-} && -f $1 ]] || return 0
  while IFS= read -r line; do
    line=${line#SKIP }
    what=${line%%: *}
    why=${line#"$what"}
    printf '%s\t%s\t%s\n' "${KISSM_SKIP_SUITE:-manual}" "$what" "${why#: }" >>"$KISSM_SKIP_LOG"
  done < <(grep -a '^SKIP ' "$1" || true)
}

needs() {
  local package=$1 what=$2 why
  if why=$(bash "$skips_repo/tools/setup.sh" --probe "$package"); then return 0; fi
  if [[ ${CI:-} == true ]]; then
    echo "FAIL $what: $why" >&2
    echo "FAIL $what: under CI=true a tool that tools/setup.sh provides must work; nothing is skipped" >&2
    exit 1
  fi
  skip "$what" "$why"
  return 1
}
