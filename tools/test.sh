#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the whole voxhap test suite on the build made by tools/setup.sh.
#
#   tools/test.sh                 every test (ctest, both cores)
#   tools/test.sh -L volume       only tests with a label (volume, tools, ...)
#
# Extra arguments go to ctest.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VOXHAP_BUILD_DIR:-$here/build}

if [ ! -f "$build_dir/CTestTestfile.cmake" ]; then
  echo "voxhap test: no build in $build_dir; run tools/setup.sh first" >&2
  exit 2
fi
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" "$@"
