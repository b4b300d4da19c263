#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The Python binding's suite: makes a venv, installs the package the way users do
# (pip install ./bindings/python[test,dask,ray], which copies the core into bindings/python/_core and builds
# libkissm, incrementally in $KISSM_BUILD_DIR/python-build), adds open3d-cpu, then runs pytest. The extras
# dask and ray bring the engines tests/batch runs kissm.batch on (package_test.sh installs only [test]: there
# those tests skip).
# bindings/python/package_test.sh tests the sdist and the manylinux wheel away from the repository.
#
# Run by tools/test.sh with KISSM_BUILD_DIR (the CMake build: its `kissm` CLI is the reference for the
# bitwise cross-checks) and KISSM_DATA_DIR (the real scans; those tests skip when absent). Both default as
# in tools/test.sh. Extra arguments go to pytest (e.g. -k cli -x).
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
build=${KISSM_BUILD_DIR:-$here/build}
data_dir=${KISSM_DATA_DIR:-$here/../shared/data}
venv=${KISSM_PYTHON_VENV:-$build/venv-python}
python=${PYTHON:-python3}
mkdir -p "$build"

# ---- a venv (Debian's python3 needs python3-venv for it: tools/setup.sh installs it) -------------------
if ! "$python" -c 'import sys; assert sys.version_info >= (3, 10)' >/dev/null 2>&1; then
  echo "python: '$python' is not a working Python >= 3.10 (set PYTHON=/path/to/python3)" >&2
  exit 1
fi
if ! "$venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$venv"
  if ! "$python" -m venv "$venv" >/dev/null 2>&1; then
    echo "python: '$python -m venv' failed: $(bash "$here/tools/setup.sh" --probe python3-venv || true)" >&2
    exit 1
  fi
fi
py="$venv/bin/python"
echo "python: $("$py" --version) in $venv"

# ---- the package, built and installed as users do ----------------------------------------------------
# The CMake build directory is kept between runs (incremental rebuilds); a failed build is retried once
# from scratch in case the kept directory is stale.
pip_build_dir="$build/python-build"
install_package() {
  "$py" -m pip install --quiet --disable-pip-version-check \
    --config-settings=build-dir="$pip_build_dir" "$here/bindings/python[test,dask,ray]"
}
start=$(date +%s)
"$py" -m pip uninstall --quiet --yes kissm >/dev/null 2>&1 || true
if ! install_package; then
  echo "python: build failed; retrying with a clean build directory" >&2
  rm -rf "$pip_build_dir"
  install_package
fi
echo "python: pip install ./bindings/python[test,dask,ray] took $(($(date +%s) - start)) s"

# Open3D for the interop test (tests/test_inputs.py, which fails here without it): large, so only in this
# venv, not in package_test.sh's fresh ones. pip returns at once when the pinned version is there.
# (open3d brings dash, whose pytest plugin is kept out with -p no:dash.)
"$py" -m pip install --quiet --disable-pip-version-check open3d-cpu==0.20.0
# Its wheel links libusb-1.0, which Debian does not install by default (tools/setup.sh does).
if ! "$py" -c 'import open3d' >/dev/null; then
  echo "python: open3d does not import: $(bash "$here/tools/setup.sh" --probe libusb-1.0-0 || true)" >&2
  exit 1
fi

# ---- the tests: against the installed package and its own library -----------------------------------
unset KISSM_LIBRARY
# (The package sits under src/, so running from bindings/python cannot import the source tree instead.)
cd "$here/bindings/python"
status=0
KISSM_BUILD_DIR=$build KISSM_DATA_DIR=$data_dir KISSM_REQUIRE_OPEN3D=1 "$py" -m pytest -p no:cacheprovider -p no:dash tests "$@" || status=$?
if ((status == 5)); then
  echo "python: pytest collected no tests" >&2
  exit 1
fi
exit "$status"
