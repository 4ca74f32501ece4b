#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Checks that a change which should not change behaviour (a move, a rename, a
# function split into steps) leaves voxhap's outputs identical: runs two voxhap
# programs, the one built before the change and the one built after, on the
# same jobs and compares every file they wrote.
#
#   tools/compare-outputs.sh OLD_VOXHAP NEW_VOXHAP [WORK_DIR]
#
# The jobs: `voxhap demo` (its report, CSV files, views and plots), `voxhap
# regress --json` (the built-in suite), and on the real data beside the
# project (../shared/data, each folder that exists): `info --json` of every
# series, `convert` to .vdb then `info --json` of the result (the grids'
# statistics and the metadata as read back), `segment` and `plan` of the
# abdominal CT (the guide's target), `segment` of the T1-weighted MR series.
# Wall times and the names of the two work folders are removed from the
# outputs before comparing; everything else must match byte for byte.
# Exit 0: identical; 1: a difference (each one listed); 2: bad arguments.
set -euo pipefail
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
  echo "usage: tools/compare-outputs.sh OLD_VOXHAP NEW_VOXHAP [WORK_DIR]" >&2
  exit 2
fi
for bin in "$1" "$2"; do
  if [ ! -x "$bin" ]; then
    echo "compare-outputs: $bin: not an executable" >&2
    exit 2
  fi
done
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
data=${VOXHAP_SHARED_DATA:-$here/../shared/data}
work=${3:-$(mktemp -d)}
mkdir -p "$work"

# Key names whose values are measured times or rates: dropped from JSON.
timing='seconds|_s$|_ms_wall|wall|elapsed|rate_hz|_ns|throughput|per_s$'

normalise_json() { # file: rewrite in place without timing keys, sorted
  python3 - "$1" "$timing" <<'EOF'
import json, re, sys
path, timing = sys.argv[1], re.compile(sys.argv[2])
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if not timing.search(k)}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x
with open(path) as f:
    doc = json.load(f)
with open(path, "w") as f:
    json.dump(strip(doc), f, indent=1, sort_keys=True)
    f.write("\n")
EOF
}

run_jobs() { # voxhap out_dir
  local vx=$1 out=$2
  rm -rf "$out"
  mkdir -p "$out"
  (
    cd "$out"
    "$vx" demo --out demo >demo.txt 2>&1 || echo "exit $?" >>demo.txt
    "$vx" regress --json --no-plots >regress.json 2>regress.txt || echo "exit $?" >>regress.txt
    local series=(
      ct-abdomen-tcia/dicom
      mr-head-trio/t1-mprage mr-head-trio/gre-field-map
      mr-dwi-prisma/t1-fl2d-sag mr-dwi-prisma/dwi-mosaic
      ct-mr-porcine/ct ct-mr-porcine/mr-t2
    )
    for s in "${series[@]}"; do
      [ -d "$data/$s" ] || continue
      local name=${s//\//-}
      "$vx" info --json "$data/$s" >"info-$name.json" 2>"info-$name.txt" || echo "exit $?" >>"info-$name.txt"
      local pick=()
      [ "$s" = mr-dwi-prisma/dwi-mosaic ] && pick=(--volume 2)
      "$vx" convert "$data/$s" "$name.vdb" "${pick[@]}" >/dev/null 2>"convert-$name.txt" ||
        echo "exit $?" >>"convert-$name.txt"
    done
    if [ -d "$data/ct-abdomen-tcia/dicom" ]; then
      "$vx" segment "$data/ct-abdomen-tcia/dicom" --out ct-seg.vdb --json >segment-ct.json 2>segment-ct.txt ||
        echo "exit $?" >>segment-ct.txt
      "$vx" plan "$data/ct-abdomen-tcia/dicom" --target 4,128,296 --allow-bone --out plan-ct >plan-ct.txt 2>&1 ||
        echo "exit $?" >>plan-ct.txt
    fi
    if [ -d "$data/mr-dwi-prisma/t1-fl2d-sag" ]; then
      "$vx" segment "$data/mr-dwi-prisma/t1-fl2d-sag" --out mr-seg.vdb --json >segment-mr.json 2>segment-mr.txt ||
        echo "exit $?" >>segment-mr.txt
    fi
    # A .vdb holds a random UUID: compare what it says (info --json: the grids'
    # statistics and the metadata) and the voxels of its first channel (a raw NRRD).
    find . -name '*.vdb' | while read -r f; do
      "$vx" info --json "$f" >"$f.info.json" 2>&1 || true
      "$vx" convert "$f" "$f.nrrd" >/dev/null 2>&1 || true
      rm -f "$f"
    done
  )
  # Times and the work folder's own name out of every text and JSON file.
  find "$out" -type f -name '*.json' | while read -r f; do
    if python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$f" 2>/dev/null; then normalise_json "$f"; fi
  done
  find "$out" -type f \( -name '*.txt' -o -name '*.csv' -o -name '*.json' \) -print0 |
    xargs -0 sed -i -E -e "s#$out#OUT#g" -e 's/[0-9]+(\.[0-9]+)? (s|ms|us)\b/T \2/g'
}

echo "compare-outputs: old $1 -> $work/old"
run_jobs "$(realpath "$1")" "$work/old"
echo "compare-outputs: new $2 -> $work/new"
run_jobs "$(realpath "$2")" "$work/new"

status=0
if ! diff -r "$work/old" "$work/new" >"$work/diff.txt"; then
  status=1
  echo "compare-outputs: the outputs differ ($work/diff.txt):"
  head -n 60 "$work/diff.txt"
else
  count=$(find "$work/new" -type f | wc -l)
  echo "compare-outputs: identical: $count files ($work/old, $work/new)"
fi
exit $status
