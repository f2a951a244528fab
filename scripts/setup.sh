#!/usr/bin/env bash
# Shared set-up of run-tests.sh and run-demo.sh: install the Debian packages that are
# missing, configure a Release build in build/ (once) and build it with all cores.
# Sourced, not run: leaves REPO_ROOT and BUILD_DIR set.
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-${REPO_ROOT}/build}"

VU_PACKAGES=(
  build-essential cmake git pkg-config
  libinsighttoolkit5-dev libfftw3-dev libgdcm-dev libgdcm-tools
  libvtk9-dev libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libfreetype-dev fonts-dejavu-core
  libsuitesparse-dev libopenblas0-pthread libblosc-dev
  qtbase5-dev libvtk9-qt-dev xvfb xauth
  tesseract-ocr tesseract-ocr-eng time
  python3 python3-numpy python3-matplotlib python3-pydicom python3-tifffile python3-scipy
  python3-zarr
)

vu_missing_packages() {
  local missing=()
  for p in "${VU_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  echo "${missing[@]:-}"
}

missing="$(vu_missing_packages)"
if [ -n "${missing}" ]; then
  echo "setup: installing missing Debian packages: ${missing}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: error: packages are missing and this is not root; install them with apt-get: ${missing}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  # shellcheck disable=SC2086
  apt-get install -y -qq --no-install-recommends ${missing} >/dev/null
fi

JOBS="$(nproc)"
if [ ! -f "${BUILD_DIR}/CMakeCache.txt" ]; then
  cmake -S "${REPO_ROOT}" -B "${BUILD_DIR}" -DCMAKE_BUILD_TYPE=Release
fi
cmake --build "${BUILD_DIR}" -j"${JOBS}"
