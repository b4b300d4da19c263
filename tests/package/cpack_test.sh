#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# package_cpack: runs cpack on the build tree into a scratch folder, checks what the .tar.gz and the .deb
# hold and the .deb's control fields, installs the .deb with dpkg, builds examples/c against /usr with
# find_package(kissm) (no prefix hints) and with `pkg-config --cflags --libs kissm` (plain cc), runs both
# on the round-trip clouds and checks that they find the same valid pose. The package is purged at the
# end whatever happens. Needs root and dpkg: exits 77 (skipped) without them.
#
#   cpack_test.sh BUILD_DIR SOURCE_DIR WORK_DIR CPACK CMAKE GENERATOR CC LIBDIR STATIC(0|1) CLI(0|1)
set -uo pipefail
if (($# != 10)); then
  echo "usage: $0 BUILD_DIR SOURCE_DIR WORK_DIR CPACK CMAKE GENERATOR CC LIBDIR STATIC CLI" >&2
  exit 2
fi
build=$1 source=$2 work=$3 cpack=$4 cmake=$5 generator=$6 cc=$7 rel_libdir=$8 static=$9 cli=${10}
package=kissm
# shellcheck source=tests/package/consumers.sh
. "$(dirname "$0")/consumers.sh"

if ((EUID != 0)); then
  echo "SKIP: needs root (dpkg -i / --purge)"
  exit 77
fi
for tool in dpkg dpkg-deb dpkg-query tar; do
  command -v "$tool" >/dev/null || { echo "SKIP: $tool not found"; exit 77; }
done
# Only what the system itself provides: no hints towards another kissm.
unset CMAKE_PREFIX_PATH kissm_DIR kissm_ROOT PKG_CONFIG_PATH LD_LIBRARY_PATH

rm -rf "$work"
mkdir -p "$work"
version=$(sed -n 's/^#define KISSM_VERSION_STRING "\(.*\)"$/\1/p' "$source/include/kissm.h")
abi=$(sed -n 's/^#define KISSM_ABI_VERSION \([0-9]*\)$/\1/p' "$source/include/kissm.h")

# --- cpack ----------------------------------------------------------------------------------------------
step "cpack -G 'TGZ;DEB' -B $work/packages"
run "$work/cpack.log" "$cpack" --config "$build/CPackConfig.cmake" -G "TGZ;DEB" -B "$work/packages" || exit 1
shopt -s nullglob
tarballs=("$work/packages/$package-$version-"*.tar.gz)
debs=("$work/packages/${package}_${version}_"*.deb)
shopt -u nullglob
((${#tarballs[@]} == 1)) || { fail "expected one $package-$version-*.tar.gz, found ${#tarballs[@]}"; exit 1; }
((${#debs[@]} == 1)) || { fail "expected one ${package}_${version}_*.deb, found ${#debs[@]}"; exit 1; }
tarball=${tarballs[0]} deb=${debs[0]}
echo "   $(basename "$tarball") ($(stat -c %s "$tarball") bytes), $(basename "$deb") ($(stat -c %s "$deb") bytes)"

# What both must hold, relative to the install prefix.
doc=share/doc/kissm
expected=("$rel_libdir/libkissm.so" "$rel_libdir/libkissm.so.$abi" include/kissm.h
          "$rel_libdir/cmake/kissm/kissmConfig.cmake" "$rel_libdir/cmake/kissm/kissmConfigVersion.cmake"
          "$rel_libdir/cmake/kissm/kissmTargets.cmake" "$rel_libdir/pkgconfig/kissm.pc"
          "$doc/LICENSE" "$doc/THIRD_PARTY.md" "$doc/copyright" "$doc/third_party/nanoflann/LICENSE"
          "$doc/third_party/eigen/LICENSE.MPL2")
((static)) && expected+=("$rel_libdir/libkissm.a")
((cli)) && expected+=(bin/kissm)
# check_listing NAME LISTING_FILE: every expected path is in the listing (one path per line, prefix cut).
check_listing() {
  local name=$1 list=$2 f
  for f in "${expected[@]}"; do
    grep -qxF "$f" "$list" || fail "$name lacks $f"
  done
  echo "   $name: $(wc -l <"$list") entries, the ${#expected[@]} expected ones present"
}

step "contents of $(basename "$tarball")"
# kissm-<version>-<system>-<cpu>/lib/libkissm.so -> lib/libkissm.so
tar -tzf "$tarball" | sed -n 's|^[^/]*/||p' | grep -v '/$' >"$work/tgz.list" || fail "cannot list $tarball"
check_listing tar.gz "$work/tgz.list"

step "contents and control fields of $(basename "$deb")"
dpkg-deb --fsys-tarfile "$deb" | tar -t | sed -n 's|^\./usr/||p' | grep -v '/$' >"$work/deb.list" ||
  fail "cannot list $deb"
check_listing deb "$work/deb.list"
field() { dpkg-deb -f "$deb" "$1"; }
dpkg-deb -I "$deb" >"$work/deb.info" && sed 's/^/  | /' "$work/deb.info"
[[ $(field Package) == "$package" ]] || fail "Package: '$(field Package)'"
[[ $(field Version) == "$version" ]] || fail "Version: '$(field Version)', expected $version"
[[ $(field Architecture) == "$(dpkg --print-architecture)" ]] || fail "Architecture: '$(field Architecture)'"
[[ $(field Maintainer) == "The kissm authors"* ]] || fail "Maintainer: '$(field Maintainer)'"
[[ -n $(field Homepage) ]] || fail "no Homepage"
[[ $(field Description) == *"point cloud registration"* ]] || fail "Description: '$(field Description)'"
# "libc6 (>= 2.34), libgcc-s1 (>= 3.0), libstdc++6 (>= 11)" or the same without versions: one name a line.
field Depends | tr ',' '\n' | sed 's/(.*)//; s/^ *//; s/ *$//' >"$work/depends.list"
for dep in libc6 libstdc++6 libgcc-s1; do
  grep -qxF "$dep" "$work/depends.list" || fail "Depends lacks $dep: '$(field Depends)'"
done
((failures)) && { echo "FAIL: $failures problems (packages in $work/packages)"; exit 1; }

# --- dpkg -i, and --purge whatever happens next ---------------------------------------------------------
if dpkg-query -W -f '${Status}\n' "$package" 2>/dev/null | grep -q ' installed$'; then
  echo "WARNING: a $package package is installed already ($(dpkg-query -W -f '${Version}' "$package")):" \
    "this test replaces it and purges it at the end"
fi
purge() {
  local status=$?
  step "dpkg --purge $package"
  if ! run "$work/purge.log" dpkg --purge "$package"; then
    echo "FAIL: dpkg --purge $package"
    status=1
  elif dpkg-query -W -f '${Status}\n' "$package" 2>/dev/null | grep -q ' installed$' ||
    [[ -e /usr/include/kissm.h || -e /usr/$rel_libdir/libkissm.so.$abi ]]; then
    echo "FAIL: $package is still installed after dpkg --purge"
    status=1
  fi
  echo "   ${SECONDS}s in all"
  exit "$status"
}
trap purge EXIT
step "dpkg -i $(basename "$deb")"
run "$work/dpkg-install.log" dpkg -i "$deb" || exit 1
for f in "${expected[@]}"; do
  [[ -e /usr/$f ]] || fail "dpkg -i did not install /usr/$f"
done
if ((cli)); then
  [[ $(command -v kissm) == /usr/bin/kissm ]] || fail "kissm on PATH is '$(command -v kissm)', not /usr/bin/kissm"
  [[ $(/usr/bin/kissm --version) == "kissm $version" ]] || fail "/usr/bin/kissm --version: '$(/usr/bin/kissm --version)'"
fi
((failures)) && exit 1

# --- consumers of /usr ----------------------------------------------------------------------------------
libdir=/usr/$rel_libdir
step "cmake: find_package(kissm) with no prefix hints"
cmake_consumer cmake-usr "$libdir/cmake/kissm" "$cmake" "$generator" "$cc"
step "pkg-config --cflags --libs kissm, plain $cc"
pkg_config_consumer pkgconfig-usr "$version" "$cc"
run_consumers "$source/tests/data/roundtrip_source.ply" "$source/tests/data/roundtrip_target.ply" 0.25

if ((failures)); then
  echo "FAIL: $failures problems"
  exit 1
fi
echo "PASS: the .tar.gz and the .deb of kissm $version hold the expected files; ${#binaries[@]} consumers of the" \
  "installed .deb found the same valid pose"
