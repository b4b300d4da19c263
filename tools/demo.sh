#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The main job: set up, build, and run `kissm demo` on the built-in synthetic LiDAR pair.
# Writes the clouds and a before/after picture into kissm_demo_out/.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
bash "$here/tools/setup.sh"
bash "$here/tools/build.sh"
build=${KISSM_BUILD_DIR:-$here/build}
cd "$here"
"$build/kissm" demo --out kissm_demo_out "$@"
