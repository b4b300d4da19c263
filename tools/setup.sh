#!/usr/bin/env bash
# Installs what building and testing kissm needs on Debian/Ubuntu. As root it uses apt-get; otherwise it
# checks and says what is missing. Safe to run repeatedly: it installs only what is absent.
set -euo pipefail

packages=(cmake g++ ninja-build libeigen3-dev pkg-config)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
    echo "setup: installing ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "setup: missing packages: ${missing[*]}" >&2
    echo "setup: install them with: sudo apt-get install ${missing[*]}" >&2
    exit 1
  fi
fi
echo "setup: build tools ready ($(cmake --version | head -1), $(g++ --version | head -1))"
