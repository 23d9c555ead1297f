#!/usr/bin/env bash
# Installs the Debian 12 packages the project needs, and only those that are missing.
# apt-get runs only when something is absent, so a machine that has everything is not touched.
set -euo pipefail

packages=(
  build-essential cmake ninja-build
  libeigen3-dev libtbb-dev libcli11-dev nlohmann-json3-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev librandom123-dev pybind11-dev
  python3 python3-dev python3-numpy python3-matplotlib python3-pytest zlib1g-dev
  python3-pip python3-venv python3-setuptools python3-wheel  # pip install (pyproject.toml, setup.py)
  clang-14 libclang-rt-14-dev  # make test-sanitize, make fuzz-smoke: clang++ 14, ASan, UBSan, libFuzzer
  libopenmpi-dev openmpi-bin  # the MPI build (docs/cluster.md)
  libyaml-cpp-dev  # ROS map_server map files (robot/map_io.cpp)
  libsqlite3-dev libzstd-dev liblz4-dev libbz2-dev  # ROS bags (robot/bag*.cpp)
  pkgconf doxygen
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing missing Debian packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "install-deps: not root and no sudo; please install: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
