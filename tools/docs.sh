#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds the three API references into ${KISSM_BUILD_DIR:-build}/docs/:
#   c/        doxygen docs/Doxyfile (include/kissm.h only; any warning fails); doxygen comes from
#             tools/setup.sh: without it this part fails under CI=true and is skipped (recorded) elsewhere
#   python/   bindings/python/docs.sh OUTDIR
#   rust/     bindings/rust/docs.sh OUTDIR
#   index.html  links the three
# Exit status 0 when all three built cleanly, 1 otherwise.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=skips.sh
source "$here/tools/skips.sh"
build=${KISSM_BUILD_DIR:-$here/build}
mkdir -p "$build/docs"
out=$(cd "$build/docs" && pwd)
version=$(sed -n 's/^#define KISSM_VERSION_STRING "\(.*\)"$/\1/p' "$here/include/kissm.h")
failures=0
declare -A state=()

# c: Doxygen
build_c() {
  if ! needs doxygen "the C API reference (docs/c)"; then return 77; fi
  (cd "$here" && KISSM_VERSION=$version KISSM_DOXYGEN_OUTPUT="$out/c" doxygen docs/Doxyfile) && [[ -f $out/c/index.html ]]
}

# binding NAME: bindings/NAME/docs.sh OUTDIR, if it exists.
build_binding() {
  local script=$here/bindings/$1/docs.sh
  if [[ ! -f $script ]]; then
    echo "docs: bindings/$1/docs.sh is missing" >&2
    return 1
  fi
  mkdir -p "$out/$1"
  bash "$script" "$out/$1"
}

for part in c python rust; do
  echo "== docs/$part"
  start=$SECONDS
  rm -rf "${out:?}/$part"
  status=0
  if [[ $part == c ]]; then
    build_c || status=$?
  else
    build_binding "$part" || status=$?
  fi
  case $status in
    0) state[$part]=built ;;
    77) state[$part]=skipped ;;
    *)
      state[$part]=failed
      failures=$((failures + 1))
      echo "FAIL: the $part API reference did not build (exit status $status)"
      ;;
  esac
  echo "   docs/$part: ${state[$part]} in $((SECONDS - start)) s"
done

# The page each reference opens with: its own index.html, or the one a level down (cargo doc: rust/<crate>/).
entry() {
  local dir=$out/$1 found
  if [[ -f $dir/index.html ]]; then
    echo "$1/index.html"
    return
  fi
  found=$(find "$dir" -mindepth 2 -maxdepth 2 -name index.html 2>/dev/null | sort | head -n 1)
  if [[ -n $found ]]; then echo "${found#"$out"/}"; else echo "$1/"; fi
}
link() { # link PART TITLE
  if [[ ${state[$1]} == built ]]; then
    echo "  <li><a href=\"$(entry "$1")\">$2</a></li>"
  else
    echo "  <li>$2: ${state[$1]}</li>"
  fi
}
{
  echo '<!DOCTYPE html>'
  echo "<html lang=\"en\"><head><meta charset=\"utf-8\"><title>kissm $version API reference</title></head><body>"
  echo "<h1>kissm $version API reference</h1>"
  echo '<ul>'
  link c "C (include/kissm.h)"
  link python "Python (bindings/python)"
  link rust "Rust (bindings/rust)"
  echo '</ul>'
  echo '</body></html>'
} >"$out/index.html"
echo "docs: $out/index.html (c: ${state[c]}, python: ${state[python]}, rust: ${state[rust]})"
if ((failures)); then
  echo "FAIL: $failures API references did not build"
  exit 1
fi
