#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plan a biopsy path with voxhap's Python module and plot its force-depth profile.

On the built-in torso phantom (and on a CT when --ct and --target are given):
search entries to the target, take the best path, insert a needle along it
through the scene's force model, and draw the force the planner predicts and
the force the simulation renders against depth, over the tissues the path
crosses, to a PNG (matplotlib, Agg: no display needed).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/plan_and_plot.py --out plan.png
    PYTHONPATH=build/python /usr/bin/python3 examples/python/plan_and_plot.py \
        --ct ../shared/data/ct-abdomen-tcia/dicom --target 4,128,296 --allow-bone --out plan.png

Prints one JSON line per volume: the best path, its risk and the peak forces.
"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import voxhap  # noqa: E402

# One colour per tissue, the same in every panel; bone grey, critical structures red.
PALETTE = ["#f4d6c6", "#fbeeb8", "#d9b3a3", "#c7dcef", "#d8e8c8", "#e6d0ea", "#f0e0c0", "#cfe3e0"]
COLOURS = {}


def plan_and_simulate(volume, target, scene, allow_bone):
    """The best path to target and an insertion along it: (report path, simulation)."""
    if "label" not in volume:
        # A CT or MR: label it once (on a copy) for both the planner and the scene.
        volume = volume.copy()
        voxhap.segment(volume)
    report = voxhap.plan(volume, target, scene=scene, top=5, allow_bone=allow_bone)
    if not report["paths"]:
        raise SystemExit("plan_and_plot: no path satisfies the constraints")
    best = report["paths"][0]
    sim = voxhap.simulate(scene, volume, entry=best["entry"], target=best["target"])
    return best, sim


def draw(ax, title, best, sim):
    for s in best["segments"]:
        if s["tissue"] not in COLOURS:
            COLOURS[s["tissue"]] = "#bbbbbb" if s["rigid"] else "#f2a0a0" if s["critical"] else \
                PALETTE[len(COLOURS) % len(PALETTE)]
        ax.axvspan(s["start_mm"], s["end_mm"], color=COLOURS[s["tissue"]], alpha=0.6, lw=0,
                   label=s["tissue"] if s["tissue"] not in ax.get_legend_handles_labels()[1] else None)
    force = best["force"]  # the planner's profile: depth_mm, force_N, peak_N, contact_mm, speed_mm_per_s
    ax.plot(force["depth_mm"], force["force_N"], "k--", lw=1.5,
            label=f"predicted at {force['speed_mm_per_s']:.0f} mm/s (planner)")
    inside = sim["depth_mm"] >= 0
    scale = sim["summary"]["force_scale"]  # the scene renders its model force times this (kyung: 0.5)
    label = "rendered (simulation)" if scale == 1.0 else f"rendered (simulation, force_scale {scale:g})"
    ax.plot(sim["depth_mm"][inside], sim["force_N"][inside], color="#1f5fa8", lw=1.2, label=label)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("depth past the entry [mm]")
    ax.set_ylabel("force [N]")
    ax.set_xlim(0, best["length_mm"])
    ax.legend(fontsize=7, loc="upper left", ncol=2)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="plan_and_plot.png", help="PNG to write")
    p.add_argument("--scene", default="kyung", help="scene whose force model, needle and device are used")
    p.add_argument("--spacing", type=float, default=1.0, help="phantom voxel size [mm]")
    p.add_argument("--ct", help="also plan on this CT (DICOM folder, .nii, .nrrd, .mha or .vdb)")
    p.add_argument("--target", help="the CT's target x,y,z [mm, LPS] (with --ct)")
    p.add_argument("--allow-bone", action="store_true", help="on the CT: accept paths that cross bone")
    a = p.parse_args(argv)
    if bool(a.ct) != bool(a.target):
        p.error("--ct and --target go together")

    cases = []
    torso = voxhap.phantom("torso", spacing=a.spacing)
    cases.append(("torso phantom, vertebral lesion", torso, torso.landmark("lesion"), False))
    if a.ct:
        target = [float(x) for x in a.target.split(",")]
        name = "/".join(a.ct.rstrip("/").split("/")[-2:])
        cases.append((f"CT {name}, target {a.target}", voxhap.load(a.ct), target,
                      a.allow_bone))

    fig, axes = plt.subplots(len(cases), 1, figsize=(8, 3.6 * len(cases)), dpi=100, squeeze=False)
    for ax, (title, volume, target, allow_bone) in zip(axes[:, 0], cases):
        best, sim = plan_and_simulate(volume, target, a.scene, allow_bone)
        draw(ax, f"{title}: path 1, risk {best['risk']['total']:.2f}", best, sim)
        print(json.dumps({"volume": title, "entry": best["entry"], "target": best["target"],
                          "length_mm": best["length_mm"], "risk": best["risk"]["total"],
                          "peak_predicted_N": best["force"]["peak_N"],
                          "peak_rendered_N": sim["summary"]["peak_rendered_N"]}))
    fig.tight_layout()
    fig.savefig(a.out)
    print(json.dumps({"plot": a.out}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
