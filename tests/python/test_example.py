# SPDX-License-Identifier: Apache-2.0
"""examples/python/plan_and_plot.py runs to the end, plots a real picture, and
reports the path and the forces the module gives for the same phantom."""
import json
import os
import subprocess
import sys

import matplotlib.image
import pytest

import voxhap

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# A plot with tissue bands, two curves and a legend; a blank 800x360 PNG is under 5 kB.
MIN_PNG_BYTES = 10_000


def test_plan_and_plot_example(source_dir, tmp_path):
    script = os.path.join(source_dir, "examples", "python", "plan_and_plot.py")
    out = tmp_path / "plan.png"
    p = subprocess.run([sys.executable, script, "--out", str(out)], capture_output=True, text=True, check=False)
    assert p.returncode == 0, p.stderr
    lines = [json.loads(line) for line in p.stdout.splitlines()]
    assert lines[-1] == {"plot": str(out)}
    summary = lines[0]

    with open(out, "rb") as f:
        assert f.read(8) == PNG_SIGNATURE
    assert out.stat().st_size > MIN_PNG_BYTES
    height, width = matplotlib.image.imread(out).shape[:2]
    assert (width, height) == (800, 360)  # figsize (8, 3.6) at 100 dpi, one panel

    # The same plan and insertion through the module directly.
    torso = voxhap.phantom("torso", spacing=1.0)
    best = voxhap.plan(torso, torso.landmark("lesion"), top=5)["paths"][0]
    assert summary["entry"] == best["entry"] and summary["risk"] == best["risk"]["total"]
    assert summary["peak_predicted_N"] == best["force"]["peak_N"]
    sim = voxhap.simulate("kyung", torso, entry=best["entry"], target=best["target"])
    assert summary["peak_rendered_N"] == pytest.approx(sim["summary"]["peak_rendered_N"], rel=0, abs=0)
    # The device renders the model's force times the scene's force_scale, or less where its limits act;
    # the planner's prediction ends at bone contact, the insertion goes on into bone, so the two peaks
    # are not ordered.
    scaled = sim["summary"]["force_scale"] * sim["summary"]["peak_model_N"]
    assert 0 < summary["peak_rendered_N"] <= scaled + 1e-9
