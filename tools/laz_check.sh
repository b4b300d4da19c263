#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The LAZ build (KISSM_WITH_LAZ=ON, off by default) in tools/test.sh, kept cheap: configures build-laz/
# (or $KISSM_LAZ_BUILD_DIR), builds the Rust decompressor (src/io/laz_rs, with cargo) and the two test
# programs that compile src/io's readers with LAZ built in (not the whole library), runs the crate's own
# tests, makes a venv with laspy and lazrs for the test files (tests/io/make_laz_files.py), then runs the
# io_laz* tests and io_las with LAZ built in. The whole library and the CLI with LAZ: `cmake -DKISSM_WITH_LAZ=ON` and build as usual.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=tools/skips.sh
source "$here/tools/skips.sh"
build=${KISSM_LAZ_BUILD_DIR:-$here/build-laz}
venv=$build/venv-laz
python=${PYTHON:-python3}
mkdir -p "$build"

if ! needs python3-venv "the LAZ test files (a venv with laspy and lazrs)"; then exit 0; fi
if ! "$venv/bin/python" -c 'import laspy, lazrs' >/dev/null 2>&1; then
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "laspy[lazrs]>=2.7,<3"
fi

generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$here" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DKISSM_WITH_LAZ=ON \
  -DKISSM_LAZ_PYTHON="$venv/bin/python" >/dev/null
cmake --build "$build" --parallel 2 --target io_laz_readers io_las_readers
# The C ABI crate's own tests (the stack guard of laz's recursive GPS time decoder), in the same target dir.
(cd "$here/src/io/laz_rs" && CARGO_TARGET_DIR=$build/laz_rs cargo test --release --locked --quiet)
ctest --test-dir "$build" -R '^io_la(z|z_files|s_with_laz)$' --output-on-failure --timeout 600 \
  --output-junit "$build/ctest-junit.xml"
