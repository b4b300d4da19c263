#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The benchmark in one command: sets up its own venv (kissm's Python binding built from this checkout, the
# reference KISS-Matcher, Open3D, small_gicp, numpy, matplotlib) and runs bench/bench.py (with --maps:
# bench/map_bench.py, the scan-to-map benchmark; with --ground: bench/ground_bench.py, ground suppression and
# yaw only against Patchwork++ and the reference's Quatro).
#
#   bash bench/run.sh                  # full run: threads 1 and 2, every pair raw + 2 rotations, scaling to 3M voxels;
#                                      # writes docs/reports/benchmarks.md, docs/reports/img/*.png, bench/results/latest.json.gz
#   bash bench/run.sh --smoke          # seconds: the harness on one small pair (results in a temp dir)
#   bash bench/run.sh --quick          # minutes: 1 rotation, 1 repeat, scaling to 100K voxels
#   bash bench/run.sh --refine-only --out /tmp/refine   # 15 minutes: the refinement comparison alone (issue 14)
#   bash bench/run.sh --setup-only     # only make the venv
#   bash bench/run.sh --maps [...]     # the scan-to-map benchmark instead (bench/map_bench.py and its options)
#   bash bench/run.sh --ground [...]   # the ground-vehicle benchmark instead (bench/ground_bench.py, 6 minutes)
#   bash bench/run.sh --threads 2 --repeats 5 ...   # any bench.py option (python bench/bench.py --help)
#
# Environment: KISSM_BENCH_VENV (default bench/.venv), PYTHON (default python3), KISSM_DATA_DIR (default
# ../shared/data). As root it installs missing Debian packages with apt-get (build tools via tools/setup.sh;
# libusb-1.0-0, which Open3D's wheel links against); otherwise it says what is missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
venv=${KISSM_BENCH_VENV:-$here/bench/.venv}
python=${PYTHON:-python3}

setup_only=0
maps=0
ground=0
args=()
for a in "$@"; do
  if [[ $a == --setup-only ]]; then
    setup_only=1
  elif [[ $a == --maps ]]; then
    maps=1
  elif [[ $a == --ground ]]; then
    ground=1
  else
    args+=("$a")
  fi
done

# ---- Debian packages ---------------------------------------------------------------------------------
bash tools/setup.sh
apt_install() {  # apt_install PACKAGE...: installs the missing ones as root, or explains
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
    echo "bench: installing ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "bench: missing Debian packages: ${missing[*]} (sudo apt-get install ${missing[*]})" >&2
    return 1
  fi
}
if command -v dpkg-query >/dev/null; then
  apt_install libusb-1.0-0 || exit 1   # Open3D's wheel needs libusb-1.0.so.0
fi

# ---- the venv ----------------------------------------------------------------------------------------
if ! "$venv/bin/python" -c 'import sys' >/dev/null 2>&1; then
  rm -rf "$venv"
  if ! "$python" -m venv "$venv"; then
    apt_install python3-venv python3-pip && rm -rf "$venv" && "$python" -m venv "$venv"
  fi
fi
py="$venv/bin/python"
pip() { "$py" -m pip --disable-pip-version-check "$@"; }
echo "bench: $("$py" --version) in $venv"
stamp="$venv/.peers-installed-3" # -2: pypatchworkpp joined the peers; -3: laspy with lazrs (read_bench.py)
if [[ ! -f $stamp ]]; then
  pip install --quiet --upgrade pip
  # The peers named in the issue, pinned; numpy and matplotlib within tested major versions.
  pip install --quiet "kiss-matcher==1.0.2" "open3d-cpu==0.20.0" "small-gicp==1.0.1" "pypatchworkpp==1.4.1" \
    "laspy[lazrs]>=2.7,<3" "numpy>=1.24,<3" "matplotlib>=3.7,<4"
  touch "$stamp"
fi
# kissm from this checkout, rebuilt every time (incrementally, in a build directory kept in the venv).
start=$(date +%s)
pip uninstall --quiet --yes kissm >/dev/null 2>&1 || true
if ! pip install --quiet --config-settings=build-dir="$venv/kissm-build" ./bindings/python; then
  echo "bench: build failed; retrying with a clean build directory" >&2
  rm -rf "$venv/kissm-build"
  pip install --quiet --config-settings=build-dir="$venv/kissm-build" ./bindings/python
fi
echo "bench: pip install ./bindings/python took $(($(date +%s) - start)) s"
"$py" - <<'EOF'
import importlib.metadata as md
print("bench: " + ", ".join(f"{d} {md.version(d)}" for d in
      ("kissm", "kiss-matcher", "open3d-cpu", "small-gicp", "pypatchworkpp", "numpy", "matplotlib")))
import kissm, kiss_matcher, open3d, small_gicp, pypatchworkpp  # noqa: F401  (fails here rather than mid-run)
EOF
((setup_only)) && exit 0

# ---- the run -----------------------------------------------------------------------------------------
if ((ground)); then
  export KISSM_BENCH_COMMAND="bash bench/run.sh --ground${args[*]:+ ${args[*]}}"
  exec "$py" bench/ground_bench.py "${args[@]}"
fi
if ((maps)); then
  export KISSM_BENCH_COMMAND="bash bench/run.sh --maps${args[*]:+ ${args[*]}}"
  exec "$py" bench/map_bench.py "${args[@]}"
fi
export KISSM_BENCH_COMMAND="bash bench/run.sh${args[*]:+ ${args[*]}}"
exec "$py" bench/bench.py "${args[@]}"
