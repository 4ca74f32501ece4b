#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs voxhap's libFuzzer targets (fuzz/), built by the main build with clang.
#
#   tools/fuzz.sh                       every target, 10 minutes each
#   tools/fuzz.sh --minutes 60 NrrdHeader
#   tools/fuzz.sh --runs 4000 --fresh T  what the test suite runs: a fixed
#                                       number of inputs from seed 1 and an
#                                       empty corpus, so that every run of the
#                                       suite tries the same inputs
#   --min-runs N                        fail when a target tried fewer than N
#                                       inputs (the time cap stopped it first:
#                                       a slow runner must not test less)
#
# Each target starts from fuzz/seeds/<target> and fuzz/regressions/<target>
# (inputs that once broke it) and keeps what it learns in
# <build>/fuzz/corpus/<target>. A crash, a leak, an uncaught exception or a
# refusal that is not "<file>: ..." on one line stops it with a non-zero
# exit, and so does an accepted input that fails the target's content check
# (a value the parser promises and does not keep); the input is saved under
# <build>/fuzz/artifacts/ — add it to fuzz/regressions/<target>/ once fixed.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VOXHAP_BUILD_DIR:-$here/build}
seconds=600
runs=-1
min_runs=0
fresh=0
targets=()
while (($#)); do
  case "$1" in
    --minutes) seconds=$(($2 * 60)); shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --min-runs) min_runs=$2; shift 2 ;;
    --fresh) fresh=1; shift ;;
    --build-dir) build_dir=$2; shift 2 ;;
    -h|--help) sed -n '3,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "voxhap fuzz: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
bin=$build_dir/fuzz/bin
if ((${#targets[@]} == 0)); then # every target built
  for f in "$bin"/fuzz_*; do if [ -x "$f" ]; then targets+=("${f##*/fuzz_}"); fi; done
  if ((${#targets[@]} == 0)); then
    echo "voxhap fuzz: no targets in $bin (tools/setup.sh builds them when clang++ is installed)" >&2
    exit 2
  fi
fi
# Leaks inside third-party codecs that voxhap cannot free (see the file).
export LSAN_OPTIONS="suppressions=$here/fuzz/lsan-suppressions.txt${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
for t in "${targets[@]}"; do
  if [ ! -x "$bin/fuzz_$t" ]; then
    echo "voxhap fuzz: $bin/fuzz_$t not built (tools/setup.sh builds it when clang++ is installed)" >&2
    exit 2
  fi
done

for t in "${targets[@]}"; do
  corpus=$build_dir/fuzz/corpus/$t
  artifacts=$build_dir/fuzz/artifacts/$t
  extra=()
  if ((fresh)); then
    corpus=$(mktemp -d)
    trap 'rm -rf "$corpus"' EXIT
    extra=(-seed=1)
  fi
  mkdir -p "$corpus" "$artifacts"
  inputs=("$corpus" "$here/fuzz/seeds/$t")
  if [ -d "$here/fuzz/regressions/$t" ]; then inputs+=("$here/fuzz/regressions/$t"); fi
  if ((runs >= 0)); then echo "voxhap fuzz: $t, $runs inputs"; else echo "voxhap fuzz: $t for ${seconds} s"; fi
  # 4 KiB inputs reach every header field; rss 2 GiB: a parser asking for more is a finding.
  # grep hides libFuzzer's progress lines; the fuzzer's exit status is what counts.
  log=$(mktemp)
  set +e
  "$bin/fuzz_$t" -max_total_time="$seconds" -runs="$runs" "${extra[@]}" -max_len=4096 -rss_limit_mb=2048 -timeout=10 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" "${inputs[@]}" 2>&1 | tee "$log" |
    grep -E '^(#[0-9]+ +DONE|stat::number_of_executed_units|==[0-9]+==|SUMMARY|INFO: seed corpus)|ERROR|refusal|content check|^ +#[0-9]+ .* in [a-zA-Z_:]+voxhap'
  status=${PIPESTATUS[0]}
  set -e
  executed=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -n 1)
  rm -f "$log"
  if ((status != 0)); then
    echo "voxhap fuzz: $t failed (exit $status); inputs in $artifacts" >&2
    exit 1
  fi
  if ((min_runs > 0)) && ((${executed:-0} < min_runs)); then
    echo "voxhap fuzz: $t tried ${executed:-no} inputs, fewer than the floor of $min_runs:" \
      "the ${seconds} s cap stopped it (a slower machine must not test less)" >&2
    exit 1
  fi
done
