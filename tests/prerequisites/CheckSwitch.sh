#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The switch turns every missing prerequisite into a failure naming it, and a
# skip never shows as a pass:
# - GoogleTest (common/Prerequisites.h, common/SharedData.h): skipped without a
#   switch; VOXHAP_REQUIRE_SHARED_DATA fails the shared data alone;
#   VOXHAP_REQUIRE_ALL fails both, naming each; a skip beside a pass exits 77
#   through skips_exit_77.sh, a failure beside a skip exits 1;
# - scripts (common/prerequisite.sh): 77 without the switch, 1 with it;
# - pytest (tests/python/conftest.py): a skip exits 77, the switch fails it, a
#   failure beside a skip stays a failure.
#
#   CheckSwitch.sh PROBE SOURCE_DIR PYTHON
set -uo pipefail
probe=$1 src=$2 python=$3
unset VOXHAP_REQUIRE_ALL VOXHAP_REQUIRE_SHARED_DATA VOXHAP_PROBE_FAIL
bad=0
out=$(mktemp)
trap 'rm -f "$out"' EXIT
# expect STATUS GREP-PATTERN... -- COMMAND...: the command exits STATUS and its output holds each pattern.
expect() {
  local want=$1 patterns=()
  shift
  while [ "$1" != -- ]; do patterns+=("$1"); shift; done
  shift
  "$@" >"$out" 2>&1
  local got=$?
  if [ "$got" -ne "$want" ]; then
    echo "FAILED: exit $got, not $want: $*"; sed 's/^/    /' "$out"; bad=1; return
  fi
  for p in "${patterns[@]}"; do
    grep -qF -- "$p" "$out" || { echo "FAILED: no '$p' in the output of: $*"; sed 's/^/    /' "$out"; bad=1; }
  done
  echo "ok: exit $want: $*"
}
skip77=$src/tests/common/skips_exit_77.sh

expect 0 '[  SKIPPED ] Probe.MissingTool' '[  SKIPPED ] Probe.MissingSharedData' -- "$probe"
expect 77 '[  SKIPPED ]' -- "$skip77" "$probe"
expect 1 'failed on request' -- env VOXHAP_PROBE_FAIL=1 "$skip77" "$probe"
expect 1 'shared data missing' '[  SKIPPED ] Probe.MissingTool' -- env VOXHAP_REQUIRE_SHARED_DATA=1 "$probe"
expect 1 "missing prerequisite: the probe's missing tool" 'shared data missing' '[  FAILED  ] 2 tests' \
  -- env VOXHAP_REQUIRE_ALL=1 "$probe"

expect 77 'SKIPPED: a tool' -- "$src/tests/common/prerequisite.sh" a tool
expect 1 'missing prerequisite: a tool' -- env VOXHAP_REQUIRE_ALL=1 "$src/tests/common/prerequisite.sh" a tool

pytest=("$python" -m pytest -q -rs -p no:cacheprovider "$src/tests/python/prerequisite_probe.py")
if "$python" -c 'import pytest' 2>/dev/null; then
  expect 77 "the probe's missing tool" -- env PYTHONDONTWRITEBYTECODE=1 "${pytest[@]}"
  expect 1 'failed on request' -- env PYTHONDONTWRITEBYTECODE=1 VOXHAP_PROBE_FAIL=1 "${pytest[@]}"
  expect 1 "missing prerequisite: the probe's missing tool" \
    -- env PYTHONDONTWRITEBYTECODE=1 VOXHAP_REQUIRE_ALL=1 "${pytest[@]}"
else
  echo "FAILED: $python has no pytest (Debian: python3-pytest; tools/setup.sh installs it)"
  bad=1
fi
exit $bad
