#!/usr/bin/env bash
# Installs the Debian 12 packages viosfm needs. Idempotent: installs only what
# is missing. Needs root (or sudo) for apt-get.
#   scripts/install-deps.sh          build, test and benchmark (`make test`)
#   scripts/install-deps.sh --demo   build and run the `viosfm` program only
#                                    (`make demo`): no test or benchmark
#                                    libraries, no browser
set -euo pipefail

profile=all
case "${1:-}" in
  "") ;;
  --demo) profile=demo ;;
  *) echo "install-deps: unknown argument '$1' (expected nothing or --demo)" >&2; exit 2 ;;
esac

# To build and run `viosfm` (compiler, CMake, Ninja, and the libraries).
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libceres-dev libopencv-dev libsqlite3-dev libcli11-dev
  libyaml-cpp-dev nlohmann-json3-dev libtbb-dev
  libbz2-dev liblz4-dev  # bz2- and lz4-compressed chunks of ROS bags (and MCAP's lz4)
  libzstd-dev  # ROS 2 bags: zstd MCAP chunks, zstd-compressed rosbag2 messages and files
  libxxhash-dev  # XXH3 content hashes of the inputs (util/hash.h)
  libjs-three  # three.js, copied into the report's 3D view
  # An optimised BLAS and LAPACK (single-threaded, so runs stay repeatable)
  # in place of the reference or ATLAS ones: the sparse Cholesky of the
  # bundle adjustment's reduced camera system spends its time in them.
  libopenblas0-serial
  file  # `make package`: CPack's Debian generator reads the binary's type with it
)
# To test and benchmark it.
if [[ "$profile" == "all" ]]; then
  packages+=(
    libgtest-dev libgmock-dev libbenchmark-dev
    chromium  # headless, for the tests that open `viosfm report` pages
    python3  # scripts/check_transforms_json.py (standard library only)
  )
fi
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

echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
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
# apt's progress, shortened to a line every 25 packages downloaded or set up.
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! "${SUDO[@]}" apt-get install -y --no-install-recommends -o Dpkg::Use-Pty=0 "${missing[@]}" \
     2>&1 | tee "$log" |
     awk '/^Need to get/ { print "install-deps: " $0; fflush() }
          /^Get:/ { if (++n % 25 == 0) { print "install-deps: downloaded " n " packages"; fflush() } }
          /^Setting up/ { if (++s % 25 == 0) { print "install-deps: set up " s " packages"; fflush() } }'; then
  tail -n 20 "$log" >&2
  echo "install-deps: apt-get install failed (its last lines above)" >&2
  exit 1
fi
echo "install-deps: done"
