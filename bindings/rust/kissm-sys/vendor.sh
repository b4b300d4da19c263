#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Copies what a packaged kissm-sys needs to build on its own into the crate, as zstd-sys and
# libgit2-sys ship their C sources: the C/C++ core (root CMakeLists.txt, cmake/, include/, src/,
# third_party/) into vendor/kissm/, and the repository's LICENSE and THIRD_PARTY.md into vendor/kissm/
# and into both crates (kissm-sys/ and ../kissm/). All of it is git-ignored; `cargo package` picks it up
# through the `include` lists of the two Cargo.toml. build.rs builds vendor/kissm when it is present, so
# remove it after packaging (`vendor.sh --clean`) or the repository build keeps using the copy.
#
#   bash bindings/rust/kissm-sys/vendor.sh           # copy
#   bash bindings/rust/kissm-sys/vendor.sh --clean   # remove the copies again
#
# Eigen is not vendored: like the C library, the crate needs the system's Eigen 3 headers
# (libeigen3-dev), CMake and a C++17 compiler to build.
set -euo pipefail
crate=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$crate/../../.." && pwd)
vendor=$crate/vendor/kissm
copies=("$crate/LICENSE" "$crate/THIRD_PARTY.md" "$crate/../kissm/LICENSE" "$crate/../kissm/THIRD_PARTY.md")

rm -rf "$crate/vendor"
rm -f "${copies[@]}"
if [[ ${1:-} == --clean ]]; then
  echo "vendor.sh: removed $crate/vendor and the licence copies"
  exit 0
fi
if [[ $# -gt 0 ]]; then
  echo "usage: vendor.sh [--clean]" >&2
  exit 2
fi

for path in CMakeLists.txt cmake include src third_party LICENSE THIRD_PARTY.md; do
  if [[ ! -e $repo/$path ]]; then
    echo "vendor.sh: $repo/$path is missing; run this from a complete kissm checkout" >&2
    exit 1
  fi
done
mkdir -p "$vendor"
# Only files git knows (when this is a git checkout), so that build leftovers never reach the crate.
if git -C "$repo" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  git -C "$repo" ls-files -z --cached --others --exclude-standard -- CMakeLists.txt cmake include src third_party \
    LICENSE THIRD_PARTY.md | (cd "$repo" && xargs -0 cp --parents -t "$vendor")
else
  cp -R "$repo"/{CMakeLists.txt,cmake,include,src,third_party,LICENSE,THIRD_PARTY.md} "$vendor/"
fi
for file in LICENSE THIRD_PARTY.md; do
  cp "$repo/$file" "$crate/$file"
  cp "$repo/$file" "$crate/../kissm/$file"
done
echo "vendor.sh: copied the kissm sources into $vendor ($(find "$vendor" -type f | wc -l) files)"
