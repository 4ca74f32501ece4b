#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Regenerates every picture of docs/guide.md with the voxhap that was built, so
# the guide shows what this version of voxhap makes.
#
#   docs/guide/make-pictures.sh                 write docs/guide/img/*.png
#   docs/guide/make-pictures.sh --out DIR       write them to DIR instead
#   docs/guide/make-pictures.sh --ct DIR        the patient CT (default ../shared/data/ct-abdomen-tcia/dicom)
#   docs/guide/make-pictures.sh --pair DIR      a CT and MR pair with ct/ and mr-t2/ (default ../shared/data/ct-mr-porcine)
#   docs/guide/make-pictures.sh --list          print the pictures' names and exit
#
# Environment: VOXHAP_BUILD_DIR (default ./build), with the voxhap program and
# the Python module. Needs the CT of the planning chapter and the CT and MR pair of the fusion chapter; every other picture comes from built-in phantoms and
# scenes. About two minutes on 2 cores. Pictures are written only when every
# step succeeded: a failed step leaves the old pictures in place.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build_dir=${VOXHAP_BUILD_DIR:-$here/build}
out=$here/docs/guide/img
ct=$here/../shared/data/ct-abdomen-tcia/dicom
pair=$here/../shared/data/ct-mr-porcine

# The pictures, in the order the guide shows them. tests/docs checks that this
# list and the guide's image links are the same set.
pictures=(
  plan-views.png          # voxhap plan: slices through the target and the 3D overview, paths drawn
  plan-force-depth.png    # voxhap plan: the predicted force along the best path
  viewer.png              # voxhap view: the planning viewer, 3D pane turned
  simulate-force-depth.png  # voxhap simulate: an epidural insertion through the Senac model
  serve-session.png       # voxhap serve: a simulated trainee's hand stops at the loss of resistance
  regress-failure.png     # voxhap regress: a tissue edit caught, where and by how much
  bench-sampler.png       # voxhap bench sampler: runtime against error, Pareto front
  python-plan-force.png   # examples/python/plan_and_plot.py: predicted and rendered force, phantom and CT
  fusion-axial.png        # voxhap render --fusion: the porcine CT and MR, before and after registration
  fusion-plan-force.png   # voxhap plan on a fused torso phantom: damping from the MR's T1
  plan-bending-views.png  # voxhap plan with a bending needle: the predicted bent needles on the CT
  bending-predicted-simulated.png  # the best path's bent needle as plan predicts it and as simulate runs it
)

while (($#)); do
  case $1 in
    --out) out=$2; shift 2 ;;
    --ct) ct=$2; shift 2 ;;
    --pair) pair=$2; shift 2 ;;
    --list) printf '%s\n' "${pictures[@]}"; exit 0 ;;
    -h|--help) sed -n '3,15p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "make-pictures: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

voxhap=$build_dir/bin/voxhap
[ -x "$voxhap" ] || { echo "make-pictures: no $voxhap; run tools/setup.sh first" >&2; exit 2; }
[ -d "$ct" ] || { echo "make-pictures: no CT folder '$ct' (--ct DIR)" >&2; exit 2; }
[ -d "$pair/ct" ] && [ -d "$pair/mr-t2" ] || { echo "make-pictures: no CT and MR pair in '$pair' (--pair DIR)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
step() { echo "make-pictures: $*" >&2; }

step "plan a biopsy path on the CT"
"$voxhap" plan "$ct" --target 4,128,296 --allow-bone --out plan >plan.txt
cp plan/views.png plan-views.png
cp plan/force-depth.png plan-force-depth.png

step "the planning viewer with the plan, 3D pane turned"
printf 'drag 3d 60 -20\nrelease\n' >turn.txt
"$voxhap" view "$ct" --plan plan/paths.mrk.json --script turn.txt --snapshot viewer.png >/dev/null

step "a simulated epidural insertion"
"$voxhap" simulate --scene senac-average --out sim >/dev/null
cp sim/force-depth.png simulate-force-depth.png

step "a simulated trainee's hand in the servo loop (20 s in real time)"
"$voxhap" serve --scene senac-average --duration 20 --out serve >/dev/null
"$voxhap" plot serve/session.csv --out serve-session.png >/dev/null

step "a regression run after raising the ligamentum flavum's cutting force by 20 %"
python3 - "$here/data/tissues.json" edited-tissues.json <<'EOF'
import json, sys
table = json.load(open(sys.argv[1]))
for t in table["tissues"]:
    if t["name"] == "ligamentum_flavum":
        t["cutting_force"]["value"] *= 1.2
json.dump(table, open(sys.argv[2], "w"), indent=1)
EOF
# Exit 1 is the expected outcome here: the edit must fail the cases it touches.
set +e
"$voxhap" regress --tissues edited-tissues.json --only senac-average --plots regress >regress.txt
rc=$?
set -e
[ "$rc" -eq 1 ] || { echo "make-pictures: regress exited $rc, expected 1 (the edit caught)" >&2; exit 1; }
cp regress/senac-average.png regress-failure.png

step "the shaft-integration benchmark (quick)"
"$voxhap" bench sampler --quick --png bench-sampler.png >/dev/null

step "the Python example: plan on the phantom and the CT, insert, plot force against depth"
[ -f "$build_dir/python/voxhap/__init__.py" ] ||
  { echo "make-pictures: no Python module in $build_dir/python (VOXHAP_WITH_PYTHON=ON builds it)" >&2; exit 2; }
PYTHONPATH="$build_dir/python" MPLBACKEND=Agg /usr/bin/python3 "$here/examples/python/plan_and_plot.py" \
  --ct "$ct" --target 4,128,296 --allow-bone --out python-plan-force.png >/dev/null

step "fuse the porcine CT and MR, and draw the check"
"$voxhap" fuse "$pair/ct" "$pair/mr-t2" --out pig.vdb >/dev/null
"$voxhap" render pig.vdb --fusion --out pig-views >/dev/null
cp pig-views/fusion-axial.png fusion-axial.png

step "a phantom scan pair, fused, and a plan on it"
"$voxhap" phantom torso --spacing 1 --scan-pair pair --mr-turn 0,0,180 --mr-shift 10,-5,20 >/dev/null
"$voxhap" fuse pair/ct.nrrd pair/mr.nrrd --out torso-fused.vdb >/dev/null
"$voxhap" plan torso-fused.vdb --target 5,-78,0 --allow-bone --out fused-plan >/dev/null
cp fused-plan/force-depth.png fusion-plan-force.png

step "plan on the CT with a needle that bends"
"$voxhap" plan "$ct" --target 4,128,296 --allow-bone --scene kyung-bending --top 3 --out plan-bend >plan-bend.txt
cp plan-bend/views.png plan-bending-views.png

step "the best path's bent needle, predicted (plan) and simulated (simulate), with and without its half turn"
# Scripts at 10 mm/s for the chosen bevel: without a turn, and with the half turn plan chose.
/usr/bin/python3 - plan-bend/report.json <<'EOF' >bend-path.txt
import json, sys
path = json.load(open(sys.argv[1]))["paths"][0]
d = path["deflection"]
base = d["without_turn"][0]["bevel_orientation_deg"]
roll = (d["best"]["bevel_orientation_deg"] - base) % 360.0  # the chosen bevel, as a roll from the scene's
turn, length = d["best"]["turn_depth_mm"], path["length_mm"]
with open("straight.csv", "w") as f:
    f.write(f"t_s,depth_mm,roll_deg\n0,-5,{roll}\n{(length + 5) / 10},{length},{roll}\n")
rows = [(0, -5, roll)]
if turn is not None:
    t = (turn + 5) / 10
    rows += [(t, turn, roll), (t + 0.1, turn, roll + 180), (t + 0.1 + (length - turn) / 10, length, roll + 180)]
else:
    rows += [((length + 5) / 10, length, roll)]
with open("turned.csv", "w") as f:
    f.write("t_s,depth_mm,roll_deg\n" + "".join(f"{a},{b},{c}\n" for a, b, c in rows))
print(",".join(map(str, path["entry"])), ",".join(map(str, path["target"])))
EOF
read -r bend_entry bend_target <bend-path.txt
"$voxhap" segment "$ct" --out ct-labelled.vdb >/dev/null # the labels plan segments for itself
for motion in straight turned; do
  "$voxhap" simulate ct-labelled.vdb --scene kyung-bending --entry "$bend_entry" --target "$bend_target" \
    --script $motion.csv --no-plot --json --out sim-$motion >sim-$motion.json
done
MPLBACKEND=Agg /usr/bin/python3 - plan-bend/report.json sim-straight.json sim-turned.json <<'EOF'
import json, sys
import matplotlib.pyplot as plt
import numpy as np
path = json.load(open(sys.argv[1]))["paths"][0]
d = path["deflection"]
entry, target = np.array(path["entry"]), np.array(path["target"])
u = (target - entry) / np.linalg.norm(target - entry)
def offsets(shaft):
    p = np.array(shaft) - entry
    depth = p @ u
    return depth, p - np.outer(depth, u)
straight = json.load(open(sys.argv[2]))["bending"]["shaft"]
turned = json.load(open(sys.argv[3]))["bending"]["shaft"]
# Signed along the side the unturned needle bends to (the bevel's push).
_, lat = offsets(straight)
side = lat[-1] / np.linalg.norm(lat[-1])
turn = d["best"]["turn_depth_mm"]
how = f"half turn at {turn:.0f} mm" if turn is not None else "no turn"
fig, ax = plt.subplots(figsize=(8, 4.5), dpi=100)
for shaft, style, label in [(d["bent_shaft"], "-", "predicted by plan"), (turned, "--", "simulated by simulate")]:
    depth, lat = offsets(shaft)
    ax.plot(depth, lat @ side, style, lw=2, label=f"{label} ({how})")
depth, lat = offsets(straight)
ax.plot(depth, lat @ side, ":", lw=2, label="simulated without the turn")
unturned = [c for c in d["without_turn"] if c["bevel_orientation_deg"] == d["best"]["bevel_orientation_deg"]][0]
ax.plot([path["length_mm"]], [unturned["tip_deviation_mm"]], "o",
        label=f"predicted tip without the turn ({unturned['tip_deviation_mm']:.1f} mm off the line)")
ax.axhline(0, color="grey", lw=0.8)
ax.set_xlim(0, path["length_mm"] + 2)
ax.set_xlabel("depth along the planned line [mm]")
ax.set_ylabel("needle off the planned line [mm]")
ax.set_title("kyung-bending on the CT: the best path's 18 G needle, hub pushed along the line")
ax.legend(loc="upper left", fontsize=9)
fig.tight_layout()
fig.savefig("bending-predicted-simulated.png")
EOF

mkdir -p "$out"
for p in "${pictures[@]}"; do
  [ -s "$p" ] || { echo "make-pictures: $p was not made" >&2; exit 1; }
done
for p in "${pictures[@]}"; do
  cp "$p" "$out/.$p.tmp" && mv "$out/.$p.tmp" "$out/$p"
done
step "wrote ${#pictures[@]} pictures to $out"
