#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs what building and testing kissm needs on Debian/Ubuntu. As root it uses apt-get; otherwise it
# checks and says what is missing. Safe to run repeatedly: it installs only what is absent.
#   required: the build (cmake, a C++17 compiler, Eigen), pkg-config for the install tests, dpkg-dev for the
#             .deb's computed dependencies, clang-format and shellcheck for tools/lint.sh, doxygen for the C
#             API reference (tools/docs.sh), libusb-1.0-0 for the Open3D interop test (open3d-cpu needs it);
#   optional: abigail-tools for the ABI baseline test, which skips (exit 77) without it.
set -euo pipefail

required=(cmake g++ ninja-build libeigen3-dev pkg-config dpkg-dev clang-format shellcheck doxygen libusb-1.0-0)
optional=(abigail-tools)

absent() {
  local p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
  done
}
mapfile -t missing < <(absent "${required[@]}")
mapfile -t missing_optional < <(absent "${optional[@]}")

if ((${#missing[@]} + ${#missing_optional[@]})) && [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
  echo "setup: installing ${missing[*]} ${missing_optional[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" "${missing_optional[@]}" >/dev/null
  missing=()
  missing_optional=()
fi
if ((${#missing_optional[@]})); then
  echo "setup: optional packages missing (their tests will be skipped): ${missing_optional[*]}" >&2
fi
if ((${#missing[@]})); then
  echo "setup: missing packages: ${missing[*]}" >&2
  echo "setup: install them with: sudo apt-get install ${missing[*]}" >&2
  exit 1
fi
echo "setup: build tools ready ($(cmake --version | head -1), $(g++ --version | head -1))"
