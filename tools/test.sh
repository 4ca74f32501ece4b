#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the whole voxhap test suite on the build made by tools/setup.sh.
#
#   tools/test.sh                 every test (ctest, both cores)
#   tools/test.sh -L volume       only tests with a label (volume, tools, ...)
#
# Extra arguments go to ctest. A test whose prerequisite is missing here (the
# shared data, root for SLURM, a display) is skipped, and the skips are listed
# at the end with their reasons; with VOXHAP_REQUIRE_ALL=1 (as CI runs it,
# .ci/run) each of them fails instead.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VOXHAP_BUILD_DIR:-$here/build}

if [ ! -f "$build_dir/CTestTestfile.cmake" ]; then
  echo "voxhap test: no build in $build_dir; run tools/setup.sh first" >&2
  exit 2
fi
console=$(mktemp)
trap 'rm -f "$console"' EXIT
status=0
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" "$@" | tee "$console" || status=${PIPESTATUS[0]}

# The skipped tests of this run (ctest's "did not run" list) and, from each one's
# output in ctest's log, the reason it gave: a script's "SKIPPED: why", a pytest
# "SKIPPED [n] file:line: why", a GoogleTest "file:line: Skipped" and the line after.
skipped=$(sed -n '/^The following tests did not run:/,/^$/s/^[[:space:]]*[0-9]* - \(.*\) (Skipped)$/\1/p' "$console")
if [ -n "$skipped" ]; then
  log=$build_dir/Testing/Temporary/LastTest.log
  echo
  echo "voxhap test: $(wc -l <<<"$skipped") test(s) skipped here, not passed (VOXHAP_REQUIRE_ALL=1 fails them):"
  while IFS= read -r name; do
    reason=$(awk -v start="\"$name\" start time:" '
      index($0, start) == 1 { block = 1; next }
      !block { next }
      /^<end of output>/ { exit }
      after { print; found = 1; exit }
      /^SKIPPED: / { sub(/^SKIPPED: /, ""); print; found = 1; exit }
      /^SKIPPED \[[0-9]+\] / { sub(/^SKIPPED \[[0-9]+\] [^ ]*: /, ""); print; found = 1; exit }
      /: Skipped$/ { after = 1; next }
      NF { last = $0 }
      END { if (!found) print last }' "$log" 2>/dev/null || true)
    echo "  $name: ${reason:-(no reason printed)}"
  done <<<"$skipped"
fi
exit "$status"
