#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs a GoogleTest program that runs several tests in one process (a shared
# suite) and exits 77, which ctest counts as skipped, when it passed but skipped
# a test; any other status passes through. (ctest's SKIP_REGULAR_EXPRESSION would
# count a run that skipped one test and failed another as skipped.)
#
#   skips_exit_77.sh PROGRAM ARGS...
set -uo pipefail
log=$(mktemp)
trap 'rm -f "$log"' EXIT
"$@" 2>&1 | tee "$log"
status=$?
if [ "$status" -eq 0 ] && grep -qF '[  SKIPPED ]' "$log"; then exit 77; fi
exit "$status"
