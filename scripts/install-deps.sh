#!/usr/bin/env bash
# Installs the Debian 12 packages viosfm needs to build, test and benchmark.
# Idempotent: installs only what is missing. Needs root (or sudo) for apt-get.
set -euo pipefail

# Build and library packages (compiler, CMake, Ninja, and the libraries).
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libceres-dev libopencv-dev libsqlite3-dev libcli11-dev
  libyaml-cpp-dev nlohmann-json3-dev libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libbz2-dev liblz4-dev  # bz2- and lz4-compressed chunks of ROS bags (and MCAP's lz4)
  libzstd-dev  # ROS 2 bags: zstd MCAP chunks, zstd-compressed rosbag2 messages and files
  libxxhash-dev  # XXH3 content hashes of the inputs (util/hash.h)
  libjs-three  # three.js, copied into the report's 3D view
  chromium  # headless, for the test that opens `viosfm report` pages
  python3  # scripts/check_transforms_json.py (standard library only)
)
# The baseline the benchmarks compare against, and what the benchmark
# scripts read their results with (jq; numpy in bench-fountain-priors.sh):
# not needed to build or test.
if [[ "${VIOSFM_WITH_COLMAP:-0}" == "1" ]]; then
  packages+=(colmap sqlite3 time jq python3-numpy)
fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [[ $(id -u) -eq 0 ]]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo)
else
  echo "install-deps: need root to install: ${missing[*]}" >&2
  echo "install-deps: run as root, or: apt-get install ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -qq
"${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
