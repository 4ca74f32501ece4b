#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A test whose prerequisite is missing: skipped locally (exit 77, "SKIPPED: why"),
# failed when VOXHAP_REQUIRE_ALL is set (CI: .ci/run), naming what is missing.
#
#   prerequisite.sh WHY...                 as a test of its own (CMake registers it
#                                          where a test cannot be built)
#   source prerequisite.sh; missing WHY    inside a test script
missing() {
  if [ -n "${VOXHAP_REQUIRE_ALL:-}" ]; then
    echo "FAILED: missing prerequisite: $* (VOXHAP_REQUIRE_ALL is set)"
    exit 1
  fi
  echo "SKIPPED: $* (skipped locally; VOXHAP_REQUIRE_ALL fails it)"
  exit 77
}
if [ "${BASH_SOURCE[0]}" = "$0" ]; then missing "$@"; fi
