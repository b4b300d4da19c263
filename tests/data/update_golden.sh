#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Regenerates tests/data/golden.json from the C library (single thread). Run it only when a change is meant
# to change results, and say so in the commit: the C, Python and Rust suites all compare with this file.
#   bash tests/data/update_golden.sh [BUILD_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../../build}
"$build/tests/roundtrip/roundtrip_golden" "$here" --write > "$here/golden.json.new"
mv "$here/golden.json.new" "$here/golden.json"
echo "wrote $here/golden.json"
