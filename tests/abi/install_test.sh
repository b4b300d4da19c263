#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# abi_install: installs the build tree with `cmake --install` into a scratch prefix, then builds the C
# example (examples/c) against the installed tree only, four ways, and runs each on two clouds:
#   1. CMake find_package(kissm), kissm::kissm         (libkissm.so)
#   2. CMake find_package(kissm), kissm::kissm_static  (libkissm.a)
#   3. pkg-config --cflags --libs kissm                (libkissm.so)
#   4. pkg-config --static --libs kissm                (libkissm.a)
# Every binary must find a valid pose, and all four must print the same pose.
#
#   install_test.sh BUILD_DIR SOURCE_DIR WORK_DIR CMAKE GENERATOR CC LIBDIR CLOUDS SHARED(0|1) STATIC(0|1)
#
# CLOUDS is tests/data (roundtrip_source.ply and roundtrip_target.ply, voxel 0.25), or else the kissm
# command-line tool, whose `kissm demo --out DIR` writes two simulated LiDAR scans (voxel 0.3).
set -uo pipefail
if (($# != 10)); then
  echo "usage: $0 BUILD_DIR SOURCE_DIR WORK_DIR CMAKE GENERATOR CC LIBDIR CLOUDS SHARED STATIC" >&2
  exit 2
fi
build=$1 source=$2 work=$3 cmake=$4 generator=$5 cc=$6 libdir=$7 cloud_source=$8 shared=$9 static=${10}
prefix=$work/prefix
# step, fail, run and run_consumers (and `failures`, `binaries`), shared with the .deb test.
# shellcheck source=../package/consumers.sh
source "$(dirname "$0")/../package/consumers.sh"

rm -rf "$work"
mkdir -p "$work"

# --- install --------------------------------------------------------------------------------------------
step "cmake --install $build --prefix $prefix"
run "$work/install.log" "$cmake" --install "$build" --prefix "$prefix" || exit 1
header=$prefix/include/kissm.h
expected=("$header" "$prefix/$libdir/cmake/kissm/kissmConfig.cmake"
          "$prefix/$libdir/cmake/kissm/kissmConfigVersion.cmake" "$prefix/$libdir/cmake/kissm/kissmTargets.cmake"
          "$prefix/$libdir/pkgconfig/kissm.pc")
((shared)) && expected+=("$prefix/$libdir/libkissm.so")
((static)) && expected+=("$prefix/$libdir/libkissm.a")
for f in "${expected[@]}"; do
  [[ -e $f ]] || fail "not installed: ${f#"$prefix"/}"
done
((failures)) && { sed 's/^/  | /' "$work/install.log"; exit 1; }
version=$(sed -n 's/^#define KISSM_VERSION_STRING "\(.*\)"$/\1/p' "$header")
abi=$(sed -n 's/^#define KISSM_ABI_VERSION \([0-9]*\)$/\1/p' "$header")
echo "installed kissm $version (ABI $abi) into $prefix"

if ((shared)); then
  # The SONAME carries the ABI version: libkissm.so.<KISSM_ABI_VERSION>.
  soname=$(readelf -d "$prefix/$libdir/libkissm.so" | sed -n 's/.*Library soname: \[\(.*\)\]/\1/p')
  [[ $soname == "libkissm.so.$abi" ]] || fail "SONAME is '$soname', expected libkissm.so.$abi (KISSM_ABI_VERSION)"
fi

# --- the package version file ---------------------------------------------------------------------------
# find_package(kissm X.Y) accepts an installed version of the same major version that is not older.
step "kissmConfigVersion.cmake (SameMajorVersion)"
cat >"$work/version_check.cmake" <<EOF
function(check requested expected)
  string(REPLACE "." ";" parts "\${requested}")
  list(GET parts 0 PACKAGE_FIND_VERSION_MAJOR)
  list(GET parts 1 PACKAGE_FIND_VERSION_MINOR)
  set(PACKAGE_FIND_VERSION "\${requested}")
  set(PACKAGE_FIND_VERSION_COUNT 2)
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
  include("$prefix/$libdir/cmake/kissm/kissmConfigVersion.cmake")
  if(NOT PACKAGE_VERSION_COMPATIBLE STREQUAL expected)
    message(SEND_ERROR "find_package(kissm \${requested}) with kissm \${PACKAGE_VERSION} installed: compatible = \${PACKAGE_VERSION_COMPATIBLE}, expected \${expected}")
  endif()
endfunction()
string(REPLACE "." ";" v "$version")
list(GET v 0 major)
list(GET v 1 minor)
math(EXPR next_major "\${major} + 1")
math(EXPR next_minor "\${minor} + 1")
check("\${major}.\${minor}" TRUE)
check("\${major}.0" TRUE)
check("\${major}.\${next_minor}" FALSE)
check("\${next_major}.0" FALSE)
EOF
run "$work/version_check.log" "$cmake" -P "$work/version_check.cmake" || fail "kissmConfigVersion.cmake"

# --- two clouds -----------------------------------------------------------------------------------------
if [[ -d $cloud_source ]]; then
  clouds=("$cloud_source/roundtrip_source.ply" "$cloud_source/roundtrip_target.ply" 0.25)
  step "two clouds: ${clouds[*]}"
else
  step "two clouds: $cloud_source demo --out $work/clouds"
  run "$work/demo.log" "$cloud_source" demo --out "$work/clouds" --threads 2 || exit 1
  clouds=("$work/clouds/source.ply" "$work/clouds/target.ply" 0.3)
fi

# --- consumers ------------------------------------------------------------------------------------------
# check_linkage NAME PATH WANT_SHARED(0|1): uses the installed libkissm.so, or no libkissm.so at all.
check_linkage() {
  local name=$1 exe=$2 want_shared=$3
  if ((want_shared)); then
    local resolved
    resolved=$(ldd "$exe" | awk '/libkissm\.so/ {print $3}')
    [[ $resolved == "$prefix/$libdir/"* ]] || fail "$name: libkissm.so resolves to '$resolved', not the installed one"
  elif readelf -d "$exe" | grep -q 'NEEDED.*libkissm'; then
    fail "$name: linked statically but needs libkissm.so"
  fi
}

prefix_cmake_consumer() { # prefix_cmake_consumer NAME STATIC(ON|OFF)
  local name=$1 dir=$work/$1
  step "$name: find_package(kissm) with CMAKE_PREFIX_PATH=$prefix"
  run "$dir.configure.log" "$cmake" -S "$source/examples/c" -B "$dir" -G "$generator" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_COMPILER="$cc" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
    -DKISSM_EXAMPLE_STATIC="$2" || { fail "$name: configure"; return; }
  local found
  found=$(sed -n 's/^kissm_DIR:PATH=//p' "$dir/CMakeCache.txt")
  [[ $found == "$prefix/$libdir/cmake/kissm" ]] || fail "$name: found kissm in '$found', not in the prefix"
  run "$dir.build.log" "$cmake" --build "$dir" || { fail "$name: build"; return; }
  check_linkage "$name" "$dir/kissm_example" "$([[ $2 == OFF ]] && echo 1 || echo 0)"
  binaries+=("$name:$dir/kissm_example")
}

prefix_pkg_config_consumer() { # prefix_pkg_config_consumer NAME STATIC(0|1)
  local name=$1 exe=$work/$1/kissm_example libs
  command -v pkg-config >/dev/null || return
  mkdir -p "$work/$1"
  step "$name: pkg-config$( (($2)) && echo " --static") with PKG_CONFIG_PATH=$prefix/$libdir/pkgconfig"
  export PKG_CONFIG_PATH=$prefix/$libdir/pkgconfig
  run "$work/$1.modversion.log" pkg-config --modversion kissm || { fail "$name: pkg-config cannot find kissm"; return; }
  [[ $(pkg-config --modversion kissm) == "$version" ]] || fail "$name: kissm.pc says $(pkg-config --modversion kissm)"
  if (($2)); then
    # libkissm.so sits next to libkissm.a: name the archive (-l:libkissm.a, GNU ld and lld) and add
    # Libs.private (the C++ runtime, threads, libm) with --static.
    libs=$(pkg-config --static --libs kissm | sed 's/-lkissm\b/-l:libkissm.a/')
  else
    libs="$(pkg-config --libs kissm) -Wl,-rpath,$(pkg-config --variable=libdir kissm)"
  fi
  # shellcheck disable=SC2046,SC2086
  run "$work/$1.build.log" "$cc" -std=c99 -Wall -Wextra -pedantic -Werror $(pkg-config --cflags kissm) \
    "$source/examples/c/register_pair.c" -o "$exe" $libs || { fail "$name: build"; return; }
  check_linkage "$name" "$exe" "$((1 - $2))"
  binaries+=("$name:$exe")
}

if ! command -v pkg-config >/dev/null; then
  fail "pkg-config not found: the pkg-config consumers cannot be checked (tools/setup.sh installs pkg-config)"
fi
if ((shared)); then
  prefix_cmake_consumer cmake-shared OFF
  prefix_pkg_config_consumer pkgconfig-shared 0
fi
if ((static)); then
  prefix_cmake_consumer cmake-static ON
  prefix_pkg_config_consumer pkgconfig-static 1
fi

# --- run them -------------------------------------------------------------------------------------------
run_consumers "${clouds[@]}"

if ((failures)); then
  echo "FAIL: $failures problems"
  exit 1
fi
echo "PASS: ${#binaries[@]} consumers built against the installed kissm $version and found the same valid pose"
