#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs what building and testing kissm needs on Debian/Ubuntu: the packages of tools/packages.tsv (each
# with the step that needs it, the programs it brings, a probe and a reason). Every package is judged by
# its probe, a command that succeeds only when the tool works (bindgen's: a header including <stddef.h>
# parses), never by a file or a package database entry. As root, what fails its probe is installed with
# apt-get and probed again; otherwise setup names the packages to install and fails. Safe to repeat.
#
#   bash tools/setup.sh                   every group tools/test.sh needs (all but the on-demand ones)
#   bash tools/setup.sh --group fuzz ...  those groups only (fuzz: clang and libFuzzer for tools/fuzz.sh)
#   bash tools/setup.sh --probe PACKAGE   probe one package without installing; exit 0 when it works,
#                                         else 1 with the line that says what to install (for the scripts)
#   bash tools/setup.sh --list            the table: group, package, programs, why
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
table=$here/tools/packages.tsv
on_demand=(fuzz) # groups installed only when asked for by name

# rows [--all | GROUP...]: the table's rows (no comments, no header) of those groups; no argument: every
# group but the on-demand ones.
rows() {
  local group package programs probe why
  while IFS=$'\t' read -r group package programs probe why; do
    [[ -z $group || $group == \#* || $group == group ]] && continue
    if [[ ${1:-} == --all ]]; then
      :
    elif (($#)); then
      [[ " $* " == *" $group "* ]] || continue
    elif [[ " ${on_demand[*]} " == *" $group "* ]]; then
      continue
    fi
    printf '%s\t%s\t%s\t%s\t%s\n' "$group" "$package" "$programs" "$probe" "$why"
  done <"$table"
}

# works PROBE: runs a probe quietly from the repository root.
works() { (cd "$here" && bash -c "$1") >/dev/null 2>&1; }

groups=()
case ${1:-} in
  --list)
    rows --all | awk -F'\t' '{ printf "%-7s %-14s %-22s %s\n", $1, $2, $3, $5 }'
    exit 0
    ;;
  --probe)
    (($# == 2)) || { echo "usage: setup.sh --probe PACKAGE" >&2; exit 2; }
    row=$(rows --all | awk -F'\t' -v p="$2" '$2 == p')
    [[ -n $row ]] || { echo "setup: no package '$2' in tools/packages.tsv" >&2; exit 2; }
    IFS=$'\t' read -r group package _ probe why <<<"$row"
    if out=$( (cd "$here" && bash -c "$probe") 2>&1); then exit 0; fi
    echo "$package does not work here (apt-get install $package; bash tools/setup.sh does it as root); it is" \
      "needed for $group: $why. Its probe ($probe) said: $(tail -n 3 <<<"$out" | tr '\n' ' ')"
    exit 1
    ;;
  --group)
    shift
    (($#)) || { echo "usage: setup.sh --group GROUP..." >&2; exit 2; }
    groups=("$@")
    ;;
  "") ;;
  *)
    echo "usage: setup.sh [--group GROUP... | --probe PACKAGE | --list]" >&2
    exit 2
    ;;
esac

# broken: the packages whose probe fails, as "group package" lines.
broken() {
  local group package programs probe why
  while IFS=$'\t' read -r group package programs probe why; do
    works "$probe" || echo "$group $package"
  done < <(rows "${groups[@]}")
}
mapfile -t missing < <(broken)

if ((${#missing[@]})) && [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
  packages=()
  for m in "${missing[@]}"; do packages+=("${m#* }"); done
  echo "setup: installing ${packages[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
  mapfile -t missing < <(broken)
fi
if ((${#missing[@]})); then
  echo "setup: these packages are missing or do not work (group, package):" >&2
  printf '  %s\n' "${missing[@]}" >&2
  packages=()
  for m in "${missing[@]}"; do packages+=("${m#* }"); done
  if [[ $(id -u) -eq 0 ]]; then
    echo "setup: they still fail their probes after apt-get install (see tools/packages.tsv)" >&2
  else
    echo "setup: install them with: sudo apt-get install ${packages[*]} (or run this as root)" >&2
  fi
  exit 1
fi
echo "setup: $(rows "${groups[@]}" | wc -l) packages work (groups: $(rows "${groups[@]}" | cut -f1 | uniq | tr '\n' ' ' | sed 's/ $//'))"
