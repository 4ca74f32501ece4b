#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs the Debian 12 packages voxhap needs (only those missing), then
# configures and builds in ./build (Release, Ninja).
#
#   tools/setup.sh            install what is missing, configure, build
#   tools/setup.sh --deps     only install what is missing
#
# Idempotent: on a ready machine it costs a dpkg query and an incremental build.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VOXHAP_BUILD_DIR:-$here/build}

# Every library comes from Debian (docs: toolchain.md). Grouped by purpose.
packages=(
  # build
  build-essential cmake ninja-build pkg-config git
  # sparse volumes (OpenVDB's find module needs boost-iostreams but does not pull it in)
  libopenvdb-dev libboost-iostreams-dev
  # math, threads
  libeigen3-dev libtbb-dev
  # rendering, headless X
  libvtk9-dev xvfb xauth
  # 2D images (its CMake config references the /usr/bin tools)
  libopenimageio-dev openimageio-tools
  # DICOM
  libgdcm-dev
  # CT-MR registration (ITK 5.2's v4 framework); elastix, the independent reference of its tests and bench
  libinsighttoolkit5-dev elastix
  # gzip-encoded .nrrd; NIfTI headers (qform/sform)
  zlib1g-dev libnifti2-dev
  # device link
  libopenigtlink-dev openigtlink-examples
  # CLI, config
  libcli11-dev nlohmann-json3-dev
  # tests, benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # libFuzzer targets of the parsers (clang's runtime: fuzzer, address, undefined)
  clang libclang-rt-14-dev
  # the format check of the sources (.clang-format)
  clang-format
  # benchmark plots (pngcairo, no X needed)
  gnuplot-nox
  # real DICOM test files of other encodings and object classes (pydicom's test data)
  python3-pydicom
  # DICOM series re-encoded in every transfer syntax for the held-out classes test (DCMTK; GDCM's
  # gdcmconv for JPEG 2000, which DCMTK lacks)
  dcmtk libgdcm-tools
  # the Python module (python/): pybind11 and numpy for /usr/bin/python3; its tests and example
  python3-dev python3-pybind11 pybind11-dev python3-numpy python3-pytest python3-matplotlib
  # a one-node SLURM for the test that runs the cohort example as an array job
  slurmctld slurmd slurm-client
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "voxhap setup: installing ${#missing[@]} Debian package(s): ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "voxhap setup: all Debian packages present"
fi

if [ "${1:-}" = "--deps" ]; then exit 0; fi

cmake -S "$here" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build_dir" -j "$(nproc)"
