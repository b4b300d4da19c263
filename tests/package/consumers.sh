# SPDX-License-Identifier: MIT
# shellcheck shell=bash disable=SC2154 # work, source and libdir are set by the sourcing script
# Shared by the package tests: builds examples/c against an installed kissm as a CMake and as a pkg-config
# consumer, runs every consumer on the same two clouds and checks that they found the same valid pose.
# Source it, then set:
#   work       scratch folder (logs and consumer builds go there)
#   source     the kissm source tree (examples/c)
#   libdir     the folder the installed libkissm.so must resolve to at run time (absolute)
# and call the functions; `failures` counts what went wrong, `binaries` lists NAME:PATH of the consumers.
failures=0
binaries=()

step() { echo "== $*"; }
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}
# run LOG command...: runs quietly, shows the log on failure.
run() {
  local log=$1
  shift
  if ! "$@" >"$log" 2>&1; then
    echo "command failed: $*"
    sed 's/^/  | /' "$log"
    return 1
  fi
}

# check_shared_linkage NAME EXE: the binary needs libkissm.so, and it resolves into $libdir.
check_shared_linkage() {
  local name=$1 exe=$2 resolved
  resolved=$(env -u LD_LIBRARY_PATH ldd "$exe" | awk '/libkissm\.so/ {print $3}')
  if [[ -z $resolved ]]; then
    fail "$name: does not load libkissm.so"
  elif [[ $(realpath "$resolved") != "$(realpath "$libdir")"/* ]]; then
    fail "$name: libkissm.so resolves to '$resolved', not into $libdir"
  fi
}

# cmake_consumer NAME EXPECTED_KISSM_DIR CMAKE GENERATOR CC [cmake arguments...]: configures and builds
# examples/c (kissm::kissm) and checks that find_package found the package in EXPECTED_KISSM_DIR.
cmake_consumer() {
  local name=$1 expected=$2 cmake=$3 generator=$4 cc=$5 dir=$work/$1 found
  shift 5
  run "$dir.configure.log" "$cmake" -S "$source/examples/c" -B "$dir" -G "$generator" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_COMPILER="$cc" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF "$@" || { fail "$name: configure"; return; }
  found=$(sed -n 's/^kissm_DIR:PATH=//p' "$dir/CMakeCache.txt")
  [[ $(realpath -m "$found") == "$(realpath -m "$expected")" ]] || fail "$name: found kissm in '$found', not in $expected"
  run "$dir.build.log" "$cmake" --build "$dir" || { fail "$name: build"; return; }
  check_shared_linkage "$name" "$dir/kissm_example"
  binaries+=("$name:$dir/kissm_example")
}

# pkg_config_consumer NAME VERSION CC [extra linker arguments...]: compiles examples/c/register_pair.c
# with `pkg-config --cflags --libs kissm` (whatever PKG_CONFIG_PATH the caller set, if any).
pkg_config_consumer() {
  local name=$1 version=$2 cc=$3 exe=$work/$1/kissm_example flags
  shift 3
  command -v pkg-config >/dev/null || { fail "$name: pkg-config not found (tools/setup.sh installs it)"; return; }
  mkdir -p "$work/$name"
  run "$work/$name.modversion.log" pkg-config --modversion kissm || { fail "$name: pkg-config cannot find kissm"; return; }
  [[ $(pkg-config --modversion kissm) == "$version" ]] || fail "$name: kissm.pc says $(pkg-config --modversion kissm)"
  flags=$(pkg-config --cflags --libs kissm)
  echo "   pkg-config --cflags --libs kissm: $flags"
  # shellcheck disable=SC2086 # the flags are words
  run "$work/$name.build.log" "$cc" -std=c99 -Wall -Wextra -pedantic -Werror "$source/examples/c/register_pair.c" \
    -o "$exe" $flags "$@" || { fail "$name: build"; return; }
  check_shared_linkage "$name" "$exe"
  binaries+=("$name:$exe")
}

# run_consumers SOURCE_CLOUD TARGET_CLOUD VOXEL: every binary exits 0, prints "valid: yes", and all print
# the same (the first one is the reference).
run_consumers() {
  local reference="" entry name exe status
  ((${#binaries[@]})) || { fail "no consumer was built"; return; }
  for entry in "${binaries[@]}"; do
    name=${entry%%:*} exe=${entry#*:}
    step "run $name"
    # No LD_LIBRARY_PATH: the binaries must find the installed library by themselves.
    env -u LD_LIBRARY_PATH "$exe" "$@" >"$work/$name.out" 2>&1
    status=$?
    sed 's/^/  | /' "$work/$name.out"
    ((status == 0)) || fail "$name: exit status $status (0 = valid pose)"
    grep -q '^valid: yes$' "$work/$name.out" || fail "$name: no valid pose printed"
    if [[ -z $reference ]]; then
      reference=$name
    elif ! cmp -s "$work/$reference.out" "$work/$name.out"; then
      fail "$name printed something else than $reference"
      diff "$work/$reference.out" "$work/$name.out" | sed 's/^/  | /'
    fi
  done
}
