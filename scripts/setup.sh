#!/usr/bin/env bash
# Installs the Debian 12 packages the project builds and tests with. Idempotent: quiet and fast when all is there.
# Run as root (or with sudo available). Usage: scripts/setup.sh [program]
#   program: only what building the point-detail program needs (scripts/run_demo.sh); without it, everything
#   (the tests, the Python package, the studio's browser, the tiled runs, the viewers the tests open files in).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache
  libcgal-dev libeigen3-dev libboost-dev libtbb-dev libgmp-dev libmpfr-dev
  libcli11-dev nlohmann-json3-dev libstb-dev
  libsuitesparse-dev libopenblas-dev
)
if [ "${1:-}" != program ]; then
  packages+=(
    libgtest-dev libgmock-dev libbenchmark-dev
    clang clang-format-14 libclang-rt-14-dev time bc
    doxygen python3 python3-matplotlib
    pybind11-dev python3-dev python3-numpy python3-pytest
    python3-venv python3-build python3-mypy python3-setuptools python3-wheel python3-pip
    python3-aiohttp libjs-three chromium chromium-driver python3-selenium
    python3-scipy python3-dask python3-distributed python3-zarr
    cloudcompare python3-open3d
  )
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup.sh: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
echo "setup.sh: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
